"""The numba cache locator that stamps a kernel's cache entry with the code digest of its module.

numba asks each locator in ``NUMBA_CACHE_LOCATOR_CLASSES`` in turn (``numba_cache.configure`` lists this
one first) when a ``cache=True`` function is decorated. The stamp numba stores beside the cached machine
code is ``code_digest.module_digest`` of the function's module: its own source and that of every project
module it imports, transitively, so a kernel that inlines a helper from another module is recompiled when
that helper changes, and a kernel whose modules did not change loads from the cache. The project is the
installed node packages, the engine (``nodegraph``) and the function's own top-level package.
"""

from __future__ import annotations

import os

from numba.core import config
from numba.core.caching import _CacheLocator

from . import code_digest

_PACKAGES: set[str] | None = None


def project_packages() -> set[str]:
    """The installed node packages and the engine (read once per process)."""
    global _PACKAGES
    if _PACKAGES is None:
        from .node_packages import project_packages as installed

        _PACKAGES = installed()
    return _PACKAGES


class ModuleDigestLocator(_CacheLocator):
    """Cache entries under ``NUMBA_CACHE_DIR``, one folder per source folder (as numba's own locator), each
    stamped with the digest of the function's module and the project modules it imports."""

    def __init__(self, py_func, py_file):
        self._module = py_func.__module__
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = os.path.join(config.CACHE_DIR, self.get_suitable_cache_subpath(py_file))

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        return code_digest.module_digest(self._module, project_packages())

    def get_disambiguator(self):
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func, py_file):
        """A locator for a function defined in a source file on disk (None otherwise: numba's next locator)."""
        if not config.CACHE_DIR or not os.path.isfile(py_file) or not py_file.endswith(".py"):
            return None
        if code_digest.module_file(py_func.__module__) is None:
            return None
        locator = cls(py_func, py_file)
        try:
            locator.ensure_cache_path()
        except OSError:
            return None
        return locator
