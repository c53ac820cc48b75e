"""poisson_place: Poisson-disk quality, maximality, modes, derived r, determinism and bad input (SPEC §2.1–2.2)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from scipy.spatial import cKDTree

from nodegraph.values import Mesh
from nodes.placement import poisson_place
from nodes.shapes import shape
from nodes.values import ElementLibrary

from .conftest import digest, ellipsoid


@pytest.mark.parametrize("method", ["random", "subdivide"])
def test_surface_points_keep_2r_and_cover_the_shape(small_onigiri, method):
    r = 0.3
    out = poisson_place.call(shape=small_onigiri, r=r, candidates=method)
    points = out["placement"].positions
    assert out["stats"].columns["min_distance_ratio"][0] >= 1.0 - 1e-9
    # Maximal: every surface point lies within 2r (+ candidate gap) of a placed point.
    from nodes.placement.candidates import surface_candidates

    probe, _ = surface_candidates(small_onigiri.vertices, small_onigiri.faces, r, "random", np.random.default_rng(9))
    gap, _ = cKDTree(points).query(probe)
    assert gap.max() < 2 * r + r
    normals = out["placement"].normals
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert (np.einsum("nd,nd->n", normals, points - points.mean(axis=0)) > 0).mean() > 0.95  # outward


def test_volume_points_lie_inside_with_up_normals():
    ball = shape.call(kind="sphere", size=5.0)["mesh"]
    out = poisson_place.call(shape=ball, r=0.5, mode="volume")
    points = out["placement"].positions
    assert len(points) > 50
    assert np.linalg.norm(points, axis=1).max() < 5.0 + 0.25 * 0.5
    assert np.allclose(out["placement"].normals, [0, 0, 1])
    assert cKDTree(points).query(points, k=2)[0][:, 1].min() >= 1.0 - 1e-9


def test_volume_inset_keeps_points_off_the_surface():
    ball = shape.call(kind="sphere", size=5.0)["mesh"]
    inset = poisson_place.call(shape=ball, r=0.5, mode="volume", inset=1.0)["placement"].positions
    full = poisson_place.call(shape=ball, r=0.5, mode="volume")["placement"].positions
    assert np.linalg.norm(full, axis=1).max() > 4.5  # without: up to the wall
    assert np.linalg.norm(inset, axis=1).max() <= 4.0 + 0.05  # the sphere's facets lie a little inside r = 5
    assert len(inset) > 0.3 * len(full)


def test_r_from_the_element_is_half_its_inscribed_radius(small_onigiri):
    library = ElementLibrary("rice", (ellipsoid((1.1, 0.64, 0.44)),))
    out = poisson_place.call(shape=small_onigiri, elements=[library])
    assert out["stats"].columns["r"][0] == pytest.approx(0.22, rel=0.03)


def test_r_from_volume_follows_a_longer_grain_where_the_inscribed_radius_does_not(small_onigiri):
    # issue 47: an indica grain is 1.8× a japonica's length at the same width and thickness; r from the inscribed
    # radius (its thickness) stays, r from the volume grows by 1.8^(1/3), so the grains fill the same share
    def r(length, r_from):
        library = ElementLibrary("rice", (ellipsoid((length, 0.64, 0.44)),))
        out = poisson_place.call(shape=small_onigiri, elements=[library], r_from=r_from, r_scale=0.5)
        return out["stats"].columns["r"][0], out["placement"].spacing

    assert r(1.1 * 1.8, "inscribed")[0] == pytest.approx(r(1.1, "inscribed")[0], rel=0.03)
    short, spacing = r(1.1, "volume")
    assert spacing == short == pytest.approx(0.5 * (1.1 * 0.64 * 0.44) ** (1 / 3), rel=0.02)  # a sphere's volume
    assert r(1.1 * 1.8, "volume")[0] == pytest.approx(short * 1.8 ** (1 / 3), rel=0.01)


def test_same_seed_same_placement(small_onigiri):
    a = poisson_place.call(seed=3, shape=small_onigiri, r=0.3)["placement"]
    b = poisson_place.call(seed=3, shape=small_onigiri, r=0.3)["placement"]
    c = poisson_place.call(seed=4, shape=small_onigiri, r=0.3)["placement"]
    assert digest(a.positions, a.normals, a.p_num) == digest(b.positions, b.normals, b.p_num)
    assert digest(a.positions) != digest(c.positions)


def test_r_larger_than_the_shape_is_refused(small_onigiri):
    with pytest.raises(ValueError, match="larger than the shape"):
        poisson_place.call(shape=small_onigiri, r=50.0)


def test_tiny_r_is_refused_quickly_with_a_memory_estimate(small_onigiri):
    start = time.process_time()  # CPU seconds: the work done, not how busy the machine is
    with pytest.raises(ValueError, match="MiB"):
        poisson_place.call(shape=small_onigiri, r=1e-4)
    assert time.process_time() - start < 2.0


def test_no_r_and_no_elements_is_refused(small_onigiri):
    with pytest.raises(ValueError, match="give r"):
        poisson_place.call(shape=small_onigiri)


def test_zero_candidates_is_a_clear_error():
    plate = shape.call(kind="box", extents=(10.0, 10.0, 0.2))["mesh"]
    with pytest.raises(ValueError, match="no candidate"):
        poisson_place.call(shape=plate, r=1.0, mode="volume")


def test_open_or_inverted_shapes_are_refused():
    import trimesh

    ball = trimesh.creation.icosphere(2)
    inverted = Mesh(ball.vertices, ball.faces[:, ::-1])
    with pytest.raises(ValueError, match="inwards"):
        poisson_place.call(shape=inverted, r=0.1)
    holed = Mesh(ball.vertices, ball.faces[10:])
    with pytest.raises(ValueError, match="holes"):
        poisson_place.call(shape=holed, r=0.1)


def test_flat_element_cannot_set_r(small_onigiri):
    flat = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]]), np.array([[0, 1, 2], [1, 3, 2]]))
    with pytest.raises(ValueError, match="no interior"):
        poisson_place.call(shape=small_onigiri, elements=[ElementLibrary("flat", (flat,))])


@pytest.mark.parametrize("r", [12.0, 5.0])
def test_the_r_a_refusal_suggests_then_works(r):
    """A thin slab in volume mode holds a far smaller r than its extent suggests: the hint names an r that
    runs (it used to say "use r < 12" for a 24 mm slab 2 mm thick, where r = 5 fails too)."""
    import re

    slab = shape.call(kind="box", extents=[24.0, 24.0, 2.0])["mesh"]
    with pytest.raises(ValueError) as info:
        poisson_place.call(shape=slab, r=r, mode="volume")
    suggested = float(re.search(r"r ≤ ([0-9.]+) finds candidate points", str(info.value)).group(1))
    assert suggested < min(r, 12.0)  # below what the old hint allowed (half the extent)
    assert len(poisson_place.call(shape=slab, r=suggested, mode="volume")["placement"].positions) > 0
