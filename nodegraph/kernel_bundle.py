"""Compiled kernels shipped beside the code: a first run loads them from numba's cache instead of compiling them
(issue 49: the main job's first run ≤ 60 s on 2 cores; docs/performance.md, "Shipped kernels").

A bundle is numba's cache files (``.nbi`` index, ``.nbc`` machine code) of a first run, packed by source folder
relative to the project (``nodes/simulation/integrate.predict-212.py311.nbi``), so that it is independent of where
the code lies: numba's own cache folder names hash the absolute source folder (``_CacheLocator``). Unpacking puts
each file where this installation's locator looks (``install``), never over a file that is there already. What
numba checks on loading is the same on any machine: each index's stamp is the code digest of the kernel's module
(``numba_locator``: content, not path or modification time), each entry is keyed on the argument types, the hash of
the function's bytecode and the code generator (target triple, CPU name and features), and a file holds the numba
version; a bundle entry that does not match any of these is not used and the kernel compiles as before.

The CPU: numba compiles for the host's model by default (its name and feature list), which keys an entry to that
model. Kernels compile for the ``generic`` x86-64 model (``NUMBA_CPU_NAME=generic``, numba's setting for cache
files meant for other machines; ``numba_cache.configure`` sets it unless the user chose a CPU), so that an entry
built on one x86-64 machine is found on any other. What it costs at run time and that the outputs are the same
bytes: docs/performance.md, "Shipped kernels".

``python tools/kernel_bundle.py build`` writes a bundle from a first run of the main job; a run unpacks
``BUNDLE`` (or the file ``NODEGRAPH_KERNEL_BUNDLE`` names; ``off``: none) into its numba cache once per bundle file
and installation (``ensure_installed``). ``BUNDLE`` is kept in git, so that a first run from a checkout compiles
nothing; ``stale`` names the entries whose module changed since (``tests/engine/test_kernel_bundle.py`` fails on any).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import sys
import tarfile
from pathlib import Path

BUNDLE = Path(__file__).parent / "kernels.tar.gz"
ENV_VAR = "NODEGRAPH_KERNEL_BUNDLE"
MANIFEST = "bundle.json"
CPU = "generic"
SUFFIXES = (".nbi", ".nbc")


def manifest() -> dict:
    """What a bundle's files depend on besides each kernel's code: numba's version, Python's, the CPU model."""
    from importlib.metadata import version

    return {"numba": version("numba"), "python": f"{sys.version_info[0]}.{sys.version_info[1]}", "cpu": CPU}


def project_roots() -> dict[str, Path]:
    """The folder of each top-level project package (the engine and the installed node packages) by name."""
    from importlib.util import find_spec

    from .node_packages import project_packages

    roots = {}
    for name in sorted(project_packages()):
        spec = find_spec(name)
        if spec is not None and spec.submodule_search_locations:
            roots[name] = Path(next(iter(spec.submodule_search_locations)))
    return roots


def _cache_subpath(folder: Path) -> str:
    """The folder under ``NUMBA_CACHE_DIR`` that numba's locators (ours included) use for source folder ``folder``."""
    from numba.core.caching import _CacheLocator

    return _CacheLocator.get_suitable_cache_subpath(str(folder / "module.py"))


def source_folders() -> dict[str, str]:
    """Cache subfolder → source folder relative to the projects' parent (``nodes/simulation``), every folder of
    every project package."""
    folders = {}
    for name, root in project_roots().items():
        for folder in [root, *(p for p in root.rglob("*") if p.is_dir() and p.name != "__pycache__")]:
            folders[_cache_subpath(folder)] = (Path(name) / folder.relative_to(root)).as_posix()
    return folders


def pack(cache_dir: Path, out: Path) -> int:
    """Write the cache files under ``cache_dir`` that belong to the project's kernels into bundle ``out``; returns
    the number of files."""
    folders = source_folders()
    count = 0
    out.parent.mkdir(parents=True, exist_ok=True)
    with tarfile.open(out, "w:gz", compresslevel=6) as tar:
        data = json.dumps(manifest()).encode()
        info = tarfile.TarInfo(MANIFEST)
        info.size = len(data)
        tar.addfile(info, io.BytesIO(data))
        for sub in sorted(cache_dir.iterdir()):
            if sub.name not in folders:
                continue
            for file in sorted(sub.iterdir()):
                if file.suffix in SUFFIXES:
                    tar.add(file, arcname=f"{folders[sub.name]}/{file.name}", recursive=False)
                    count += 1
    return count


def install(bundle: Path, cache_dir: Path) -> int:
    """Unpack ``bundle`` into ``cache_dir``, each file where this installation's locator looks; a file there already
    is kept. A bundle for another numba, Python or CPU is not unpacked. Returns the number of files written."""
    roots = project_roots()
    written = 0
    with tarfile.open(bundle, "r:gz") as tar:
        if json.loads(tar.extractfile(tar.getmember(MANIFEST)).read()) != manifest():
            return 0
        for member in tar.getmembers():
            top, _, rest = member.name.partition("/")
            folder, _, name = rest.rpartition("/")
            if not member.isfile() or top not in roots or not name.endswith(SUFFIXES) or ".." in folder.split("/"):
                continue
            target = cache_dir / _cache_subpath(roots[top] / folder) / name
            if target.exists():
                continue
            target.parent.mkdir(parents=True, exist_ok=True)
            temporary = target.with_name(f".{name}.{os.getpid()}")
            temporary.write_bytes(tar.extractfile(member).read())
            os.replace(temporary, target)  # numba reads a whole file or none
            written += 1
    return written


def fits(bundle: Path) -> bool:
    """Whether ``bundle`` was built for this numba, Python and CPU model (``install`` unpacks nothing otherwise)."""
    with tarfile.open(bundle, "r:gz") as tar:
        return json.loads(tar.extractfile(tar.getmember(MANIFEST)).read()) == manifest()


def _index_stamps(bundle: Path):
    """(bundle path, kernel module, stamp) of each index file in ``bundle``: numba's pickled version, then its pickled
    ``(stamp, overloads)`` (``numba.core.caching.IndexDataCacheFile``)."""
    import pickle

    with tarfile.open(bundle, "r:gz") as tar:
        for member in tar.getmembers():
            if not member.name.endswith(".nbi"):
                continue
            folder, _, name = member.name.rpartition("/")
            data = tar.extractfile(member)
            pickle.load(data)  # numba's version: the manifest covers it
            stamp, _overloads = pickle.loads(data.read())
            yield member.name, ".".join([*folder.split("/"), name.split(".")[0]]), stamp


def _stale_and_current(bundle: Path) -> tuple[list[str], set[str]]:
    """The index files whose stamp is not the current code digest of their module (``stale``), and the modules all
    of whose indices are current."""
    from . import code_digest
    from .node_packages import project_packages

    packages = project_packages()
    digests: dict[str, str] = {}
    old, modules, old_modules = [], set(), set()
    for name, module, stamp in _index_stamps(bundle):
        modules.add(module)
        if module not in digests:
            digests[module] = code_digest.module_digest(module, packages)
        if stamp != digests[module]:
            old.append(name)
            old_modules.add(module)
    return old, modules - old_modules


def stale(bundle: Path) -> list[str]:
    """The bundle's index files whose stamp is not the current code digest of their kernel's module (numba would
    not load them: the kernel compiles), as bundle paths."""
    return _stale_and_current(bundle)[0]


def current_modules(bundle: Path) -> set[str]:
    """The kernel modules whose every index in ``bundle`` matches the current code (``stale``), where the bundle fits
    this numba, Python and CPU model (``fits``); empty otherwise: a run loads these modules' kernels, compiling none."""
    return _stale_and_current(bundle)[1] if fits(bundle) else set()


def bundle_path() -> Path | None:
    setting = os.environ.get(ENV_VAR, "")
    if setting.lower() in ("off", "0", "false", "no"):
        return None
    path = Path(setting) if setting else BUNDLE
    return path if path.is_file() else None


def ensure_installed(cache_dir: Path) -> int:
    """Unpack the bundle into ``cache_dir`` unless that was done for this bundle file and this installation (a
    marker in the cache folder named by the bundle's path, size and modification time and the project's folders:
    two checkouts sharing one cache each get their own unpacking). Without a bundle: one ``stat``. Never raises:
    a failure only means the kernels compile."""
    bundle = bundle_path()
    if bundle is None or os.environ.get("NUMBA_CPU_NAME", CPU) != CPU:
        return 0
    try:
        stat = bundle.stat()
        roots = sorted(str(root) for root in project_roots().values())
        key = json.dumps([str(bundle.resolve()), stat.st_size, stat.st_mtime_ns, roots])
        marker = cache_dir / "kernel_bundle" / f"{hashlib.sha256(key.encode()).hexdigest()[:32]}.installed"
        if marker.exists():
            return 0
        written = install(bundle, cache_dir)
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.touch()
        return written
    except Exception:
        return 0
