"""Long (indica) grains in the run (issue 26, docs/look.md "indica"): long grains that crossed in the pile stayed
crossed into each other after the XPBD run, and the contact step's deep dents were then the concave skin. The reduced
rice bowl of ``bench_skin.py --exported`` with indica grains at the draft's resolution (4 variants, 400 faces); and
a long grain placed through a container's wall, which the run tore across the wall."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scene_builders import long_grain, open_box

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
from nodes.contact_shaping.cull_crossing import crossing_depths
from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, ElementLibrary, Placement

REPO = Path(__file__).resolve().parents[2]
INDICA = [
    "bowl.size=14.0",
    "bowl.depth=12.0",
    "bowl.mound=2.0",  # at 3–5 the chawan's heaped top layer reaches this 28 mm bowl's rim: long grains end on it
    "variety.variety=indica",
    "grain_spheres.variants=4",
    "grain_volume.resolution=24",
    "grain_mesh.target_faces=400",
]


@pytest.fixture(scope="module")
def indica_run(tmp_path_factory):
    """(the run's aggregate, the bowl's vessel, the placed pile) of the reduced indica bowl."""
    recipe = load_recipe(REPO / "graphs" / "rice_bowl.yaml", default_registry(), INDICA)
    cache = Cache(tmp_path_factory.mktemp("indica") / "cache")
    result = run_recipe(recipe, outputs=["rice_sim.aggregate", "bowl.vessel", "pile.aggregate"], cache=cache)
    return result.output("rice_sim.aggregate"), result.output("bowl.vessel"), result.output("pile.aggregate")


def test_the_run_keeps_the_long_grains_in_the_bowl(indica_run):
    # a fix by more solver effort must not launch grains: 16 particles at 80 substeps (or 8 at 40) sent grains
    # through the reduced bowl at up to 1,200 mm/s (docs/look.md); the recipe's run keeps every grain inside
    aggregate, vessel, _ = indica_run
    assert not vessel.outside(aggregate.placement.positions, margin=vessel.wall).any()


def test_long_grains_do_not_stay_crossed_after_the_run(indica_run):
    # pairs cutting into each other after the run, depth in mm (grains 2.6 mm thick): a012bc0 216 pairs, p50 / p95 /
    # max 0.57 / 1.12 / 1.30, 133 deeper than 0.5 mm (fails); with the clusters started rigid inside the bowl
    # (``rigid_start``), ``slender`` and ``depenetration_speed``: 203 pairs, 0.25 / 0.40 / 0.50, 1 deeper than 0.5 mm.
    # Not the count of pairs: the draft's 400-face meshes cut ≈ 0.25 mm into each other wherever grains touch (the
    # 16 × 80 run that launched grains out of the bowl had 59); japonica's full-resolution meshes cross p95 0.62 mm
    aggregate, _, _ = indica_run
    _, depth = crossing_depths([aggregate.element_mesh(i) for i in range(len(aggregate.placement))])
    depth = depth[depth > 0]
    assert (depth > 0.5).sum() <= 10
    assert np.percentile(depth, 95) <= 0.62 and depth.max() <= 1.0


@pytest.mark.xfail(
    strict=True,
    reason="issue 46: the contacts' mass scaling lifts the clumped pile 12.9 mm at the depenetration cap "
    "(docs/validation.md, 'Mass scaling adds momentum')",
)
def test_the_pile_does_not_rise(indica_run):
    # the slender run's 80 substeps turn the contacts' mass scaling into a lift: the overlaps that shape matching
    # re-makes every substep are pushed apart with the upper particle taking the larger share, every substep, and the
    # whole clumped pile rises from its placement at the depenetration cap (50 mm/s); placed nearer the rim (the rice
    # core halfway through the bowl's wall) it carried a grain over it. Bounding the scaled split to ten layers'
    # sinking per substep keeps it to 1.2 mm (its start's overlaps with the core), see the docs for what that broke
    aggregate, _, placed = indica_run
    rise = aggregate.placement.positions[:, 2].mean() - placed.placement.positions[:, 2].mean()
    assert rise <= 2.5


@pytest.mark.parametrize("rigid_start", [None, True, pytest.param(False, marks=pytest.mark.xfail(strict=True))])
def test_a_grain_placed_through_a_wall_starts_inside_and_whole(rigid_start):
    # a 12 mm grain lying across the wall x ∈ [−1, 0] of an open box, 3 mm of it outside: without rigid_start the
    # wall pushes its far particles out of the far side and the cluster stays torn across the wall (xfail); the
    # default (None) is on: off, the main job drew a grain torn 1.70× through its bowl's wall
    aggregate = Aggregate(
        Placement(np.array([[3.0, 10.0, 1.6]]), np.array([[0.0, 0.0, 1.0]]), kind_names=("long",)),
        (ElementLibrary("long", [long_grain(12.0, 3.0)]),),
    )
    given = {"frames": 10, "particles_per_element": 8, "log_every": 0}
    if rigid_start is not None:
        given["rigid_start"] = rigid_start
    params = XpbdParams(**xpbd.resolve_params(given))
    sim = build_simulation(aggregate, open_box(20.0, wall=1.0), frozenset({"gravity", "collider"}), params)
    for _ in range(10):
        sim.frame()
    x, q = sim.state.x, sim.model.q_rest
    p, q = x - x.mean(axis=0), q - q.mean(axis=0)
    u, _, vt = np.linalg.svd(p.T @ q)
    rotation = u @ np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))]) @ vt
    assert np.linalg.norm(p - q @ rotation.T, axis=1).max() < 0.1  # whole: a rigid copy of its rest shape
    assert (x[:, 0] > 0.0).all()  # inside the box
