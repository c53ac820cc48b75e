"""rotate and mix_ratio: frames, ranges, per-P_num stability, ratios (SPEC §2.3–2.4)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from nodes.placement import mix_ratio, rotate
from nodes.values import ElementLibrary, ParticleState, Placement

from .conftest import digest, ellipsoid, rice_library


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


def test_lift_apart_lifts_an_element_clear_by_its_own_size_and_leaves_a_clear_one_as_it_was():
    """Eggs spaced by the smallest and drawn large side by side start deep inside one another, and the drop threw
    them out of the bowl (issue 47): the upper is lifted until the overlap is at most the share of the smaller."""
    from nodes.placement import lift_apart

    eggs = ElementLibrary("ikura", (ellipsoid((5.0, 5.0, 5.0), 1), ellipsoid((3.0, 3.0, 3.0), 1)))
    positions = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.2], [20.0, 0.0, 0.0], [26.5, 0.0, 0.0]])
    placement = Placement(positions, np.tile([0.0, 0.0, 1.0], (4, 1)), variants=[0, 0, 1, 0])
    out = lift_apart.call(placement=placement, libraries=[eggs], overlap=0.25)
    moved = out["placement"].positions
    least = 10.0 - 0.25 * 5.0  # the two large ones: R + R less a quarter of R
    assert np.isclose(np.linalg.norm(moved[1] - moved[0]), least)  # the higher one lifted just clear, straight up
    assert np.array_equal(moved[[0, 2]], positions[[0, 2]]) and np.array_equal(moved[:, :2], positions[:, :2])
    assert np.isclose(np.linalg.norm(moved[3] - moved[2]), 8.0 - 0.25 * 3.0)  # large over small: the small's share
    clear = Placement(positions[[0, 2]], np.tile([0.0, 0.0, 1.0], (2, 1)))
    assert lift_apart.call(placement=clear, libraries=[eggs])["placement"] is clear  # the same values, bit for bit
    pile = ParticleState(np.array([[0.0, 0.0, -5.5]]), np.zeros((1, 3)), np.array([1.0]), np.zeros(1), np.zeros(1, int))
    on_pile = lift_apart.call(placement=clear, libraries=[eggs], below=[pile], overlap=0.25)["placement"].positions
    assert np.isclose(on_pile[0, 2], -5.5 + 6.0 - 0.25 * 1.0) and on_pile[1, 2] == 0.0  # clear of the pile below
    # the main job's eggs go through it, clear of the settled rice, before they are dropped
    from nodegraph.api import default_registry, load_recipe

    recipe = load_recipe(Path(__file__).resolve().parents[2] / "graphs" / "ikura_don.yaml", default_registry())
    (wire,) = recipe.nodes["egg_sim"].inputs["aggregate"]
    apart = recipe.nodes[wire.node]
    assert apart.spec.type_name == "lift_apart" and [w.node for w in apart.inputs["below"]] == ["rice_sim"]


def test_lift_apart_says_nothing_a_user_cannot_act_on():
    """Issue 47: larger eggs (``--set egg_base.diameter=8``) printed "egg_apart: lifted 37 of 82 elements by up to
    6.6 mm, so that none starts deeper than 0.25 of a radius …: they fall" on every run: the node doing its work,
    with nothing to change. The numbers stay in its ``stats`` output."""
    from nodegraph.context import Context
    from nodes.placement import lift_apart

    said = []

    class Reporter:
        def info(self, message):
            said.append(message)

        warn = info

    eggs = ElementLibrary("ikura", (ellipsoid((5.0, 5.0, 5.0), 1),))
    placement = Placement(np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.2]]), np.tile([0.0, 0.0, 1.0], (2, 1)))
    ctx = Context.standalone(node_type="lift_apart")
    ctx.reporter = Reporter()
    out = lift_apart.run(ctx, placement=placement, libraries=[eggs], below=[], overlap=0.25)
    assert out["stats"].columns["lifted"][0] == 1 and said == [], said
