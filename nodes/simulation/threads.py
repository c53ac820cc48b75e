"""How many threads the solver's parallel kernels get: the cores other processes leave free.

numba's OpenMP layer (its default, ≈ 2 µs per parallel launch) splits a loop evenly over its
threads and waits for the slowest at the end of the loop; when another process holds a core, the
thread that shares it arrives late at every barrier. Measured on this 2-core machine at load 4:
the same 10k-sphere profile ran 366 and then 12 substeps/s on two threads, as the other
processes came and went, and one thread launched in 2.8 µs where two took 370 µs. So the solver
measures, between frames, how much CPU the other processes used (``/proc/stat`` minus this
process's own time) and runs on the cores they leave. The kernels' results do not depend on the
thread count (tested), only their speed. Only the solver adapts so (``nodegraph/runtime.py``, the policy for parallel
work: other kernels run on numba's thread count). Hand-written: no library reports "cores used by other
processes" (psutil gives the same numbers from the same files, as one more dependency).
"""

from __future__ import annotations

import os
import time
from contextlib import contextmanager

import numba

WINDOW_S = 0.25  # shortest measuring window: /proc/stat counts in 10 ms ticks


@contextmanager
def thread_count(n: int):
    """Run numba's parallel kernels on ``n`` threads inside the block."""
    old = numba.get_num_threads()
    numba.set_num_threads(n)
    try:
        yield
    finally:
        numba.set_num_threads(old)


def _busy_seconds() -> float | None:
    """CPU seconds all processes have spent busy since boot (every core summed), or None off Linux."""
    try:
        with open("/proc/stat", "rb") as handle:
            fields = handle.readline().split()
    except OSError:
        return None
    ticks = [int(v) for v in fields[1:]]
    idle = ticks[3] + (ticks[4] if len(ticks) > 4 else 0)  # idle + iowait
    return (sum(ticks[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def _own_seconds() -> float:
    t = os.times()
    return t.user + t.system


class FreeCores:
    """The thread count to use now: ``most`` minus the cores other processes kept busy over the
    last window (at least one). ``threads()`` is cheap; it re-measures once per ``WINDOW_S``."""

    def __init__(self, most: int):
        self.most = most
        self.current = most
        self._mark = (time.perf_counter(), _busy_seconds(), _own_seconds())

    def threads(self) -> int:
        if self.most == 1 or self._mark[1] is None:
            return self.most
        now, busy, own = time.perf_counter(), _busy_seconds(), _own_seconds()
        wall = now - self._mark[0]
        if wall < WINDOW_S or busy is None:
            return self.current
        others = max(0.0, (busy - self._mark[1]) - (own - self._mark[2])) / wall  # cores
        self._mark = (now, busy, own)
        self.current = max(1, min(self.most, int(len(os.sched_getaffinity(0)) - others + 0.5)))
        return self.current
