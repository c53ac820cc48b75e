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


def stl_problem(data: bytes) -> str | None:
    """Why ``data`` is neither an ASCII nor a binary STL, or None when its layout is one of them."""
    if data[:5].lower() == b"solid":
        try:
            data.decode("ascii")
            return None
        except UnicodeDecodeError:
            pass  # binary STLs may also begin with "solid": check the binary layout
    if len(data) >= STL_HEADER:
        count = int.from_bytes(data[80:84], "little")
        if len(data) == STL_HEADER + STL_TRIANGLE * count:
            return None
        return (
            f"not an STL file: not ASCII ('solid …') and not binary either (its header counts {count:,} "
            f"triangles, which take {STL_HEADER + STL_TRIANGLE * count:,} bytes; the file has {len(data):,})"
        )
    return f"not an STL file: {len(data)} bytes is shorter than a binary STL header ({STL_HEADER} bytes)"


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
