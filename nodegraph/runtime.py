"""What a process that runs work sets up once: ``configure()``, called by the entry points, never on import.

``import nodegraph`` changes nothing outside the package: no environment variable, no numba setting. The entry
points that run work call ``configure()`` before the first kernel module is imported (numba picks a kernel's cache
locator when ``@njit(cache=True)`` decorates it): ``nodegraph``'s command line (``cli.main``), a run's start
(``executor.Executor.run``, for notebooks and scripts), a pool worker's job (``pool.run_job``), the compile-ahead
worker (``compile_ahead.main``), the test suite (``tests/conftest.py``) and the benchmarks that import kernel modules
directly.
"""

from __future__ import annotations

from . import numba_cache


def configure() -> None:
    """Point numba at the project's kernel cache and its per-module locator (``numba_cache.configure``): in
        ``os.environ`` too, so that the processes this one starts (the compile-ahead worker, Dask workers) and numba's
        own re-reading of its ``NUMBA_*`` variables at each compile see the same. A directory or locators the user set
    are kept; calling it again follows a ``NUMBA_CACHE_DIR`` changed since."""
    numba_cache.configure()


__all__ = ["configure"]
