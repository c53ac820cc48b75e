"""Staging of the onigiri (issue 26): a real plate under it, not a box, and a nori band round its bottom —
on the recipe's own shapes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from nodes.mesh_inside import inside_points
from nodes.shapes import nori, plate, shape
from nodes.shapes.nori import band_size
from nodes.shapes.solids import first_hits

ROOT = Path(__file__).resolve().parents[2]


def _recipe_shapes(draft: bool):
    """The onigiri recipe's mould, plate and nori band (the scenery nodes alone: no simulation)."""
    from nodegraph.api import default_registry, load_recipe

    recipe = load_recipe(ROOT / "graphs" / "onigiri.yaml", default_registry(), [], draft=draft)
    mould = shape.call(**recipe.nodes["onigiri"].params)["mesh"]
    dish = plate.call(shape=mould, **recipe.nodes["plate"].params)
    band = nori.call(shape=mould, **recipe.nodes["nori"].params)
    return mould, dish, band


@pytest.mark.parametrize("draft", [False, True])
def test_the_onigiri_rests_in_a_plate_with_a_rim(draft):
    """The plate is closed; its flat well lies under the onigiri's footprint within 0.5 mm of its lowest point
    (0 to 0.5 mm below), and its rim rises above the well around it: a dish, not a slab."""
    mould, plate, _ = _recipe_shapes(draft)
    solid = trimesh.Trimesh(plate.vertices, plate.faces)
    assert solid.is_watertight and solid.volume > 0
    bottom = mould.vertices[:, 2].min()
    footprint = mould.vertices[mould.vertices[:, 2] < bottom + 0.5]
    origins = np.column_stack([footprint[:, :2], np.full(len(footprint), bottom + 1.0)])
    depth, _ = first_hits(origins, np.tile([0.0, 0.0, -1.0], (len(footprint), 1)), plate.vertices[plate.faces])
    assert np.isfinite(depth).all()  # the plate is under every point the onigiri stands on
    top = bottom + 1.0 - depth
    assert (bottom - top >= 0).all() and (bottom - top <= 0.5 + 1e-9).all()
    radius = np.hypot(plate.vertices[:, 0], plate.vertices[:, 1])
    rim = plate.vertices[radius > 0.95 * radius.max(), 2].max()
    assert rim - top.max() > 0.05 * radius.max()  # the rim stands above the well


def test_the_nori_band_wraps_the_onigiris_bottom():
    """The band lies just outside the mould (at its gap), is folded under it (its lowest point under the
    mould's) and reaches its height up both faces, across its width."""
    mould, _, band = _recipe_shapes(False)
    assert band.name == "nori"
    assert not inside_points(mould.vertices, mould.faces, band.vertices).any()
    surface = trimesh.sample.sample_surface_even(trimesh.Trimesh(mould.vertices, mould.faces), 100_000, seed=0)[0]
    distance = cKDTree(surface).query(band.vertices)[0]  # ≥ the distance to the surface, within the samples' spacing
    assert distance.max() < 0.4 + 0.2 + 0.06 + 0.3  # the gap, the crinkles and the ribs over it
    lo = mould.vertices.min(axis=0)
    assert band.vertices[:, 2].min() < lo[2]
    assert band.vertices[:, 2].max() == pytest.approx(lo[2] + 0.6 * 80.3, abs=0.5)
    y = band.vertices[band.vertices[:, 2] > lo[2] + 40.0, 1]
    assert y.min() < 0 < y.max()  # up the front and the back face
    assert np.ptp(band.vertices[:, 0]) == pytest.approx(42.0, abs=2 * 0.4)  # a five-cut strip, 21 cm / 5


def test_a_band_too_wide_for_the_shape_is_refused():
    mould = shape.call(kind="onigiri", size=20.0)["mesh"]
    with pytest.raises(ValueError, match="width"):
        nori.call(shape=mould, width=1.0, height=0.5)


def _bulging_grains(mould, bulge: float):
    """Balls of 2.5 mm radius ≈ 3 mm apart round the mould's lower half, their outer sides ``bulge`` mm outside
    its surface: rice that slumped out of its mould."""
    from nodegraph.values import Mesh
    from nodes.values import Aggregate, ElementLibrary, Placement

    ball = trimesh.creation.icosphere(subdivisions=2, radius=2.5)
    solid = trimesh.Trimesh(mould.vertices, mould.faces)
    points, face = trimesh.sample.sample_surface_even(solid, 1500, seed=1)
    lo = mould.vertices[:, 2].min()
    low = points[:, 2] < lo + 30.0
    centres = points[low] + (bulge - 2.5) * solid.face_normals[face[low]]
    placement = Placement(centres, np.tile([0.0, 0.0, 1.0], (len(centres), 1)))
    library = ElementLibrary("ball", (Mesh(ball.vertices, ball.faces, name="ball"),))
    return Aggregate(placement, (library,))


def _outside_the_sheet(band, grains, mould, height: float) -> np.ndarray:
    """How far (mm) each grain vertex in the band's strip lies beyond the sheet, along the band's ray through it
    (from the point ``height`` over the mould's lowest point, in the y–z plane); ≤ 0 where the sheet covers it.
    Vertices under the mould's lowest point are left out: there the sheet stays on the plate."""
    lo, hi = mould.vertices.min(axis=0), mould.vertices.max(axis=0)
    centre = np.array([0.5 * (lo[1] + hi[1]), lo[2] + height])
    points = np.concatenate([grains.element_mesh(i).vertices for i in range(len(grains.placement))])
    x0, x1 = band.vertices[:, 0].min() + 1.0, band.vertices[:, 0].max() - 1.0
    points = points[
        (points[:, 0] > x0) & (points[:, 0] < x1) & (points[:, 2] < centre[1] - 3.0) & (points[:, 2] > lo[2])
    ]

    def polar(p):
        rel = p[:, 1:] - centre
        return np.arctan2(rel[:, 1], rel[:, 0]), np.hypot(rel[:, 0], rel[:, 1])

    band_angle, band_radius = polar(band.vertices)
    angle, radius = polar(points)
    nearest = cKDTree(np.column_stack([band.vertices[:, 0], 30.0 * band_angle])).query(
        np.column_stack([points[:, 0], 30.0 * angle])
    )[1]
    return radius - band_radius[nearest], nearest


def test_the_nori_lies_on_the_rice_that_slumped_out_of_its_mould():
    """Given the grains, the band covers every grain in its strip (the mould's band leaves grains 1 mm out of it
    through the sheet) and rests on them: along the median ray, within the gap and a millimetre of the
    farthest grain under it."""
    from nodegraph.api import default_registry, load_recipe

    recipe = load_recipe(ROOT / "graphs" / "onigiri.yaml", default_registry(), [])
    mould = shape.call(**recipe.nodes["onigiri"].params)["mesh"]
    grains = _bulging_grains(mould, bulge=1.0)
    params = {**recipe.nodes["nori"].params, "crinkle": 0.0, "thickness": 0.0, "reach": 0.5}  # the drape alone
    gap = params["gap"]
    assert (params["width"], params["height"], gap) == (0.472, 0.6, 0.25)
    height = band_size(mould, params["width"], params["height"])[1]
    assert height == pytest.approx(0.6 * 80.3, abs=0.5)
    on_mould = nori.call(shape=mould, **params)
    assert _outside_the_sheet(on_mould, grains, mould, height)[0].max() > 0.4  # the mould's sheet: grains through it
    draped = nori.call(shape=mould, aggregate=grains, **params)
    beyond, ray = _outside_the_sheet(draped, grains, mould, height)
    assert beyond.max() <= -(gap - 0.15)  # under the sheet by its gap, less the slack of its nearest vertex
    closest = np.full(len(draped.vertices), -np.inf)  # per sheet vertex: its nearest grain's distance under it
    np.maximum.at(closest, ray, beyond)
    assert np.median(closest[np.isfinite(closest)]) > -(gap + 1.0)  # it rests on the grains' tops


def test_the_recipes_nori_is_ribbed_outwards_only():
    """Issue 26: the band is a sheet with the fine ribs of the mat it dried on — ridges across it every
    ``rib_period`` mm of its length, raised outwards up to ``ribs`` mm, never inwards (it still covers what it
    covered), and none under the shape (the sheet there stays above the plate)."""
    from nodegraph.api import default_registry, load_recipe

    recipe = load_recipe(ROOT / "graphs" / "onigiri.yaml", default_registry(), [])
    mould = shape.call(**recipe.nodes["onigiri"].params)["mesh"]
    params = recipe.nodes["nori"].params
    ribs, period = params["ribs"], params["rib_period"]
    assert ribs > 0
    params = {**params, "crinkle": 0.0, "thickness": 0.0}  # the ribs alone, on the open sheet
    smooth = nori.call(shape=mould, **{**params, "ribs": 0.0})
    ribbed = nori.call(shape=mould, **params)
    lo, hi = mould.vertices.min(axis=0), mould.vertices.max(axis=0)
    centre = np.array([0.5 * (lo[1] + hi[1]), lo[2] + band_size(mould, params["width"], params["height"])[1]])
    lift = np.hypot(*(ribbed.vertices[:, 1:] - centre).T) - np.hypot(*(smooth.vertices[:, 1:] - centre).T)
    assert lift.min() >= -1e-9 and lift.max() <= ribs + 1e-9
    assert ribbed.vertices[:, 2].min() >= lo[2] - params["gap"] - 1e-9  # above the plate (0.44 mm under lo)
    column = lift.reshape(params["columns"] + 1, params["rows"] + 1)[params["columns"] // 2]
    points = ribbed.vertices.reshape(params["columns"] + 1, params["rows"] + 1, 3)[params["columns"] // 2]
    front = points[:, 2] > lo[2] + 5.0  # up the faces, clear of the bend under the shape
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    length = steps[front[1:] & front[:-1]].sum()  # both faces' length, not the bend under the shape between them
    crests = np.flatnonzero((column[1:-1] > column[:-2]) & (column[1:-1] >= column[2:]) & front[1:-1])
    assert len(crests) == pytest.approx(length / period, rel=0.15)


def test_the_recipes_nori_is_a_thin_crinkled_sheet():
    """Issue 48: the band read as a flat plastic decal. It is a closed thin solid ``thickness`` thick (its cut edges
    show; its inner face stays outside the mould), its outer face crinkled outwards only, by up to ``crinkle``
    over the smooth sheet, with relief on the scale of a crinkle (not one bump), the same for the same seed."""
    from nodegraph.api import default_registry, load_recipe

    recipe = load_recipe(ROOT / "graphs" / "onigiri.yaml", default_registry(), [])
    mould = shape.call(**recipe.nodes["onigiri"].params)["mesh"]
    params = {**recipe.nodes["nori"].params, "ribs": 0.0, "columns": 12, "rows": 160}  # coarser: a fast test
    thickness, crinkle = params["thickness"], params["crinkle"]
    assert 0.05 <= thickness <= 0.3 and crinkle > 0
    sheet = nori.call(shape=mould, **params)
    solid = trimesh.Trimesh(sheet.vertices, sheet.faces, process=False)
    assert solid.is_watertight and solid.is_winding_consistent and solid.volume > 0
    assert solid.volume == pytest.approx(0.5 * solid.area * thickness, rel=0.35)  # the rays meet the faces aslant
    assert not inside_points(mould.vertices, mould.faces, sheet.vertices).any()
    count = (params["columns"] + 1) * (params["rows"] + 1)
    flat = nori.call(shape=mould, **{**params, "crinkle": 0.0, "thickness": 0.0})
    lo, hi = mould.vertices.min(axis=0), mould.vertices.max(axis=0)
    centre = np.array([0.5 * (lo[1] + hi[1]), lo[2] + band_size(mould, params["width"], params["height"])[1]])
    radius = lambda v: np.hypot(*(v[:, 1:] - centre).T)  # noqa: E731 - along the band's rays
    lift = radius(sheet.vertices[:count]) - radius(flat.vertices)
    up = flat.vertices[:, 2] > lo[2] + 5.0  # up the faces (under the shape the plate bounds it)
    assert lift.min() >= -1e-9 and lift.max() <= crinkle + 1e-9 and np.ptp(lift[up]) > 0.8 * crinkle
    depth = radius(sheet.vertices[:count]) - radius(sheet.vertices[count:])
    assert depth[up] == pytest.approx(thickness, abs=1e-3)  # the gap is along the face's normal, not the ray
    again = nori.call(shape=mould, **params)
    assert np.array_equal(again.vertices, sheet.vertices)


def test_the_nori_is_black_green_and_dry():
    """Issue 26: the band read as a flat black rectangle (linear (0.010, 0.018, 0.008), L* 13); issue 48: with a
    satin face and a white-ish sheen it read as grey rubber. Nori is black-green (L* 15–20 as an albedo: a
    colorimeter's 29 for a test sheet, specular included), dry: a broad specular lobe, no clear coat."""
    from nodes.shading.materials import nori_material

    material = nori_material()
    r, g, b = material.base_color
    lightness = 116.0 * (0.2126 * r + 0.7152 * g + 0.0722 * b) ** (1.0 / 3.0) - 16.0
    assert 15.0 <= lightness <= 20.0 and g > r and g > b
    assert 0.5 <= material.roughness <= 0.7 and material.clearcoat == 0.0 and material.sheen <= 0.3
