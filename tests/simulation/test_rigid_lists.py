"""The Verlet lists outlive a rigid motion of the whole set (``spatial_hash.rigid_deviation``, ``XpbdSolver``): a
glued onigiri rocking on its plate moves every particle past half the skin without moving any pair."""

import numpy as np

from nodes.simulation.scenes import GLUE_EFFECTS, pressed_block
from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.shape_matching import quat_to_matrix
from nodes.simulation.spatial_hash import rigid_deviation
from nodes.simulation.xpbd import xpbd


def turned(x, angle, shift):
    """``x`` turned by ``angle`` about a tilted axis through its centre and shifted by ``shift``."""
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    q = np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])
    rot = np.empty((3, 3))
    quat_to_matrix(q, rot)
    c = x.mean(axis=0)
    return (x - c) @ rot.T + c + shift


def test_a_rigid_motion_deviates_by_nothing_and_a_push_by_its_length():
    x = np.random.default_rng(1).normal(size=(500, 3)) * [20.0, 8.0, 30.0]
    moved = turned(x, 0.05, [1.0, -2.0, 0.5])  # the far particles travel ≈ 3 mm
    assert np.linalg.norm(moved - x, axis=1).max() > 2.0
    quat = np.array([1.0, 0.0, 0.0, 0.0])
    assert rigid_deviation(moved, x, quat, np.empty((3, 3))) < 0.01  # the fitted rotation converges over calls
    moved[17, 2] += 0.4  # one particle pushed out of the rigid motion
    assert abs(rigid_deviation(moved, x, quat, np.empty((3, 3))) - 0.4) < 0.01


def test_lists_survive_a_rigid_motion_and_not_a_deformation():
    aggregate, colliders = pressed_block(3, 3, 4, press_frames=3)
    p = XpbdParams(**xpbd.resolve_params({"frames": 1, "glue": 1.0, "clumping": 0.5}))
    sim = build_simulation(aggregate, colliders, GLUE_EFFECTS, p, threads=1)
    sim.frame()
    solver, st = sim.solver, sim.state
    pairs = solver.pairs
    built = pairs.lists
    st.x[:] = turned(pairs.x_built, 0.03, [0.0, 0.0, 0.5])
    pairs.displacement = np.linalg.norm(st.x - pairs.x_built, axis=1).max()
    assert pairs.displacement > 0.5 * pairs.skin  # each particle's own move asks for a new build
    assert not solver._refresh_neighbours(st) and pairs.lists is built
    st.x[5, 0] += pairs.skin  # a deformation
    assert solver._refresh_neighbours(st) and pairs.lists is not built
