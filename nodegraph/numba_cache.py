"""numba's on-disk cache, each kernel keyed on its own module and the project modules that module imports.

numba keys a cached kernel on its own file only: a kernel that inlines a helper from another module
would keep running the stale machine code after that helper changes. ``numba_locator.ModuleDigestLocator``
(handed to numba through ``NUMBA_CACHE_LOCATOR_CLASSES``, numba ≥ 0.68) stamps each kernel's cache entry
with ``code_digest.module_digest`` of the kernel's module instead, the digest the node cache keys nodes
on: an edit to one node file recompiles the kernels that import it, directly or not, and no others.

Kernels compile for numba's ``generic`` x86-64 CPU (``NUMBA_CPU_NAME``, unless the user chose one), so that a cache
entry built on one machine is found on any other: a bundle of compiled kernels shipped beside the code
(``kernel_bundle``) is unpacked into an empty cache on the first run.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from . import kernel_bundle

ENV_VAR = "NUMBA_CACHE_DIR"
LOCATOR_VAR = "NUMBA_CACHE_LOCATOR_CLASSES"
CPU_VAR = "NUMBA_CPU_NAME"
# ours first; numba's own locators (names it resolves itself) for functions without a source file on disk
LOCATORS = "nodegraph.numba_locator.ModuleDigestLocator,UserProvidedCacheLocator,IPythonCacheLocator,ZipCacheLocator"


def default_directory() -> Path:
    """Where compiled kernels go unless ``NUMBA_CACHE_DIR`` says otherwise."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "nodegraph" / "numba"


def configure() -> Path | None:
    """Point numba at the kernel cache directory (unless the user chose one), at the per-module locator
    (unless the user chose locators) and at the generic CPU (unless the user chose a CPU); before numba loads, or
    on numba's live config after. Unpacks the shipped kernels into the directory once (``kernel_bundle``).
    Returns the directory chosen, None when the user's is kept."""
    chosen = None
    if not os.environ.get(ENV_VAR):
        chosen = default_directory()
        os.environ[ENV_VAR] = str(chosen)
    os.environ.setdefault(LOCATOR_VAR, LOCATORS)
    if not os.environ.get(CPU_VAR):
        os.environ[CPU_VAR] = kernel_bundle.CPU
    if "numba" in sys.modules:  # numba read its config already: kernels decorated from now on see these
        from numba.core import config

        config.CACHE_DIR = os.environ[ENV_VAR]
        config.CACHE_LOCATOR_CLASSES = os.environ[LOCATOR_VAR]
        if config.CPU_NAME != os.environ[CPU_VAR]:  # numba's own default for these features (its config.py)
            config.CPU_NAME = os.environ[CPU_VAR]
            config.CPU_FEATURES = "" if config.CPU_NAME == kernel_bundle.CPU else None
    kernel_bundle.ensure_installed(Path(os.environ[ENV_VAR]))
    return chosen
