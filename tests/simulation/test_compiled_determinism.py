"""Kernels compiled in the running process and the same kernels loaded from numba's cache give the
same bits (with fastmath they did not: LLVM may contract or reorder differently per compile path)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import hashlib
from scene_builders import rice_bowl
from nodes.simulation.xpbd import xpbd
aggregate, colliders = rice_bowl(30, seed=1)
effects = ("gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping")
out = xpbd.call(effects=effects, aggregate=aggregate, colliders=colliders, frames=3, substeps=4,
                deformation="quadratic")
print(hashlib.sha256(out["particles"].positions.tobytes()).hexdigest())
"""


@pytest.mark.slow  # compiles every simulation kernel once more (≈ 30 s)
def test_fresh_and_cached_kernels_give_the_same_bits(tmp_path):
    env = {
        **os.environ,
        "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
        # this tree's nodes, and benchmarks/ for scene_builders
        "PYTHONPATH": os.pathsep.join(
            filter(None, [str(ROOT), str(ROOT / "benchmarks"), os.environ.get("PYTHONPATH")])
        ),
    }
    runs = [
        subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True, text=True, check=True).stdout
        for _ in range(2)
    ]  # the first compiles and fills the cache, the second loads from it
    assert any((tmp_path / "numba").rglob("*.nbi"))
    assert len(runs[0].strip()) == 64 and runs[0] == runs[1]
