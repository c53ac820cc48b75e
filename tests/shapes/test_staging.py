"""Staging of the onigiri (issue 26): a real plate under it, not a box, and a nori band round its bottom —
on the recipe's own shapes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from nodes.mesh_inside import inside_points
from nodes.shapes import nori, shape
from nodes.shapes.solids import first_hits

ROOT = Path(__file__).resolve().parents[2]


def _recipe_shapes(draft: bool):
    """The onigiri recipe's mould, plate and nori band (the scenery nodes alone: no simulation)."""
    from nodegraph.api import default_registry, load_recipe

    recipe = load_recipe(ROOT / "graphs" / "onigiri.yaml", default_registry(), [], draft=draft)
    mould = shape.call(**recipe.nodes["onigiri"].params)["mesh"]
    plate = shape.call(**recipe.nodes["plate"].params)["mesh"]
    band = nori.call(shape=mould, **recipe.nodes["nori"].params)
    return mould, plate, band


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
    assert distance.max() < 0.4 + 0.3
    lo = mould.vertices.min(axis=0)
    assert band.vertices[:, 2].min() < lo[2]
    assert band.vertices[:, 2].max() == pytest.approx(lo[2] + 28.0, abs=0.5)
    y = band.vertices[band.vertices[:, 2] > lo[2] + 20.0, 1]
    assert y.min() < 0 < y.max()  # up the front and the back face
    assert np.ptp(band.vertices[:, 0]) == pytest.approx(34.0, abs=2 * 0.4)  # ± the gap along slanted normals


def test_a_band_too_wide_for_the_shape_is_refused():
    mould = shape.call(kind="onigiri", size=20.0)["mesh"]
    with pytest.raises(ValueError, match="width"):
        nori.call(shape=mould, width=60.0, height=10.0)
