"""rotate and mix_ratio: frames, ranges, per-P_num stability, ratios (SPEC §2.3–2.4)."""

from __future__ import annotations

import numpy as np
import pytest

from nodes.placement import mix_ratio, rotate
from nodes.values import Placement

from .conftest import digest, rice_library


def _points(n=400, seed=0):
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return Placement(normals * 10.0, normals)


def test_rotations_are_proper_and_zero_angles_give_the_uvw_frame():
    placement = _points()
    rotated = rotate.call(placement=placement)
    R = rotated.rotations
    assert np.allclose(np.einsum("nij,nkj->nik", R, R), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(R), 1.0)
    still = rotate.call(placement=placement, angles=(0.0, 0.0, 0.0))
    assert np.allclose(still.rotations[:, :, 2], placement.normals)  # local w (element z) = normal


def test_flow_field_steers_the_long_axis():
    placement = _points()
    flow = np.array([0.0, 0.0, 1.0])
    out = rotate.call(placement=placement, angles=(0.0, 0.0, 0.0), field="flow", flow=tuple(flow))
    u = out.rotations[:, :, 0]
    tangent = flow - (placement.normals @ flow)[:, None] * placement.normals
    ok = np.linalg.norm(tangent, axis=1) > 1e-3
    tangent = tangent[ok] / np.linalg.norm(tangent[ok], axis=1, keepdims=True)
    assert np.allclose(np.einsum("nd,nd->n", u[ok], tangent), 1.0)
    with pytest.raises(ValueError, match="zero vector"):
        rotate.call(placement=placement, field="flow", flow=(0.0, 0.0, 0.0))


def test_angle_ranges_bound_the_rotation_about_the_normal():
    placement = _points()
    base = rotate.call(placement=placement, angles=(0.0, 0.0, 0.0))
    out = rotate.call(placement=placement, angles=(0.0, 0.0, 20.0))
    cos = np.einsum("nd,nd->n", base.rotations[:, :, 0], out.rotations[:, :, 0])
    assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() <= 20.0 + 1e-6
    assert np.allclose(out.rotations[:, :, 2], placement.normals)


def test_rotation_and_kind_follow_p_num_not_the_array_index():
    placement = _points()
    keep = np.arange(0, len(placement), 3)
    full = rotate.call(seed=5, placement=placement)
    part = rotate.call(seed=5, placement=placement.subset(keep))
    assert np.array_equal(full.rotations[keep], part.rotations)
    libs = [rice_library("rice"), rice_library("chestnut")]
    mixed_full = mix_ratio.call(seed=5, placement=placement, libraries=libs, ratios=[3.0, 1.0])["placement"]
    mixed_part = mix_ratio.call(seed=5, placement=placement.subset(keep), libraries=libs, ratios=[3.0, 1.0])[
        "placement"
    ]
    assert np.array_equal(mixed_full.kinds[keep], mixed_part.kinds)


def test_ratios_are_normalised_and_respected():
    placement = _points(n=20000)
    libs = [rice_library("rice", variants=3), rice_library("chestnut", variants=1, refine_range=0.1)]
    out = mix_ratio.call(placement=placement, libraries=libs, ratios=[100.0, 1.0])["placement"]
    share = (out.kinds == 1).mean()
    assert share == pytest.approx(1 / 101, abs=0.004)
    assert out.kind_names == ("rice", "chestnut")
    assert set(out.variants[out.kinds == 0]) == {0, 1, 2} and set(out.variants[out.kinds == 1]) == {0}
    same = mix_ratio.call(placement=placement, libraries=libs, ratios=[100 / 101, 1 / 101])["placement"]
    assert digest(out.kinds, out.variants) == digest(same.kinds, same.variants)


def test_bad_ratio_lists_are_refused():
    placement = _points(n=10)
    libs = [rice_library("rice"), rice_library("chestnut")]
    with pytest.raises(ValueError, match="2 libraries"):
        mix_ratio.call(placement=placement, libraries=libs, ratios=[1.0])
    with pytest.raises(ValueError, match="> 0"):
        mix_ratio.call(placement=placement, libraries=libs, ratios=[0.0, 0.0])
    with pytest.raises(ValueError, match="must differ"):
        mix_ratio.call(placement=placement, libraries=[libs[0], libs[0]])
