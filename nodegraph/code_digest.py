"""A digest of the code a node runs: its own module and the project modules that module imports,
followed statically and transitively, so that editing any of them changes the node's cache key.

Node functions import their kernels inside their bodies (``from . import distance_fields``), so the
imports are read from each module's source (``import_statements``: every import statement, parsed with
``ast``), at any depth, relative or absolute, without importing anything. A module counts as the
project's when its top-level package is the node's own or one of the installed node packages
(``nodegraph.nodes`` entry points). A node's digest (``node_code_digest``) also follows its imports into the
engine (``nodegraph.values``, ``nodegraph.node``, …) and covers the engine modules that hand every node its
parameters, context and inputs and store its outputs (``ENGINE_ROOTS``): editing the engine's code re-runs the
nodes whose results it can change, and nothing else (the executor, the CLI and the reports decide which results
are computed, not what they are). Third-party libraries enter by version: ``node_libraries`` gives the
installed version of every distribution whose top-level package the node's modules import (numpy, numba,
trimesh, …), so a library upgrade re-runs the nodes that use it and no ``version`` is bumped by hand. A plugin
file (``--plugin``) is its own project: its digest covers the file.
A package's ``__init__`` counts only where it is imported by name (``from pkg import helper`` naming a
function defined there), not because a module below it is, so an edit to one node module does not
change the keys of its siblings.

The digest of a node module is computed once per loaded module object (once per process, at the first
plan), matching the code that actually runs even if a file changes on disk meanwhile. Across processes it
is remembered on disk (``remembered_digest``), keyed on the files' stat stamps, so that a run whose code did
not change reads no source: hashing and scanning the node modules took ≈ 0.1–0.2 s of a cached re-run.
"""

from __future__ import annotations

import ast
import bisect
import hashlib
import importlib.util
import json
import os
import re
import sys
import tempfile
import time
import weakref
from pathlib import Path
from types import ModuleType

ENGINE = __name__.partition(".")[0]
# the engine modules every node's result passes through, whatever it imports: its parameters are validated and
# made canonical (``params``), its context and random stream made (``context``), its inputs decoded from and its
# outputs encoded into the cache (``codec``)
ENGINE_ROOTS = (f"{ENGINE}.params", f"{ENGINE}.context", f"{ENGINE}.codec")
LIBRARIES = "installed distributions"  # the memory's records of them, one per sys.path (``installed_distributions``)
LIBRARY_RECORDS = 8  # sys.path sets remembered (the CLI's, python -c's, a test session's, …); the oldest go first

# per loaded module and set of project packages: its digest and the third-party top-level packages it imports
_DIGESTS: weakref.WeakKeyDictionary[ModuleType, dict[frozenset[str], tuple[str, tuple[str, ...]]]] = (
    weakref.WeakKeyDictionary()
)
_INSTALLED: dict[str, list[str]] | None = None
# a file's bytes and imports per state of the file (its path and ``_stamp``), with the time they were read
_PARSED: dict[tuple, tuple[bytes, frozenset[tuple[str, tuple[str, ...]]], int]] = {}
MEMORY_ENV_VAR = "NODEGRAPH_CODE_DIGESTS"  # the file that remembers digests across processes ("" or "off": none)
MEMORY_ROOTS = 400  # digests remembered (a few per node module and tree); the oldest go first
_MEMORY: dict | None = None
RACY_S = 2.0  # a file changed this recently may change again within its timestamp's resolution: not remembered


def node_code_digest(spec, packages: set[str] | None = None) -> str:
    """The digest of the code ``spec`` (a ``NodeSpec``) runs: its module and every module of ``packages`` (default:
    the installed node packages) and of the engine it imports, transitively (``module_digest``), and the engine
    modules every node's result passes through (``ENGINE_ROOTS``)."""
    packages = _packages(packages) | {ENGINE}
    parts = [module_digest(spec.module, packages)] + [module_digest(root, {ENGINE}) for root in ENGINE_ROOTS]
    return hashlib.sha256("/".join(parts).encode()).hexdigest()[:16]


def node_libraries(spec, packages: set[str] | None = None) -> dict[str, str]:
    """Distribution → installed version for every third-party top-level package that the code ``spec`` runs
    imports (``node_code_digest``'s modules): what a library upgrade changes in its cache key."""
    packages = _packages(packages) | {ENGINE}
    tops = set(module_libraries(spec.module, packages))
    for root in ENGINE_ROOTS:
        tops.update(module_libraries(root, {ENGINE}))
    installed = installed_distributions()
    return dict(sorted(item.split("==", 1) for top in tops for item in installed.get(top, ())))


def module_digest(name: str, packages: set[str] | None = None) -> str:
    """sha256 (16 hex digits) over the names and bytes of ``name`` and every project module it imports,
    transitively (``project_modules``); computed once per loaded module object. "" for a module with no
    source file."""
    return _digest_and_libraries(name, packages)[0]


def module_libraries(name: str, packages: set[str] | None = None) -> tuple[str, ...]:
    """The third-party top-level packages (not the project's, not the standard library's) that ``name`` and the
    project modules it imports import, transitively."""
    return _digest_and_libraries(name, packages)[1]


def _packages(packages: set[str] | None) -> set[str]:
    if packages is None:
        from .node_packages import node_package_names

        packages = set(node_package_names())
    return set(packages)


def _digest_and_libraries(name: str, packages: set[str] | None) -> tuple[str, tuple[str, ...]]:
    packages = _packages(packages)
    module = sys.modules.get(name)
    if module is None:
        return _digest(name, packages)
    known = _DIGESTS.setdefault(module, {})
    found = known.get(frozenset(packages))
    if found is None:
        found = known[frozenset(packages)] = _digest(name, packages)
    return found


def project_modules(name: str, packages: set[str] | None = None) -> dict[str, Path]:
    """``name`` and every project module it imports, transitively: module name → source file. The project
    is the top-level package of ``name`` plus ``packages`` (default: the installed node packages)."""
    packages = _packages(packages) | {name.partition(".")[0]}
    found: dict[str, Path] = {}
    pending = [name]
    while pending:
        current = pending.pop()
        path = None if current in found else module_file(current)
        if path is not None:
            found[current] = path
            pending += imported_modules(current, path, packages)
    return found


def imported_modules(name: str, path: Path, packages: set[str]) -> list[str]:
    """The modules of ``packages`` that module ``name`` (source at ``path``) imports anywhere in its code."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    _, imports = _parse(path)
    return sorted({module for target, names in imports for module in _imported(target, names, package, packages)})


def module_file(name: str) -> Path | None:
    """The source file of module ``name``, found without importing it (a loaded module's own file first:
    a plugin file is loaded under a name no finder knows)."""
    loaded = sys.modules.get(name)
    file = getattr(loaded, "__file__", None)
    if file and file.endswith(".py"):
        return Path(file)
    top, _, rest = name.partition(".")
    try:
        spec = importlib.util.find_spec(top) if top not in sys.modules else getattr(sys.modules[top], "__spec__", None)
    except (ImportError, ValueError):
        return None
    if spec is None:
        return None
    if not rest:
        return Path(spec.origin) if spec.origin and spec.origin.endswith(".py") else None
    locations = [Path(p) for p in (spec.submodule_search_locations or [])]
    parts = rest.split(".")
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        next_locations = []
        for location in locations:
            if (location / part / "__init__.py").is_file():
                if last:
                    return location / part / "__init__.py"
                next_locations.append(location / part)
            elif last and (location / f"{part}.py").is_file():
                return location / f"{part}.py"
            elif (location / part).is_dir():  # a namespace package
                next_locations.append(location / part)
        locations = next_locations
    return None


def _digest(name: str, packages: set[str]) -> tuple[str, tuple[str, ...]]:
    where = _memory_key(name, packages)
    remembered = remembered_digest(where)
    if remembered is not None:
        return remembered
    modules = project_modules(name, packages)
    if not modules:
        return "", ()
    project = packages | {name.partition(".")[0]}
    digest = hashlib.sha256()
    libraries = set()
    read = {}  # file -> (its stamp, when its bytes were read)
    for module, path in sorted(modules.items()):
        source, imports = _parse(path)
        read[str(path)] = _read_stamps[str(path)]
        digest.update(module.encode() + b"\0" + hashlib.sha256(source).digest())
        libraries.update(_third_party(imports, project))
    found = digest.hexdigest()[:16], tuple(sorted(libraries))
    if where is not None:
        _remember(where, found, read)
    return found


def _third_party(imports, project: set[str]) -> set[str]:
    """The top-level packages of the absolute imports in ``imports`` that are neither the project's nor the
    standard library's."""
    tops = {target.partition(".")[0] for target, _ in imports if not target.startswith(".")}
    return {top for top in tops if top not in project and top not in sys.stdlib_module_names and top != "__future__"}


def installed_distributions() -> dict[str, list[str]]:
    """Top-level package → ``["distribution==version", ...]`` of every installed distribution
    (``importlib.metadata.packages_distributions``). Reading every distribution's metadata takes ≈ 0.4 s, so the
    answer is read once per process and remembered across processes beside the digests, with the stamps of the
    folders on ``sys.path``: installing, upgrading or removing a distribution adds or renames its
    ``.dist-info`` folder there, which changes the folder's stamp."""
    global _INSTALLED
    if _INSTALLED is None:
        folders = {path: _stamp(path) for path in sorted({p or "." for p in sys.path})}
        where = f"{LIBRARIES} {json.dumps(sorted(folders))}"
        record = _load_memory().get(where)
        if isinstance(record, dict) and record.get("stamps") == folders and isinstance(record.get("installed"), dict):
            _INSTALLED = record["installed"]
        else:
            from importlib.metadata import PackageNotFoundError, packages_distributions, version

            versions: dict[str, str] = {}
            installed = {}
            for top, distributions in packages_distributions().items():
                for dist in distributions:
                    if dist not in versions:
                        try:
                            versions[dist] = version(dist)
                        except PackageNotFoundError:
                            versions[dist] = ""
                installed[top] = sorted({f"{dist}=={versions[dist]}" for dist in distributions})
            _INSTALLED = installed
            recent = time.time_ns() - int(RACY_S * 1e9)
            if all(s is None or max(s[2], s[3]) <= recent for s in folders.values()):
                _store(where, {"stamps": folders, "installed": installed})
    return _INSTALLED


# digests remembered across processes ------------------------------------------------------------------


def memory_file() -> Path | None:
    """Where digests are remembered: ``$NODEGRAPH_CODE_DIGESTS``, else beside the numba kernels in the user's
    cache folder; None when switched off."""
    chosen = os.environ.get(MEMORY_ENV_VAR)
    if chosen is not None:
        return None if chosen in ("", "off") else Path(chosen)
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "nodegraph" / "code_digests.json"


def _memory_key(name: str, packages: set[str]) -> str | None:
    """What a remembered digest answers: the module, the project's packages and where each is found (another
    checkout on the path is another project). None for a module with no source file."""
    where = module_file(name)
    if where is None:
        return None
    places = {p: str(module_file(p) or "") for p in sorted(packages | {name.partition(".")[0]})}
    return json.dumps([name, str(where), places], separators=(",", ":"))


def _stamp(path: str) -> list[int] | None:
    """What changes when a file or folder is written, replaced or renamed (as git's index keeps)."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return [st.st_ino, st.st_size, st.st_mtime_ns, st.st_ctime_ns]


def _load_memory() -> dict:
    """The remembered digests, read once per process (each record is checked against the files when used)."""
    global _MEMORY
    if _MEMORY is None:
        path = memory_file()
        try:
            _MEMORY = json.loads(path.read_bytes()) if path is not None else {}
        except (OSError, ValueError):  # none yet, or torn: start afresh
            _MEMORY = {}
        if not isinstance(_MEMORY, dict):
            _MEMORY = {}
    return _MEMORY


def remembered_digest(where: str | None) -> tuple[str, tuple[str, ...]] | None:
    """The digest remembered for ``where`` (``_memory_key``) if every file it covers, and every package folder
    on the way to them (a module added beside them changes what an import names), has its stamp still."""
    if where is None:
        return None
    record = _load_memory().get(where)
    if not isinstance(record, dict):
        return None
    stamps = record.get("stamps")
    if not isinstance(stamps, dict) or not stamps:
        return None
    if any(_stamp(path) != stamp for path, stamp in stamps.items()):
        return None
    digest, libraries = record.get("digest"), record.get("libraries")
    if not isinstance(digest, str) or not isinstance(libraries, list):
        return None
    return digest, tuple(libraries)


def _remember(where: str, found: tuple[str, tuple[str, ...]], read: dict[str, tuple[list[int] | None, int]]) -> None:
    """Store the digest and the libraries imported (``found``) with the stamps of its files (``read``: each
    file's stamp and the time its bytes were read), of their package folders and of this module (a change to how
    digests are made voids them all). Nothing is stored when a file changed since it was read, or within ``RACY_S``
    before it was read: a second write within the same timestamp tick leaves the stamp as it was, so the bytes read
    may not be the file's."""
    if memory_file() is None:
        return
    now = time.time_ns()
    stamps: dict[str, list[int] | None] = {__file__: _stamp(__file__)}
    for file, (stamp, read_ns) in read.items():
        if stamp is None or stamp != _stamp(file) or max(stamp[2], stamp[3]) > read_ns - int(RACY_S * 1e9):
            return
        stamps[file] = stamp
        folder = Path(file).parent
        while str(folder) not in stamps and (folder == Path(file).parent or (folder / "__init__.py").is_file()):
            stamps[str(folder)] = _stamp(str(folder))
            folder = folder.parent
    recent = now - int(RACY_S * 1e9)
    if any(s is None or max(s[2], s[3]) > recent for s in stamps.values()):
        return
    _store(where, {"digest": found[0], "libraries": list(found[1]), "stamps": stamps})


def _store(where: str, record: dict) -> None:
    """Remember ``record`` under ``where`` (the newest), forgetting the oldest digests beyond ``MEMORY_ROOTS`` and
    the oldest records of installed distributions beyond ``LIBRARY_RECORDS``."""
    path = memory_file()
    if path is None:
        return
    memory = _load_memory()
    memory.pop(where, None)
    memory[where] = record
    libraries = [key for key in memory if key.startswith(LIBRARIES)]
    digests = [key for key in memory if not key.startswith(LIBRARIES)]
    for old in digests[: max(0, len(digests) - MEMORY_ROOTS)] + libraries[: max(0, len(libraries) - LIBRARY_RECORDS)]:
        del memory[old]
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile("w", dir=path.parent, prefix=".digests-", delete=False) as out:
            json.dump(memory, out, separators=(",", ":"))
        os.replace(out.name, path)
    except OSError:  # a read-only cache folder: digests are computed each run, as without the memory
        pass


_read_stamps: dict[str, tuple[list[int] | None, int]] = {}  # file -> the stamp and read time of its last parse


def _parse(path: Path) -> tuple[bytes, frozenset[tuple[str, tuple[str, ...]]]]:
    """The file's bytes and its imports (``import_statements``), read once per state of the file (``_stamp``:
    inode, size, modification and change times)."""
    stamp = _stamp(str(path))
    memo = (str(path), *(stamp or ()))
    parsed = _PARSED.get(memo)
    if parsed is None:
        read_ns = time.time_ns()
        source = path.read_bytes()
        parsed = _PARSED[memo] = (source, import_statements(source), read_ns)
    _read_stamps[str(path)] = (stamp, parsed[2])
    return parsed[0], parsed[1]


# where an import statement can begin: a line's start, or after ``;`` or a compound statement's ``:``
_CANDIDATE = re.compile(rb"(?:^|[;:])[ \t]*(?:import|from)[ \t\\(.]", re.M)


def import_statements(source: bytes) -> frozenset[tuple[str, tuple[str, ...]]]:
    """Every ``import`` and ``from ... import`` in ``source``, at any depth (function bodies included), as
    (module, names) pairs, relative modules as written (leading dots).

    Each place an import can begin is read to the end of its logical line and parsed with ``ast``: the
    same statements a whole syntax tree holds, about ten times faster (parsing every node module took
    ≈ 0.5 s per run). Text in a string that reads as an import adds a module (a spare re-run, never a
    stale result); anything else that does not parse as a statement is not an import."""
    lines = source.split(b"\n")
    starts = [0]
    for line in lines:
        starts.append(starts[-1] + len(line) + 1)
    found = set()
    for match in _CANDIDATE.finditer(source):
        begin = match.start() + (source[match.start() : match.start() + 1] in (b";", b":"))
        row = bisect.bisect_right(starts, begin) - 1
        parts = [source[begin : starts[row + 1] - 1].split(b"#")[0]]
        while row + 1 < len(lines) and (_open(parts) or parts[-1].rstrip().endswith(b"\\")):
            row += 1
            parts.append(lines[row].split(b"#")[0])
        try:
            statements = ast.parse(b"\n".join(part.strip() for part in parts)).body
        except (SyntaxError, ValueError):
            continue
        for statement in statements:
            if isinstance(statement, ast.Import):
                found.update((alias.name, ()) for alias in statement.names)
            elif isinstance(statement, ast.ImportFrom):
                target = "." * statement.level + (statement.module or "")
                found.add((target, tuple(alias.name for alias in statement.names)))
    return frozenset(found)


def _open(parts: list[bytes]) -> bool:
    text = b"".join(parts)
    return text.count(b"(") > text.count(b")")


def _imported(target: str, names: tuple[str, ...], package: str, packages: set[str]) -> list[str]:
    """The project modules an import statement in a module of ``package`` names: ``import a.b`` → a.b;
    ``from a import b`` → a.b where that is a module, else a (b is defined in a's ``__init__``)."""
    try:
        base = importlib.util.resolve_name(target, package) if target.startswith(".") else target
    except ImportError:  # a relative import beyond the top-level package, or in a plugin file
        return []
    if base.partition(".")[0] not in packages:
        return []
    if not names:
        return [base]
    out = []
    for name in names:
        submodule = f"{base}.{name}"
        out.append(submodule if name != "*" and module_file(submodule) is not None else base)
    return out
