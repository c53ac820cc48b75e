"""Moulds: closed shapes whose inside is the free space (onigiri, bunny) — grains pressed in stay in."""

import numpy as np
import pytest
import trimesh
from scene_builders import rice_library
from scipy.spatial.transform import Rotation

from nodegraph.values import Mesh
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, Placement

PRESS = ("contact", "friction", "adhesion", "collider", "moisture", "damping")


def ball_mould(radius=12.0) -> Mesh:
    return Mesh.from_trimesh(trimesh.creation.icosphere(4, radius=radius))


def crowded_ball(n=60, radius=12.0, seed=1) -> Aggregate:
    """n grains with centres in the outer shell of the ball: many stick out through its surface."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    positions = d * rng.uniform(0.6 * radius, radius - 0.5, (n, 1))
    placement = Placement(
        positions,
        np.tile([0.0, 0.0, 1.0], (n, 1)),
        Rotation.random(n, random_state=seed).as_matrix(),
        variants=rng.integers(0, 4, n).astype(np.int32),
        kind_names=("japonica",),
    )
    return Aggregate(placement, (rice_library(seed=seed),))


def test_grains_sticking_out_of_a_mould_are_pressed_inside_and_stay():
    aggregate = crowded_ball()
    out = xpbd.call(effects=PRESS, aggregate=aggregate, moulds=[ball_mould()], frames=20, substeps=5)
    p = out["particles"]
    before = xpbd.call(effects=("contact",), aggregate=aggregate, frames=1, substeps=1)["particles"]
    reach = np.linalg.norm(p.positions, axis=1) + p.radii
    assert (np.linalg.norm(before.positions, axis=1) + before.radii).max() > 12.5  # some stuck out
    assert np.isfinite(p.positions).all()
    assert reach.max() < 12.0 + 0.1 * p.radii.max()  # all inside the ball now (φ ≥ r, up to 0.1 r)


def test_collider_effect_accepts_a_mould_alone_and_full_mode_refuses_one():
    aggregate = crowded_ball(n=10)
    out = xpbd.call(effects=("collider",), aggregate=aggregate, moulds=[ball_mould()], frames=2, substeps=2)
    p = out["particles"]
    before = xpbd.call(aggregate=aggregate, frames=1, substeps=1)
    assert (np.linalg.norm(before["particles"].positions, axis=1) + p.radii).max() > 12.5  # some stuck out
    assert np.isfinite(p.positions).all()
    assert (np.linalg.norm(p.positions, axis=1) + p.radii).max() < 12.0 + 0.1 * p.radii.max()  # the mould acted
    with pytest.raises(ValueError, match="mould"):
        xpbd.call(effects=("gravity", "collider"), aggregate=aggregate, moulds=[ball_mould()], frames=30, mode="full")
    with pytest.raises(ValueError, match="'colliders' or 'moulds'"):
        xpbd.call(effects=("collider",), aggregate=aggregate, frames=2)
