"""Sizes from published measurements, with the spread between elements (docs/sizes.md): broken grains among a
family's variants, eggs whose diameter varies, and an egg placement whose spacing follows the eggs."""

from __future__ import annotations

import numpy as np
import pytest

from nodegraph.context import Context
from nodegraph.params import ParamValueError
from nodes.elements import base_mesh, distance_field, element_library, expand, remesh, sphere_scatter, voxelise
from nodes.elements.expand import is_broken
from nodes.placement.poisson_place import _radius_from_elements

from .conftest import as_trimesh


def test_broken_variants_are_spread_evenly_over_a_family():
    assert sum(is_broken(v, 1 / 16) for v in range(16)) == 1
    assert sum(is_broken(v, 0.5) for v in range(16)) == 8
    assert not any(is_broken(v, 0.0) for v in range(16))
    assert not is_broken(None, 0.0625)  # outside a family: variant 0


def _field(japonica):
    spheres = sphere_scatter.call(seed=1, mesh=japonica, count=0)
    volume = voxelise.call(mesh=japonica, spheres=spheres, resolution=24)
    return distance_field.call(volume=volume, mesh=japonica, spheres=spheres)


def _grow(field, variant, broken, keep=(0.6, 0.6)):
    ctx = Context.standalone(node_type="expand", seed=0, variant=variant)
    return expand(
        ctx, field=field, variety=None, expansion=(1.2, 1.2), elongation=1.0, broken=broken, broken_length=keep
    )


def test_a_broken_grain_keeps_its_share_of_the_length_and_stays_closed(japonica):
    field = _field(japonica)
    whole = remesh.call(field=_grow(field, 15, 0.0))
    broken = remesh.call(field=_grow(field, 15, 1 / 16))
    tm = as_trimesh(broken)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    ratio = np.ptp(broken.vertices[:, 0]) / np.ptp(whole.vertices[:, 0])
    assert ratio == pytest.approx(0.6, abs=0.05)
    assert np.ptp(broken.vertices[:, 1]) == pytest.approx(np.ptp(whole.vertices[:, 1]), rel=0.05)  # cut across x
    # the other 15 variants are left whole, bit for bit
    assert np.array_equal(_grow(field, 3, 1 / 16).data, _grow(field, 3, 0.0).data)


def _extents(grain) -> np.ndarray:
    return np.ptp(grain.vertices, axis=0)


def test_cooking_lengthens_a_grain_more_than_it_widens_it(japonica):
    """e = 1.25: length × P·e^(2/3), width and thickness × P·e^(−1/3) — length/width grows by e, the volume by P³
    as G eq. 6's isotropic P (the field is resampled along x, so within a voxel's share), and the grain stays a
    closed outward surface; e = 1 leaves G's exact scaling bit for bit."""
    field = _field(japonica)
    ctx = Context.standalone(node_type="expand", seed=0)

    def grown(e):
        return expand(
            ctx, field=field, variety=None, expansion=(1.2, 1.2), elongation=e, broken=0.0, broken_length=(0.6, 0.6)
        )

    iso, long = remesh.call(field=grown(1.0)), remesh.call(field=grown(1.25))
    tm = as_trimesh(long)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    a, b = _extents(iso), _extents(long)
    assert (b[0] / b[1]) / (a[0] / a[1]) == pytest.approx(1.25, rel=0.03)
    assert b[0] / a[0] == pytest.approx(1.25 ** (2 / 3), rel=0.03)
    assert b[2] / a[2] == pytest.approx(1.25 ** (-1 / 3), rel=0.03)
    assert tm.volume / as_trimesh(iso).volume == pytest.approx(1.0, rel=0.03)
    assert np.array_equal(grown(1.0).data, expand.call(field=field, expansion=(1.2, 1.2)).data)


def _diameter(egg) -> float:
    return float(np.ptp(egg.vertices, axis=0).max())  # the membrane (part 0) is the outer shell


def test_eggs_vary_in_diameter_by_seed_within_two_sd():
    eggs = [base_mesh.call(seed=s, shape="ikura", diameter=6.5, diameter_sd=0.25, subdivisions=0) for s in range(8)]
    sizes = [_diameter(e) for e in eggs]
    assert len(set(np.round(sizes, 6))) == 8
    assert 6.0 - 1e-9 <= min(sizes) and max(sizes) <= 7.0 + 1e-9
    again = base_mesh.call(seed=5, shape="ikura", diameter=6.5, diameter_sd=0.25, subdivisions=0)
    assert np.array_equal(again.vertices, eggs[5].vertices)
    assert _diameter(base_mesh.call(seed=5, shape="ikura", diameter=6.5, subdivisions=0)) == pytest.approx(6.5, 1e-3)


def test_egg_spacing_follows_the_egg_size():
    """r from the elements reads the egg's membrane, not its yolk: half the egg's radius, for any diameter."""
    for diameter in (4.5, 6.5):
        library = element_library.call(meshes=[base_mesh.call(shape="ikura", diameter=diameter)], kind="ikura")
        assert _radius_from_elements([library]) == pytest.approx(diameter / 4, rel=0.03)


@pytest.mark.parametrize(
    ("given", "words"),
    [
        ({"shape": "rice", "diameter_sd": 0.2}, "only used with shape 'ikura'"),
        ({"shape": "ikura", "diameter": 4.0, "diameter_sd": 1.5}, "allowed: diameter_sd ≤ 1 mm"),
    ],
)
def test_bad_diameter_spread_is_refused_with_what_is_allowed(given, words):
    with pytest.raises(ParamValueError, match="diameter_sd") as err:
        base_mesh.call(**given)
    assert words in str(err.value)
