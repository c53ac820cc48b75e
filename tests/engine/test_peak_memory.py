"""The closing table's peak memory per node (``report.PeakMemory``): the kernel's high-water mark reset as the node
starts, so nothing samples /proc while the node runs (a 5 ms sampling thread cost 3 % of a core and took the GIL
from the node 200 times a second) and a spike shorter than any sampling interval still counts."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from nodegraph import report

# in a process of its own: in a test worker other threads (a previous test's pools) free memory while the block runs,
# and the mark can end below the start value
SPIKE = """
import json, threading
import numpy as np
from nodegraph import report
before = threading.active_count()
with report.PeakMemory() as memory:
    during = threading.active_count()
    spike = np.ones(64 * 2**20 // 8)  # 64 MiB touched and freed before the block ends
    del spike
print(json.dumps({"threads": [before, during], "peak": memory.peak_bytes}))
"""


@pytest.mark.skipif(not report._reset_peak(), reason="this system does not let a process reset its peak RSS")
def test_peak_memory_needs_no_sampling_thread_and_sees_a_short_spike():
    done = subprocess.run([sys.executable, "-c", SPIKE], capture_output=True, text=True, check=True)
    seen = json.loads(done.stdout.splitlines()[-1])
    before, during = seen["threads"]
    assert during == before
    assert seen["peak"] >= 60 * 2**20
