"""The closing table's peak memory per node (``report.PeakMemory``): the kernel's high-water mark reset as the node
starts, so nothing samples /proc while the node runs (a 5 ms sampling thread cost 3 % of a core and took the GIL
from the node 200 times a second) and a spike shorter than any sampling interval still counts."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from nodegraph import report


@pytest.mark.skipif(not report._reset_peak(), reason="this system does not let a process reset its peak RSS")
def test_peak_memory_needs_no_sampling_thread_and_sees_a_short_spike():
    before = threading.active_count()
    with report.PeakMemory() as memory:
        during = threading.active_count()
        spike = np.ones(64 * 2**20 // 8)  # 64 MiB touched and freed before the block ends
        del spike
    assert during == before
    assert memory.peak_bytes >= 60 * 2**20
