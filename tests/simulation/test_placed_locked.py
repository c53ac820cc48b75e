"""Two grains placed inside one another, particles 1.09 r deep, in a tray too narrow for them side by side (4.4 mm
for two 3 mm grains), clumping 1.0: held by static friction, with the cohesion in its load, they stay 0.56 r deep
for good; parting without friction between them (``parting``), they are under 0.3 r within 10 frames, at no more
than 41 mm/s (issue 46; docs/validation.md, "part without friction")."""

import numpy as np
from scene_builders import box_mesh, rice_library

from nodes.simulation import parting
from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, Placement

STICKY = frozenset({"gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping"})
HALF = (3.2, 2.2)  # mm: the tray's inner half length and width
FRAMES = 30


def tray(wall: float = 2.0, height: float = 8.0) -> list:
    """An open-top box: a floor and four walls around the inner half extents ``HALF``."""
    x, y, t = *HALF, wall
    return [
        box_mesh([-x - t, -y - t, -t], [x + t, y + t, 0], "floor"),
        box_mesh([-x - t, -y - t, 0], [-x, y + t, height], "west"),
        box_mesh([x, -y - t, 0], [x + t, y + t, height], "east"),
        box_mesh([-x, -y - t, 0], [x, -y, height], "south"),
        box_mesh([-x, y, 0], [x, y + t, height], "north"),
    ]


def locked_pair() -> tuple[float, float, float, float]:
    """(start depth, max speed over the run in mm/s, depth after 10 frames, final depth): depths in radii, the
    deepest particle overlap of the pair."""
    placement = Placement(
        np.array([[0.0, -0.9, 1.4], [0.0, 0.9, 1.4]]),
        np.array([[0, 0, 1.0]] * 2),
        np.stack([np.eye(3)] * 2),
        variants=np.array([0, 1], np.int32),
        kind_names=("japonica",),
    )
    params = XpbdParams(**xpbd.resolve_params({"log_every": 0, "log_meshes_every": 0, "clumping": 1.0}))
    sim = build_simulation(Aggregate(placement, (rice_library(seed=0),)), tray(), STICKY, params)
    m, pair = sim.model, np.array([[0, 1]])
    start = parting.deepest(m.x0, m.r, m.start, pair)[0]
    fastest, depths = 0.0, []
    for _ in range(FRAMES):
        sim.frame()
        fastest = max(fastest, float(np.linalg.norm(sim.state.v[: m.n_moving], axis=1).max()))
        depths.append(parting.deepest(sim.state.x, m.r, m.start, pair)[0])
    return start, fastest, depths[9], float(max(depths[9:]))


def test_a_pair_placed_locked_parts_without_a_throw():
    start, fastest, at_ten, after = locked_pair()
    assert start > 1.0  # placed 1 r deep
    assert at_ten < 0.3 and after < 0.3  # parted within 10 frames, and stays so (measured 0.25)
    assert fastest < 60.0  # mm/s over the whole run: parted, not thrown (measured 41)
