"""Target shapes: closed, outward, the sizes asked for; boolean and mesh_file repair/refusal (SPEC §2 inputs)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from nodes.shapes import boolean, mesh_file, shape


@pytest.mark.parametrize("kind", ["bowl", "onigiri", "sphere", "box", "cylinder", "plate"])
def test_every_kind_is_a_closed_outward_solid(kind):
    out = shape.call(kind=kind, resolution=3)
    mesh = trimesh.Trimesh(out["mesh"].vertices, out["mesh"].faces, process=False)
    assert mesh.is_watertight and mesh.volume > 0
    assert (len(out["container"].vertices) > 0) == (kind == "bowl")


def test_onigiri_has_the_circumscribed_radius_asked_for():
    mesh = shape.call(kind="onigiri", size=20.0)["mesh"]
    radius = np.linalg.norm(mesh.vertices - mesh.vertices.mean(axis=0), axis=1).max()
    assert radius == pytest.approx(20.0, rel=0.02)
    assert np.ptp(mesh.vertices[:, 1]) == pytest.approx(0.9 * 20.0, rel=0.05)  # thickness share


def _widths(vertices, fractions=(0.25, 0.5, 0.75)):
    """Widths along x of the x–z silhouette at fractions of its height (the vertices within 1 % of each level)."""
    z = vertices[:, 2]
    levels = z.min() + np.asarray(fractions) * np.ptp(z)
    return np.array([np.ptp(vertices[np.abs(z - level) < 0.01 * np.ptp(z), 0]) for level in levels])


@pytest.mark.parametrize("roundness", [0.01, 0.35])
def test_onigiri_seen_from_the_front_is_a_rounded_triangle(roundness):
    """Issue 26: the front view is a triangle with straight sides, not a dome. A triangle's width falls linearly
    with height (at 25 / 50 / 75 % of it: ¾, ½, ¼ of its base); rounded corners widen the top a little. The old
    gauge interpolated the radius linearly in angle between the hull's vertices, which bowed each straight side
    out into an arc: at roundness 0.01 the widths were 82 / 94 / 82 mm (a disc), at 0.35 84 / 86 / 71."""
    mesh = shape.call(kind="onigiri", size=47.3, roundness=roundness, resolution=5)["mesh"]
    w25, w50, w75 = _widths(mesh.vertices)
    if roundness < 0.1:
        assert w50 / w25 == pytest.approx(2 / 3, abs=0.03) and w75 / w25 == pytest.approx(1 / 3, abs=0.03)
    assert w75 / w25 < 0.5 and w50 / w25 < 0.8
    extent = np.ptp(mesh.vertices, axis=0)
    assert extent[2] / extent[0] == pytest.approx(np.sqrt(3) / 2, abs=0.05)  # an equilateral triangle's height


def test_bowl_region_sits_in_the_cavity_with_a_mound():
    out = shape.call(kind="bowl", size=60.0, depth=45.0, fill=0.8, mound=15.0)
    region, container = out["mesh"], out["container"]
    assert region.vertices[:, 2].max() == pytest.approx(-45.0 + 0.8 * 45.0 + 15.0, abs=0.5)
    assert region.vertices[:, 2].min() == pytest.approx(-45.0, abs=0.5)
    from nodes.mesh_inside import inside_points

    inner = region.vertices[region.vertices[:, 2] < -10.0] * 0.98
    assert not inside_points(container.vertices, container.faces, inner).any()  # the region does not cut the wall
    assert inside_points(container.vertices, container.faces, inner * 1.1).any()  # …but lies against it


def test_the_bowl_stands_on_a_foot_ring():
    """The container's lowest vertices form a ring (the kōdai), FOOT_HEIGHT of the bowl's height tall, with the
    underside inside it raised: the bowl stands on the ring, not on a point, and keeps its height."""
    from nodes.shapes.solids import FOOT_HEIGHT

    container = shape.call(kind="bowl", size=68.5, depth=81.0, wall=4.0)["container"]
    v = container.vertices
    radius = np.hypot(v[:, 0], v[:, 1])
    bottom = v[:, 2].min()
    assert bottom == pytest.approx(-85.0) and v[:, 2].max() == pytest.approx(0.0)
    lowest = radius[v[:, 2] < bottom + 1e-6]
    assert lowest.min() > 20.0  # nothing of the underside's middle touches the table
    centre = v[radius < 1e-6, 2]
    assert centre.min() == pytest.approx(bottom + 2.0)  # the underside inside the ring: half the wall up
    outside = radius.max() * np.sqrt(1 - (1 - FOOT_HEIGHT) ** 2)  # the outer wall's radius at the ring's top
    assert lowest.max() == pytest.approx(outside, rel=0.02)


def test_boolean_difference_removes_the_intersection():
    a = shape.call(kind="sphere", size=10.0)["mesh"]
    b = shape.call(kind="box", extents=(10.0, 10.0, 10.0))["mesh"]
    diff = boolean.call(a=a, b=b, operation="difference")
    inter = boolean.call(a=a, b=b, operation="intersection")
    vol = lambda m: trimesh.Trimesh(m.vertices, m.faces).volume  # noqa: E731
    assert vol(diff) + vol(inter) == pytest.approx(vol(a), rel=1e-3)
    with pytest.raises(ValueError, match="empty"):
        boolean.call(a=inter, b=a, operation="difference")


def test_mesh_file_repairs_inverted_normals_and_refuses_holes(tmp_path):
    ball = trimesh.creation.icosphere(2)
    inverted = ball.copy()
    inverted.invert()
    inverted.export(tmp_path / "inverted.stl")
    fixed = mesh_file.call(path=str(tmp_path / "inverted.stl"), size=5.0)
    assert trimesh.Trimesh(fixed.vertices, fixed.faces).volume > 0
    with pytest.raises(ValueError, match="inwards"):
        mesh_file.call(path=str(tmp_path / "inverted.stl"), repair=False)
    open_mesh = trimesh.Trimesh(ball.vertices, ball.faces[ball.vertices[ball.faces].mean(axis=1)[:, 2] < 0.5])
    open_mesh.export(tmp_path / "open.stl")
    with pytest.raises(ValueError, match="holes"):
        mesh_file.call(path=str(tmp_path / "open.stl"))
    with pytest.raises(ValueError, match="no such"):
        mesh_file.call(path=str(tmp_path / "missing.stl"))


def test_a_bowl_too_small_for_its_mound_says_the_sizes_that_fit(capsys):
    """A smaller bowl set from the command line leaves the recipe's mound too high: the refusal says what would fit,
    a mound up to twice the rim radius or a rim for the mound (a new user read only 'given: 5.0')."""
    from pathlib import Path

    from nodegraph.cli import main

    recipe = Path(__file__).resolve().parents[2] / "graphs" / "rice_bowl.yaml"
    assert main(["check", str(recipe), "--set", "bowl.size=2"]) == 2
    err = capsys.readouterr().err
    assert "node 'bowl', mound: " in err and "allowed: mound ≤ 2 × size = 4 mm at size 2, or size ≥ 8 mm" in err
