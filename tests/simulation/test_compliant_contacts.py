"""Compliant contacts (``squeeze_strain``, issue 46): a grain squeezed under 0.2 N strains 20–30 % as cooked rice
does (Tomita, via G; SPEC §3), its contacts hold the overlap α·F at rest whatever the iterations (XPBD), and a
landing grain bounces no more than on rigid contacts."""

import numpy as np
import pytest
from scene_builders import solver_run

from nodes.simulation.contact_constraints import face_compliance
from nodes.simulation.settings import CRUSH_STRAIN, SQUEEZE_LOAD, solver_settings_for

EFFECTS = frozenset({"gravity", "contact", "collider", "damping"})


def test_face_compliance_of_a_sphere():
    """A sphere of radius 1 mm squeezed 25 % at 0.2 N: each face gives 0.25 mm, carried by its one particle."""
    alpha, crush = face_compliance(np.array([1.0]), np.zeros((1, 3)), np.array([0, 1]), 0.25, SQUEEZE_LOAD, 0.5)
    assert alpha == pytest.approx(0.25 / 0.2)  # mm/N
    assert crush == pytest.approx(0.5)


def sphere_on_obstacle(iterations: int, strain: float) -> float:
    """A 20 g sphere (r 1 mm, its weight 0.196 N) resting on a static sphere for 1 s: its overlap (mm)."""
    settings = solver_settings_for(EFFECTS, 1.0, iterations=iterations, squeeze_strain=strain, sleep_speed=0.0)
    x = np.array([[0.0, 0.0, 2.05]])
    run = solver_run(
        x, np.array([1.0]), np.array([1 / 20.0]), np.array([0, 1]), np.zeros((1, 3)), np.array([[1.0, 0, 0, 0]]),
        settings, obstacles=(np.zeros((1, 3)), np.array([1.0])),
    )  # fmt: skip
    for _ in range(60):
        run.frame()
    return 2.0 - float(run.state.x[0, 2])


@pytest.mark.parametrize("iterations", [1, 2, 8])
def test_resting_overlap_is_compliance_times_load(iterations):
    """On a rigid obstacle one face gives: overlap = α·F (α of a 1 mm sphere at 25 %: 1.25 mm/N), at any
    iterations; rigid contacts hold it at 0."""
    weight = 20.0e-3 * 9.81  # N
    alpha, _ = face_compliance(np.array([1.0]), np.zeros((1, 3)), np.array([0, 1]), 0.25, SQUEEZE_LOAD, CRUSH_STRAIN)
    assert sphere_on_obstacle(iterations, 25.0) == pytest.approx(alpha * weight, rel=0.05)
    assert abs(sphere_on_obstacle(iterations, 0.0)) < 0.01 * alpha * weight


def test_a_grain_squeezed_under_a_flat_plate_strains_as_cooked_rice():
    """Three library grains under a flat plate: 20–30 % at 0.2 N (Tomita: ≈ 25 %), rigid contacts < 2 %; no grain
    squeezed out or passed through."""
    from validation import squeeze_xpbd

    def strain(strain_percent):
        rest = squeeze_xpbd(0.001, flat=True, frames=60, squeeze_strain=strain_percent)
        loaded = squeeze_xpbd(0.2, flat=True, frames=60, squeeze_strain=strain_percent)
        assert loaded["escaped"] == 0 and loaded["above"] == 0
        return 1.0 - loaded["gap"] / rest["gap"]

    assert 0.20 <= strain(25.0) <= 0.30
    assert strain(0.0) < 0.02


def test_a_landing_grain_bounces_no_more_than_on_rigid_contacts():
    """A grain dropped 10 mm on another: the damped compliance gives back no more than rigid contacts (+30 %: the
    undamped compliance rebounds twice as high)."""
    from validation import drop_bounce

    soft = drop_bounce(frames=30, squeeze_strain=25.0)["rebound"]
    rigid = drop_bounce(frames=30, squeeze_strain=0.0)["rebound"]
    assert soft <= 1.3 * rigid + 0.005
