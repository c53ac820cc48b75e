"""Grain skin (issue 26): the skin score's calibration, and cooked grains that are plump and smooth."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.elements import base_mesh, distance_field, expand, remesh, sphere_scatter, voxelise
from nodes.elements.grain_shapes import icosphere, volume_centroid
from nodes.quality.skin import skin_score

AXES = np.array([2.5, 1.5, 1.0])  # a 5 × 3 × 2 mm grain-sized ellipsoid


def ellipsoid(bumps: float = 0.0, waves: int = 5):
    """An ellipsoid (icosphere, 20,480 faces) with radial sinusoidal bumps of relative height ``bumps``."""
    vertices, faces = icosphere(5)
    unit = vertices / np.linalg.norm(vertices, axis=1, keepdims=True)
    theta = np.arccos(np.clip(unit[:, 2], -1.0, 1.0))
    phi = np.arctan2(unit[:, 1], unit[:, 0])
    radius = 1.0 + bumps * np.sin(waves * theta) * np.sin(waves * phi)
    return unit * radius[:, None] * AXES, faces


def test_convex_ellipsoid_scores_zero():
    assert skin_score(*ellipsoid()) == 0.0


def test_bumpy_ellipsoid_scores_about_017():
    assert skin_score(*ellipsoid(0.04)) == pytest.approx(0.17, abs=0.015)


def test_non_manifold_edge_is_refused():
    vertices, faces = ellipsoid()
    with pytest.raises(ValueError, match="more than two faces"):
        skin_score(vertices, np.vstack([faces, faces[:1]]))


def grain(seed, sink, blur):
    mesh = base_mesh.call()
    spheres = sphere_scatter.call(
        seed=seed, mesh=mesh, count=40, radius_range=(0.15, 0.35), surface_share=0.7, sink=sink
    )
    volume = voxelise.call(mesh=mesh, spheres=spheres, resolution=40)
    field = distance_field.call(volume=volume, mesh=mesh, spheres=spheres)
    grown = expand.call(seed=seed, field=field, expansion=(1.0, 1.5))
    return remesh.call(field=grown, target_faces=1800, blur=blur), grown


@pytest.mark.parametrize("seed", [0, 1])
def test_cooked_grain_is_smooth_and_keeps_its_volume(seed):
    lumpy, _ = grain(seed, sink=0.0, blur=0.0)  # G's spheres centred on the skin: half-ball bumps
    cooked, field = grain(seed, sink=0.6, blur=0.3)  # the recipes' cooked rice
    assert skin_score(lumpy.vertices, lumpy.faces) > 0.25
    assert skin_score(cooked.vertices, cooked.faces) <= 0.10
    cells = np.count_nonzero(np.asarray(field.data) > 0.0) * field.voxel_size**3
    volume, _ = volume_centroid(cooked.vertices, cooked.faces)
    assert volume == pytest.approx(cells, rel=0.03)  # the blur's level keeps the grain plump


def test_sunk_spheres_swell_the_skin_by_less_than_their_radius():
    mesh = base_mesh.call()
    on, sunk = (sphere_scatter.call(seed=5, mesh=mesh, count=30, surface_share=1.0, sink=s) for s in (0.0, 0.6))
    assert np.array_equal(on.radii, sunk.radii)  # same draws: only the centres move
    depth = np.linalg.norm(on.centers - sunk.centers, axis=1)
    assert np.allclose(depth, 0.6 * on.radii)
