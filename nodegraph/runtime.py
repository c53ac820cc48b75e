"""How a process runs work: what it sets up once (``configure``), and the one policy for parallel work.

**Set-up, never on import.** ``import nodegraph`` changes nothing outside the package: no environment variable, no
numba setting. The entry points that run work call ``configure()`` before the first kernel module is imported (numba
picks a kernel's cache locator when ``@njit(cache=True)`` decorates it): the command line (``cli.main``), loading the
node packages and plugins (``registry.default_registry``), a run's start (``executor.Executor.run``), a pool worker's
job (``pool.run_job``), the compile-ahead worker (``compile_ahead.main``), the test suite (``tests/conftest.py``) and
the benchmarks that import kernel modules directly.

**Cores: one number decides.** numba's thread count (``NUMBA_NUM_THREADS``; by default every core numba sees) is the
most a process uses, fixed when the process starts: by the user, or by ``dask_pool`` for its workers (cores ÷
workers, so that workers × threads stay within the cores). Work is split three ways, each for one kind of work, and
nothing else starts threads or processes:

1. *Threads inside a node*, for numba kernels: ``prange`` loops, or a few threads over ``nogil`` kernels
   (``collider``, ``contact_deformation``), never more than numba's thread count. Results do not depend on the count
   (tested per kernel). The solver, which launches thousands of short parallel loops a frame, lowers the count frame
   by frame to the cores other processes leave free (``nodes/simulation/threads.FreeCores``, from ``/proc/stat``): on a
   shared machine a thread that waits for a core holds every barrier of the loop. This makes the solver's speed, never
   its results, depend on what else runs.
2. *One thread beside the main one*, for a node whose work runs in native threads with the GIL released (the
   preview: Mitsuba): ``executor.Beside`` computes the instances that neither need it nor depend on it (``measure``,
   ``export``) meanwhile. The node stays in the main thread, where a signal stops it; only the second thread launches
   numba's parallel kernels then (numba's workqueue layer aborts on two launching at once).
3. *Other processes*, for what one process cannot share: the compile-ahead worker on a first run (numba compiles one
   kernel at a time, under a process-wide lock; ``compile_ahead``), started by exec and only onto a core the load
   average shows idle (on a busy machine a second process only splits the run's share); and, when asked for, Dask
   workers (``--workers`` / ``--scheduler``: sweeps, other machines; ``dask_pool``), started by spawn. The command
   line forks once, before any work (``interrupt.supervise``: the parent only waits, to stop the child on a signal).
   Once work has started no process forks: a fork copies the forking thread alone and runs the libraries' fork
   handlers, and OpenBLAS's stopped its workers under a matrix product another thread had under way (a run hung in
   the preview; commit 8feda45). Work that holds the GIL (libigl in ``measure``) runs in one thread.

What each earns, measured, and what was removed: docs/performance.md, "One policy for parallel work".
"""

from __future__ import annotations

from . import numba_cache


def configure() -> None:
    """Point numba at the project's kernel cache and its per-module locator (``numba_cache.configure``), in
    ``os.environ`` too: the processes this one starts (the compile-ahead worker, Dask workers) and numba's own
    re-reading of its ``NUMBA_*`` variables at each compile see the same. A directory or locators the user set are
    kept; calling it again follows a ``NUMBA_CACHE_DIR`` changed since."""
    numba_cache.configure()


__all__ = ["configure"]
