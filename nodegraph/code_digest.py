"""A digest of the code a node runs: its own module and the project modules that module imports,
followed statically and transitively, so that editing any of them changes the node's cache key.

Node functions import their kernels inside their bodies (``from . import distance_fields``), so the
imports are read from each module's source (``import_statements``: every import statement, parsed with
``ast``), at any depth, relative or absolute, without importing anything. A module counts as the
project's when its top-level package is the node's own or one of the installed node packages
(``nodegraph.nodes`` entry points); the engine is covered by its version, third-party libraries by
nothing (bump the node's ``version`` when a library upgrade matters). A plugin file (``--plugin``)
is its own project: its digest covers the file.
A package's ``__init__`` counts only where it is imported by name (``from pkg import helper`` naming a
function defined there), not because a module below it is, so an edit to one node module does not
change the keys of its siblings.

The digest of a node module is computed once per loaded module object (once per process, at the first
plan), matching the code that actually runs even if a file changes on disk meanwhile.
"""

from __future__ import annotations

import ast
import bisect
import hashlib
import importlib.util
import re
import sys
import weakref
from pathlib import Path
from types import ModuleType

_DIGESTS: weakref.WeakKeyDictionary[ModuleType, str] = weakref.WeakKeyDictionary()
_PARSED: dict[tuple[str, int, int], tuple[bytes, frozenset[tuple[str, tuple[str, ...]]]]] = {}


def node_code_digest(spec, packages: set[str] | None = None) -> str:
    """The digest of the code ``spec`` (a ``NodeSpec``) runs: see ``module_digest``."""
    return module_digest(spec.module, packages)


def module_digest(name: str, packages: set[str] | None = None) -> str:
    """sha256 (16 hex digits) over the names and bytes of ``name`` and every project module it imports,
    transitively (``project_modules``); computed once per loaded module object. "" for a module with no
    source file."""
    module = sys.modules.get(name)
    if module is None:
        return _digest(name, packages)
    digest = _DIGESTS.get(module)
    if digest is None:
        digest = _DIGESTS[module] = _digest(name, packages)
    return digest


def project_modules(name: str, packages: set[str] | None = None) -> dict[str, Path]:
    """``name`` and every project module it imports, transitively: module name → source file. The project
    is the top-level package of ``name`` plus ``packages`` (default: the installed node packages)."""
    if packages is None:
        from .registry import node_package_names

        packages = set(node_package_names())
    packages = packages | {name.partition(".")[0]}
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


def _digest(name: str, packages: set[str] | None) -> str:
    modules = project_modules(name, packages)
    if not modules:
        return ""
    digest = hashlib.sha256()
    for module, path in sorted(modules.items()):
        source, _ = _parse(path)
        digest.update(module.encode() + b"\0" + hashlib.sha256(source).digest())
    return digest.hexdigest()[:16]


def _parse(path: Path) -> tuple[bytes, frozenset[tuple[str, tuple[str, ...]]]]:
    """The file's bytes and its imports (``import_statements``), read once per state of the file."""
    stat = path.stat()
    memo = (str(path), stat.st_mtime_ns, stat.st_size)
    parsed = _PARSED.get(memo)
    if parsed is None:
        source = path.read_bytes()
        parsed = _PARSED[memo] = (source, import_statements(source))
    return parsed


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
