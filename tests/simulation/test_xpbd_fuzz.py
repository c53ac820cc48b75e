"""Property-based fuzzing of the XPBD solver (issue 11) with hypothesis: random small scenes —
element counts, masses 1e-3 … 1e3 g, radii, Δt, substeps, iterations, compliance, speed clamp over
the node's whole range, initial overlaps, degenerate (one-particle, collinear) clusters — dropped on
a ground slab. Invariants, every frame: finite; energy ≤ initial + ε (gravity's work is in the
potential term, nothing else does work); no particle centre inside the ground; same seed ⇒ same bits.
Scenes the solver refuses (``SolverSettings`` / ``step_limits.check_gravity_step`` ValueError: gravity's
step beyond what the iterations or the speed clamp hold) are skipped. CI runs a few derandomized
examples; ``XPBD_FUZZ_EXAMPLES=500`` also runs that many random ones."""

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scene_builders import box_mesh, mechanical_energy, solver_run

from nodes.simulation.collider import sample_phi, signed_distance_grid
from nodes.simulation.settings import solver_settings_for

EXAMPLES = int(os.environ.get("XPBD_FUZZ_EXAMPLES", "6"))
GROUND = signed_distance_grid(
    [box_mesh([-40, -40, -6], [40, 40, 0], "ground")], np.array([-30.0, -30, -5]), np.array([30.0, 30, 40]), 0.5
)


@st.composite
def scenes(draw):
    elements = draw(st.integers(1, 5))
    per = draw(st.sampled_from([1, 2, 4]))
    radius = draw(st.floats(0.3, 1.5))
    overlap = draw(st.floats(0.0, 1.5))  # initial overlap between neighbouring elements, radii
    masses = [10.0 ** draw(st.floats(-3.0, 3.0)) for _ in range(elements)]
    seed = draw(st.integers(0, 2**16))
    solver = dict(
        dt=draw(st.sampled_from([1 / 240, 1 / 60, 1 / 30])),
        substeps=draw(st.integers(1, 16)),
        iterations=draw(st.integers(1, 4)),
        # N/m: compliance 1e-8 (the node's stiffest; 0 is no node setting) to 1 s²/g
        stiffness=draw(st.sampled_from([100000.0, 10000.0, 100.0, 1.0, 0.001])),
        speed_clamp=draw(st.floats(0.1, 2.0)),
        shock_propagation=draw(st.sampled_from([1.0, 4.0])),
    )
    return elements, per, radius, overlap, masses, seed, solver


def build(elements, per, radius, overlap, masses, seed, solver):
    rng = np.random.default_rng(seed)
    local = np.stack([np.arange(per) * 2.0 * radius, np.zeros(per), np.zeros(per)], 1)  # collinear or single
    local -= local.mean(axis=0)
    pitch = (2.0 - overlap) * radius
    xs, ws = [], []
    for k in range(elements):
        centre = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), radius * 1.05 + k * pitch])
        xs.append(local + centre)
        ws.append(np.full(per, per / masses[k]))
    # as fuzzed (issue 11): μk/μs 2/3, no sleeping, a rigid goal (β = 0)
    plain = dict(dynamic_scale=0.4 / 0.6, sleep_speed=0.0, linear_deformation=0.0)
    effects = frozenset({"gravity", "contact", "friction", "collider"})
    settings_ = solver_settings_for(effects, radius, **plain, **solver)
    return solver_run(
        np.concatenate(xs),
        np.full(elements * per, radius),
        np.concatenate(ws),
        np.arange(elements + 1) * per,
        np.tile(local, (elements, 1)),
        np.tile([1.0, 0, 0, 0], (elements, 1)),
        settings_,
        sdf=GROUND,
    )


def run(scene, frames=20):
    try:
        s = build(*scene)
    except ValueError as refused:
        assert "substeps ≥" in str(refused)
        return None
    e0 = mechanical_energy(s)
    # separating the initial overlaps lifts the elements above them (pre-stabilisation, no velocity):
    # potential energy up to M·g·(overlap·r per element below), the only gain the invariant allows
    elements, _, radius, overlap = scene[:4]
    scale = float(np.sum(1.0 / s.model.w)) * s.solver.settings.gravity * radius * (0.05 + overlap * (elements - 1))
    phi, origin, pitch = GROUND
    for _ in range(frames):
        s.frame()
        assert np.isfinite(s.state.x).all() and np.isfinite(s.state.v).all()
        assert mechanical_energy(s) <= e0 + scale + 1e-9
        for p in s.state.x:
            if np.abs(p[:2]).max() < 29.0:
                assert sample_phi(phi, origin, pitch, p[0], p[1], p[2])[0] >= 0.0  # centre in free space
    return s


SHRUNK = [  # failures hypothesis shrank, kept as regressions
    # two unit spheres overlapping by a radius: their separation's potential energy was not allowed for
    (2, 1, 1.0, 1.0, [1.0, 1.0], 0, dict(dt=1 / 240, substeps=1, iterations=1, stiffness=100000.0, speed_clamp=1.0)),
    # the 200-example run at merge (issue 11): masses 1 : 31.6 overlapping by 0.75 r, one substep, clamp 2:
    # the energy rose to 1.53e6 against a bound of 1.47e6, while the light one under the heavy one took
    # nearly the whole correction; fixed by blending the shares of a supporting contact (``lifted_share``)
    (
        2,
        1,
        1.5,
        0.75,
        [1.0, 31.622776601683793],
        0,
        dict(dt=1 / 240, substeps=1, iterations=2, stiffness=100000.0, speed_clamp=2.0, shock_propagation=4.0),
    ),
]


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True)
@given(scenes())
def test_random_scenes_keep_the_invariants(scene):
    run(scene)


@pytest.mark.parametrize("scene", SHRUNK, ids=["equal-masses-overlap", "light-under-heavy-energy-gain"])
def test_shrunk_failures_keep_the_invariants(scene):
    run(scene)


def test_same_seed_same_bits():
    scene = (
        3,
        4,
        0.6,
        0.8,
        [1e-3, 1.0, 1e3],
        7,
        dict(dt=1 / 60, substeps=4, iterations=2, stiffness=1000.0, speed_clamp=2.0),
    )
    a, b = run(scene, 10), run(scene, 10)
    assert a.state.x.tobytes() == b.state.x.tobytes() and a.state.v.tobytes() == b.state.v.tobytes()


@pytest.mark.skipif("XPBD_FUZZ_EXAMPLES" not in os.environ, reason="many examples: XPBD_FUZZ_EXAMPLES=200")
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scenes())
def test_many_random_scenes(scene):
    run(scene)
