"""Dry rice heaps at the xpbd node's defaults, poured and dropped, and at 4× the substeps (issue 46). A heap poured
from high measures the speed its grains land at: at speed clamp 1 a 1 mm particle moved at most 0.6 m/s at the
default 10 substeps and 2.4 m/s at 40, so the stream landed braked at 10 and stood 8° steeper than the same grains
dropped as a ball, and 10° steeper than at 40 substeps (120 grains). At the default clamp 4 a fast substep runs as
several solves of ≤ 1 r (``step_limits.solve_pieces``): a falling grain keeps its speed at any substep count."""

import numpy as np
import pytest
from validation import rice_heap

# 120 grains, read at 1 s (the heaps rest from then on: the same H/R to 0.1° at 2 s)
GRAINS, FRAMES = 120, 60


def heap(shape: str, substeps: int) -> float:
    """atan H/R (°) of the 120-grain heap ``shape`` ("stream": poured from a column 96 mm tall; "ball": dropped)."""
    ((_, hr),), _ = rice_heap(GRAINS, True, frames=(FRAMES,), substeps=substeps, shape=shape)
    return hr


def landing_speed(substeps: int) -> float:
    """The downward speed (mm/s) of one japonica grain after 0.2 s of free fall from rest (200 mm), at the node's
    defaults (its damping a drag of 6.3/s)."""
    from scene_builders import rice_library

    from nodes.simulation.settings import xpbd_params
    from nodes.simulation.setup import build_simulation
    from nodes.values import Aggregate, Placement

    placement = Placement(
        np.array([[0.0, 0.0, 300.0]]),
        np.array([[0.0, 0.0, 1.0]]),
        np.eye(3)[None],
        variants=np.zeros(1, np.int32),
        kind_names=("japonica",),
    )
    params = xpbd_params(substeps=substeps, log_every=0, log_meshes_every=0)
    sim = build_simulation(Aggregate(placement, (rice_library(seed=0),)), [], {"gravity", "damping"}, params)
    for _ in range(12):
        sim.frame()
    return float(-sim.state.v[:, 2].mean())


def test_a_falling_grain_keeps_its_speed_at_any_substep_count():
    """Measured 1,112 mm/s at 40 substeps (v = g/k·(1 − e^(−kt)) = 1,114, k = −60·ln 0.9); at clamp 1: 421 at 10."""
    slow, fine = landing_speed(10), landing_speed(40)
    assert abs(slow - fine) < 0.02 * fine
    assert abs(fine - 9810.0 / 6.3217 * (1.0 - np.exp(-6.3217 * 0.2))) < 20.0


def test_poured_and_dropped_heaps_agree_at_the_defaults():
    """Measured H/R 25.6° poured, 26.6° dropped (at clamp 1: 31.6° and 23.6°)."""
    poured, dropped = heap("stream", 10), heap("ball", 10)
    assert abs(poured - dropped) <= 3.0


@pytest.mark.xfail(
    strict=True,
    reason="issue 46: at 40 substeps both heaps stand 4–5° lower (H/R 25.6° → 21.9° poured, 26.6° → 21.4° dropped; "
    "300 grains: 24.3° → 21.3° and 26.6° → 20.4° on two placements of the stream); the defaults are not converged "
    "in the substeps (docs/validation.md, 'Where the solver misses')",
)
def test_heaps_agree_at_four_times_the_substeps():
    for shape in ("stream", "ball"):
        assert abs(heap(shape, 10) - heap(shape, 40)) <= 3.0
