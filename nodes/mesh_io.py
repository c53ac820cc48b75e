"""Reading a user's mesh file with an error that names the real cause — shared by the element and
shape families (``base_mesh``'s file preset, ``mesh_file``).

trimesh reads many formats but reports a damaged file by what it tried last (a random-bytes .stl
surfaced as "No module named 'charset_normalizer'": its ASCII fallback's optional decoder), so an
STL's layout is checked here first, and any failure is reported as the file not being readable as
its format.
"""

from __future__ import annotations

from pathlib import Path

MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf")  # trimesh's triangle mesh readers
STL_HEADER = 84  # 80-byte header + uint32 triangle count
STL_TRIANGLE = 50


def suffix_problem(path: str | Path) -> str | None:
    """Why ``path`` is not a mesh file by its name (README.md, a .blend), or None: said when the recipe is checked,
    not after the nodes before the mesh has been read."""
    suffix = Path(path).suffix.lower()
    if suffix in MESH_SUFFIXES:
        return None
    kind = f"a {suffix} file" if suffix else "a file without an extension"
    return f"{Path(path).name} is {kind}, not a mesh file; allowed: {', '.join(MESH_SUFFIXES)}"


def repair_line(path: str, changes: list[str]) -> str:
    """What a run says (``Context.warn``) of a user's mesh file it repaired: the file and each change."""
    return f"{path} was repaired: {'; '.join(changes)} (fix the file to silence this)"


HEAD_BYTES = 4096  # what is read of a file to tell its format: a header, or the first lines of a text format


def file_problem(path: str | Path) -> str | None:
    """Why ``path`` is not a mesh file by its name or by its first bytes, or None: ``nodegraph check``'s rule."""
    return suffix_problem(path) or content_problem(path)


def content_problem(path: str | Path) -> str | None:
    """Why the first bytes of ``path`` are not the format its extension claims (a text file renamed to .stl), or
    None; read cheaply (a header, the first few KB), not parsed. A missing file is the parameter's own check."""
    path = Path(path)
    if not path.is_file():
        return None
    with path.open("rb") as stream:
        head = stream.read(HEAD_BYTES)
    suffix = path.suffix.lower()
    if suffix == ".stl":
        problem = stl_problem(head, path.stat().st_size)
        return None if problem is None else f"{path.name} is {problem}; found {_found(head)}"
    lines = [line for line in _text_lines(head) or () if line and not line.startswith(b"#")]
    if suffix == ".ply":
        problem = None if head[:3] == b"ply" else "a PLY file starts with 'ply'"
    elif suffix == ".off":
        problem = None if lines and lines[0].endswith(b"OFF") else "an OFF file starts with 'OFF'"
    elif suffix == ".glb":
        problem = None if head[:4] == b"glTF" else "a GLB file starts with the bytes 'glTF'"
    elif suffix == ".gltf":
        problem = None if head.lstrip()[:1] == b"{" else "a glTF file is JSON, starting with '{'"
    elif suffix == ".obj":
        listed = any(line.startswith((b"v ", b"f ")) for line in lines)
        problem = None if listed else "an OBJ file is text with 'v x y z' and 'f i j k' lines"
    else:
        return None
    if problem is None:
        return None
    kind = suffix[1:].upper()
    article = "an" if kind[0] in "AEFHILMNORSX" else "a"  # as the letter is spoken: an OBJ, an STL, a PLY
    return f"{path.name} is not {article} {kind} file: {problem}; found {_found(head)}"


def _text_lines(head: bytes) -> list[bytes] | None:
    """The stripped lines of ``head`` when it is text (UTF-8, no NUL bytes; its last line may be cut), else None."""
    if b"\0" in head:
        return None
    try:
        head.decode("utf-8")
    except UnicodeDecodeError as exc:
        if exc.start < len(head) - 3:  # a character cut at the read's end is still text
            return None
    return [line.strip() for line in head.splitlines()]


def _found(head: bytes) -> str:
    """What the first bytes look like, in words: empty, text (its first line) or binary (its first bytes)."""
    if not head:
        return "an empty file"
    lines = _text_lines(head)
    if lines is not None:
        first = next((line for line in lines if line), b"")
        return f"text beginning {first[:40].decode('utf-8', 'replace')!r}"
    return f"binary data beginning {head[:8]!r}"


def stl_problem(data: bytes, size: int | None = None) -> str | None:
    """Why ``data`` is neither an ASCII nor a binary STL, or None when its layout is one of them. ``size``: the
    file's size when ``data`` is only its first bytes (its ASCII text then judged on those)."""
    size = len(data) if size is None else size
    if data[:5].lower() == b"solid":
        try:
            data.decode("ascii")
            return None
        except UnicodeDecodeError:
            pass  # binary STLs may also begin with "solid": check the binary layout
    if size >= STL_HEADER and len(data) >= STL_HEADER:
        count = int.from_bytes(data[80:84], "little")
        if size == STL_HEADER + STL_TRIANGLE * count:
            return None
        return (
            f"not an STL file: not ASCII ('solid …') and not binary either (its header counts {count:,} "
            f"triangles, which take {STL_HEADER + STL_TRIANGLE * count:,} bytes; the file has {size:,})"
        )
    return f"not an STL file: {size} bytes is shorter than a binary STL header ({STL_HEADER} bytes)"


def read_mesh(path: str | Path, process: bool = True):
    """One ``trimesh.Trimesh`` from ``path`` (a scene's meshes concatenated); ValueError naming the cause:
    missing file, a damaged file, no triangles, non-finite coordinates."""
    import numpy as np
    import trimesh

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"no such mesh file: {path}")
    problem = suffix_problem(path)
    if problem is not None:
        raise ValueError(problem)
    if path.suffix.lower() == ".stl":
        problem = stl_problem(path.read_bytes())
        if problem is not None:
            raise ValueError(f"{path}: {problem}")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)  # processing would drop non-finite vertices
    except Exception as exc:  # trimesh raises many types (and import errors of optional readers)
        fmt = path.suffix.lstrip(".").upper() or "a mesh"
        raise ValueError(
            f"{path}: cannot be read as {fmt} ({type(exc).__name__}: {exc}); check that the file is "
            f"a complete {fmt} file, e.g. by opening it in a modeller"
        ) from exc
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError(f"{path}: holds no triangles")
    bad = int((~np.isfinite(loaded.vertices)).any(axis=1).sum())
    if bad:
        raise ValueError(
            f"{path}: {bad} vertices have NaN or infinite coordinates; no repair can place them: "
            "fix or re-export the mesh"
        )
    return loaded.process() if process else loaded
