"""A first run compiles each helper of a kernel once (issue 27: first run ≤ 90 s; docs/performance.md, "Compiling the
kernels"). In a ``parallel=True`` kernel numba types the loop body a second time with the ``prange`` index unsigned, so
a non-inlined helper taking the index compiled for int64 and again for uint64; an array assignment (``a[:, :] = b``)
compiled numba's shape-mismatch message (string formatting). Checked in a fresh process with an empty numba cache:
kernels loaded from the cache compile no helpers."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

PROBE = r"""
import json
import numpy as np
from numba import typeof, types
from numba.core import event

from nodes.elements.grid_kernels import mesh_distance_band
from nodes.placement import refine_kernels as rk
from nodes.simulation import collider, shape_matching as sm
from nodes.simulation.friction_models import FrictionRule
from nodes.simulation.model import ModelArrays
from nodes.simulation.state import StateArrays

compiled = []


class Names(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__qualname__)

    def on_end(self, ev):
        pass


event.register("numba:compile", Names())


def sig(*args):
    return tuple(typeof(a) for a in args)


f, i = np.zeros((2, 3)), np.zeros(2, np.int64)
frames = rk.ElementFrames(f, np.zeros((2, 3, 3)), f, i)
shapes = rk.TemplateShapes(i, i, f, i, f, np.zeros(2), np.zeros(2), np.zeros(2))
neighbours = rk.Neighbours(np.zeros(3, np.int64), i)
search = rk.SearchRange(np.zeros(2), np.zeros(2), np.zeros(2))
rk.overlap_depths.compile(sig(frames, neighbours, np.ones(2, np.bool_), shapes, 0.1))
rk.refine_offsets.compile(sig(frames, search, neighbours, i, i, shapes, rk.RefineCost(0, 1.0, 1.0, 0.1, 8), 2))
v, b = np.zeros(2), np.ones(2, np.bool_)
walls = (np.zeros(1, np.int8), np.zeros((2, 5)), np.zeros((1, 4)))  # mode, rubbed, force
state = StateArrays(f, f, f, f, np.zeros((1, 4)), np.zeros(1, np.bool_), b, b, f, v, v, *walls)
model = ModelArrays(v, v, i, i, f)
grid = collider.ColliderGrid(np.zeros((2, 2, 2)), np.zeros(3), 1.0, np.zeros((1, 1, 1)))
collider.collider_project.compile(sig(state, model, grid, FrictionRule(0.5, 0.5, True)))
moments = sm.LinearMoments(np.zeros((1, 3, 3)), np.zeros((1, 3, 3)))
shape_args = sig(state, model, moments, np.zeros((2, 3)), sm.MatchRule(0.0, 0.5, 4))
sm.shape_match_project.compile(shape_args + (types.Omitted(None),))
mesh_distance_band.compile(sig(f, np.zeros((1, 3), np.int64), 1.0, (2, 2, 2), 2.0))
helpers = (rk._depth_of, rk._depth_into, rk._refine_chunk, collider._swept_back, sm._match_cluster)
print(json.dumps({
    "signatures": {h.py_func.__name__: len(h.signatures) for h in helpers},
    "shape_messages": sum("raise_with_shape_context" in name for name in compiled),
}))
"""


def test_each_helper_compiles_once(tmp_path: Path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    out = subprocess.run(
        [sys.executable, "-c", PROBE], env=env, cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout
    found = json.loads(out.strip().splitlines()[-1])
    assert found["signatures"] == {
        "_depth_of": 1,
        "_depth_into": 1,
        "_refine_chunk": 1,
        "_swept_back": 1,
        "_match_cluster": 1,
    }
    assert found["shape_messages"] == 0
