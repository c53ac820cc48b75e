"""overlap_refine's shape bound: no element stands out of the shape it fills by more than ``protrusion`` of its
own size (issue 26: chestnut pieces, 2.3× a grain, stood out of the onigiri by up to 1.4× their size), measured
here on the elements' full meshes against the shape (SPEC §2.6)."""

from __future__ import annotations

import igl
import numpy as np
import pytest

from nodes.placement import mix_ratio, overlap_refine, poisson_place, rotate
from nodes.values import ElementLibrary

from .conftest import ellipsoid, rice_library


def _reach_share(placement, libraries, solid):
    """Per element: how far its mesh reaches outside ``solid`` over its extent along the solid's outward normal
    nearest its centre (every vertex of its mesh)."""
    vertices, faces = np.asarray(solid.vertices, float), np.asarray(solid.faces, np.int64)
    sign = igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL
    normals = igl.signed_distance(placement.positions, vertices, faces, sign_type=sign)[3]
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    worlds = []
    for i in range(len(placement)):
        library = libraries[placement.kinds[i]]
        mesh = library.meshes[placement.variants[i] % len(library)]
        worlds.append(placement.positions[i] + np.asarray(mesh.vertices) @ placement.rotations[i].T)
    start = np.cumsum([0] + [len(w) for w in worlds])
    distance = igl.signed_distance(np.vstack(worlds), vertices, faces, sign_type=sign)[0]
    share = np.zeros(len(placement))
    for i, world in enumerate(worlds):
        height = world @ normals[i]
        share[i] = distance[start[i] : start[i + 1]].max() / (height.max() - height.min())
    return share


@pytest.fixture(scope="module")
def onigiri():
    """An onigiri 6× a piece across, as the kuri gohan recipe's (76 mm, pieces ≈ 11 mm)."""
    from nodes.shapes import shape

    return shape.call(kind="onigiri", size=12.0, resolution=4)["mesh"]


@pytest.fixture(scope="module")
def lumpy(onigiri):
    """Grains and pieces ≈ 2× a grain (refined ±2 b, as the recipe's chestnut) on the onigiri's surface."""
    rice = rice_library()
    chestnut = ElementLibrary("chestnut", tuple(ellipsoid((2.0, 1.7, 1.4)) for _ in range(2)), refine_range=2.0)
    placed = poisson_place.call(seed=1, shape=onigiri, r=0.5)["placement"]
    turned = rotate.call(seed=1, placement=placed)
    mixed = mix_ratio.call(seed=1, placement=turned, libraries=[rice, chestnut], ratios=[10, 1])["placement"]
    return mixed, (rice, chestnut)


def test_unbounded_refine_lets_large_elements_stand_out(lumpy, onigiri):
    """The set-up does test the bound: without the shape, pieces stand out by more than half their size."""
    mixed, libraries = lumpy
    refined = overlap_refine.call(seed=2, placement=mixed, libraries=list(libraries))["placement"]
    share = _reach_share(refined, libraries, onigiri)
    assert (share[refined.kinds == 1] > 0.5).sum() >= 3


@pytest.mark.parametrize("protrusion", [0.0, 0.25, 0.5])
def test_no_element_stands_out_of_the_shape_beyond_its_share(lumpy, onigiri, protrusion):
    mixed, libraries = lumpy
    refined = overlap_refine.call(
        seed=2, placement=mixed, libraries=list(libraries), shape=onigiri, protrusion=[protrusion]
    )["placement"]
    share = _reach_share(refined, libraries, onigiri)
    assert share.max() <= protrusion + 0.03  # the bound is kept on the cost points (spread vertices)
    pieces = refined.kinds == 1
    assert pieces.sum() >= 5 and share[pieces].max() >= protrusion - 0.15  # pushed to the bound, not buried


def test_shape_bound_is_deterministic(lumpy, onigiri):
    mixed, libraries = lumpy
    a, b = (
        overlap_refine.call(seed=2, placement=mixed, libraries=list(libraries), shape=onigiri)["placement"]
        for _ in range(2)
    )
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.offsets, b.offsets)
