"""Arrays handed to numba kernels in one kind: C-contiguous, writable, of a fixed dtype.

numba compiles a kernel once per kind of each array argument, and a read-only array (every node output
is frozen by the engine) is a kind of its own: the same kernel called with a node's output and with a
fresh array compiled twice, seconds each on a first run (issue 27). A copy of a read-only input costs
microseconds against that.
"""

from __future__ import annotations

import numpy as np


def kernel_array(values, dtype=np.float64) -> np.ndarray:
    """``values`` as a C-contiguous writable array of ``dtype``: itself when it already is one, else a copy."""
    return np.require(values, dtype, ["C", "W"])
