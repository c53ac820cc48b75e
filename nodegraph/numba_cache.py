"""Numba's on-disk cache, keyed by the source of the installed node packages (entry points).

numba keys a cached kernel on its own file only: a kernel that inlines a helper from another module
keeps running the stale machine code after that helper changes (seen here: equal sources, different
outputs from cached and fresh kernels). Giving each state of the node packages' source its own cache
directory makes every cached kernel match the code beside it.

Not done yet (issue 27 wants it): keying each kernel on its own module and the project modules it imports
(``code_digest.module_digest``, the node cache's key) instead of on all the source, so that an edit
recompiles only the kernels that can see it. numba 0.68 (installed here) takes a locator class through
``NUMBA_CACHE_LOCATOR_CLASSES``, whose ``get_source_stamp`` could return that digest. Left out because it
is not safe yet: the hook is not in every numba this project allows (>= 0.59), where it would be
ignored and stale kernels come back; and a kernel compiles in any jitted function it is handed as an
argument, whose module it need not import. Doing it needs a test that edits an inlined helper and
checks the kernel's result changes (a recompile, minutes on 2 cores).
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
