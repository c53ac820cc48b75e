"""Elements placed far inside one another are refused before the contact lists are allocated (a first-hour run
with ``egg_place.r=0.3`` placed 33,874 eggs 0.6 mm apart and was killed for memory, silently, after 78 s)."""

import numpy as np
import pytest
from scene_builders import ikura_mesh

from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, ElementLibrary, Placement

EFFECTS = frozenset({"gravity", "contact", "friction", "damping"})


def eggs(spacing: float, per_side: int = 12) -> Aggregate:
    g = np.arange(per_side) * spacing
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    n = len(x)
    placement = Placement(
        x,
        np.tile([0, 0, 1.0], (n, 1)),
        np.tile(np.eye(3), (n, 1, 1)),
        variants=np.zeros(n, np.int32),
        kind_names=("ikura",),
    )
    return Aggregate(placement, (ElementLibrary("ikura", [ikura_mesh(2.25)]),))


def params() -> XpbdParams:
    return XpbdParams(**xpbd.resolve_params({"frames": 1, "particles_per_element": 4}))


def test_eggs_placed_far_inside_one_another_are_refused_with_the_remedy():
    with pytest.raises(ValueError, match=r"start inside one another.*raise its r"):
        build_simulation(eggs(0.6), [], EFFECTS, params())


def test_eggs_placed_a_diameter_apart_are_not_refused():
    sim = build_simulation(eggs(4.6, per_side=4), [], EFFECTS, params())
    assert sim.model.elements == 64
