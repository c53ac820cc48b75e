"""Static obstacle particles (xpbd input ``obstacles``): eggs dropped on a particle bed rest on it,
the bed never moves and is not in the outputs; unwired, nothing is appended or allocated."""

import numpy as np
import pytest
from scene_builders import ikura_mesh, rice_bowl
from scipy.spatial import cKDTree

from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation, finish_simulation
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, ElementLibrary, ParticleState, Placement

PAIRS = ("gravity", "contact", "friction", "adhesion", "damping")


def params(**given):
    return xpbd.resolve_params({"frames": 30, "substeps": 8, "particles_per_element": 4, "log_every": 0, **given})


def typed(**given) -> XpbdParams:
    return XpbdParams(**params(**given))


def particle_bed(half=20.0, spacing=1.5, radius=1.0, layers=2) -> ParticleState:
    """Square grid layers of unit spheres, top layer at z = 0 (holes narrower than any egg particle)."""
    axis = np.arange(-half, half + 1e-9, spacing)
    gx, gy = np.meshgrid(axis, axis, indexing="ij")
    x = np.concatenate(
        [
            np.stack(
                [
                    gx.ravel() + 0.5 * spacing * (k % 2),
                    gy.ravel() + 0.5 * spacing * (k % 2),
                    np.full(gx.size, -k * spacing),
                ],
                1,
            )
            for k in range(layers)
        ]
    )
    n = len(x)
    return ParticleState(x, np.zeros_like(x), np.full(n, radius), np.zeros(n), np.zeros(n, np.int32))


def eggs_above(n_side=3, spacing=6.0, height=6.0, radius=2.5) -> Aggregate:
    axis = (np.arange(n_side) - (n_side - 1) / 2) * spacing
    gx, gy = np.meshgrid(axis, axis, indexing="ij")
    pos = np.stack([gx.ravel(), gy.ravel(), np.full(gx.size, height)], 1)
    pos[:, 2] += np.arange(len(pos)) * 0.7  # staggered: they land one after another
    placement = Placement(pos, np.tile([0.0, 0.0, 1.0], (len(pos), 1)), kind_names=("ikura",))
    return Aggregate(placement, (ElementLibrary("ikura", [ikura_mesh(radius)]),))


def worst_overlap(x, r, bed):
    """max over (moving particle, bed particle) pairs of (r_i + r_j − d) / min(r_i, r_j)."""
    tree = cKDTree(bed.positions)
    worst = -np.inf
    for xi, ri in zip(x, r):
        for j in tree.query_ball_point(xi, ri + bed.radii.max()):
            d = np.linalg.norm(xi - bed.positions[j])
            worst = max(worst, (ri + bed.radii[j] - d) / min(ri, bed.radii[j]))
    return worst


@pytest.mark.parametrize("effects", [("gravity", "contact", "damping"), PAIRS])
def test_eggs_dropped_on_a_particle_bed_rest_on_it(effects):
    bed = particle_bed()
    aggregate = eggs_above()
    sim = build_simulation(aggregate, [], frozenset(effects), typed(), obstacles=[bed])
    n = sim.model.n_moving
    assert len(sim.state.x) == n + len(bed) and np.all(sim.model.w[n:] == 0.0)
    for _ in range(30):
        sim.frame()
    out = finish_simulation(sim)
    x, r = out["particles"].positions, out["particles"].radii
    assert np.isfinite(sim.state.x).all() and np.isfinite(sim.state.v).all()
    assert np.array_equal(sim.state.x[n:], bed.positions)  # the bed did not move, not by one bit
    assert len(x) == n and out["particles"].element.max() == len(aggregate.placement) - 1  # bed not in the output
    z0 = aggregate.placement.positions[:, 2]
    assert np.all(out["aggregate"].placement.positions[:, 2] < z0 - 2.0)  # every egg fell …
    assert x[:, 2].min() - r[x[:, 2].argmin()] > bed.positions[:, 2].max() - 0.3  # … and rests on top of the bed
    assert worst_overlap(x, r, bed) < 0.2  # penetration bound, in radii
    assert np.linalg.norm(out["particles"].velocities, axis=1).max() < 50.0  # at rest (mm/s)


def test_obstacles_through_the_node_match_the_builder():
    bed = particle_bed(half=10.0)
    out = xpbd.call(
        effects=("gravity", "contact"), aggregate=eggs_above(n_side=1), obstacles=[bed], **params(frames=20)
    )
    assert out["particles"].positions[:, 2].min() > -0.5  # landed on the bed instead of falling through
    assert len(out["particles"]) == 4


def test_unwired_obstacles_allocate_nothing():
    aggregate, colliders = rice_bowl(20, seed=1)
    effects = frozenset({"gravity", "contact", "friction", "collider"})
    plain = build_simulation(aggregate, colliders, effects, typed())
    empty = build_simulation(aggregate, colliders, effects, typed(), obstacles=[])
    for sim in (plain, empty):
        m, st, pairs = sim.model, sim.state, sim.solver.contacts
        assert m.n_moving == len(m.x0) == len(m.w) == len(m.elem) == m.start[-1]
        per_particle = (
            st.x,
            st.v,
            st.x_prev,
            st.x_start,
            st.awake,
            st.pushed,
            pairs.x_built,
            pairs.moved,
            sim.solver.clusters.lam,
        )
        assert all(len(a) == m.n_moving for a in per_particle)
    # wired, but no pair effect would touch them: nothing appended either
    lone = build_simulation(
        aggregate, colliders, frozenset({"gravity", "collider"}), typed(), obstacles=[particle_bed(half=5.0)]
    )
    assert len(lone.state.x) == lone.model.n_moving
    for _ in range(2):
        plain.frame()
        empty.frame()
    assert np.array_equal(plain.state.x, empty.state.x)


def test_bad_obstacles_are_reported():
    bed = particle_bed(half=3.0)
    broken = ParticleState(bed.positions, bed.velocities, np.zeros(len(bed)), bed.inv_mass, bed.element)
    with pytest.raises(ValueError, match="obstacles"):
        xpbd.call(
            effects=("gravity", "contact"), aggregate=eggs_above(n_side=1), obstacles=[broken], **params(frames=1)
        )
