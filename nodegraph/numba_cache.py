"""Numba's on-disk cache, keyed by the source of the installed node packages (entry points).

numba keys a cached kernel on its own file only: a kernel that inlines a helper from another module
keeps running the stale machine code after that helper changes (seen here: equal sources, different
outputs from cached and fresh kernels). Giving each state of the node packages' source its own cache
directory makes every cached kernel match the code beside it.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from pathlib import Path

ENV_VAR = "NUMBA_CACHE_DIR"


def source_digest(*packages: str) -> str | None:
    """sha256 over the relative paths and bytes of every .py file of the packages (not imported);
    None when none of them is found."""
    digest = hashlib.sha256()
    found = False
    for package in packages:
        spec = importlib.util.find_spec(package)
        if spec is None or not spec.submodule_search_locations:
            continue
        found = True
        for root in spec.submodule_search_locations:
            for path in sorted(Path(root).rglob("*.py")):
                digest.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16] if found else None


def configure(packages: list[str] | None = None) -> Path | None:
    """Point numba at a cache directory for this source state of the node packages (default: the
    installed ones), unless the user chose one or numba is already loaded."""
    if os.environ.get(ENV_VAR) or "numba" in sys.modules:
        return None
    if packages is None:
        from .registry import node_package_names

        packages = node_package_names()
    digest = source_digest(*packages)
    if digest is None:
        return None
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    directory = base / "nodegraph" / "numba" / digest
    os.environ[ENV_VAR] = str(directory)
    return directory
