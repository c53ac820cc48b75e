"""The onigiri recipe sets its pressed grains on the plate under gravity (issue 24): glued, it keeps its height
and rests on the plate (issue 26: the lowest grain within 0.5 mm of it), measured on the element meshes after the
run and on the exported .glb (after deform_contacts and shading: what a user opens)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from recipe_sizes import quick_sizes

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

REPO = Path(__file__).resolve().parents[2]


def mesh_extent(aggregate) -> tuple[float, float]:
    """Lowest and highest z of the element meshes."""
    z = np.concatenate([aggregate.element_mesh(i).vertices[:, 2] for i in range(len(aggregate.placement))])
    return float(z.min()), float(z.max())


def plate_gap(glb) -> float:
    """Lowest grain vertex above the plate's top under the onigiri (mm; < 0: sunk in), read from an exported .glb:
    nodes named ``<kind>/<number>`` are grains, ``plate`` the plate (shade's mesh names)."""
    import trimesh

    scene = trimesh.load(glb)
    world = {}
    for name in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[name]
        x, y_up, z = trimesh.transform_points(scene.geometry[geometry].vertices, transform).T
        world[name] = 1e3 * np.column_stack([x, -z, y_up])  # glTF's Y-up metres → our Z-up millimetres
    grains = [v for name, v in world.items() if "/" in name]
    assert grains and "plate" in world, sorted(world)[:5]
    centres = np.array([v.mean(axis=0) for v in grains])
    plate = world["plate"]
    reach = 0.5 * float(np.ptp(centres[:, :2], axis=0).min())  # the plate under the onigiri (its well), not the rim
    under = np.hypot(*(plate[:, :2] - centres[:, :2].mean(axis=0)).T) < reach
    return float(min(v[:, 2].min() for v in grains) - plate[under, 2].max())


def rested(tmp_path, *overrides, exported=False):
    recipe = load_recipe(
        REPO / "graphs" / "onigiri.yaml",
        default_registry(),
        quick_sizes()["onigiri"] + list(overrides) + (["export.formats=[glb]"] if exported else []),
    )
    outputs = ["press.aggregate", "rest.aggregate", "plate.mesh"] + (["export.files"] if exported else [])
    result = run_recipe(recipe, cache=Cache(tmp_path / "cache"), outputs=outputs, out_dir=tmp_path / "out")
    pressed, rest = mesh_extent(result.output("press.aggregate")), mesh_extent(result.output("rest.aggregate"))
    plate = result.output("plate.mesh").vertices
    grains = result.output("rest.aggregate").placement.positions
    reach = 0.5 * float(np.ptp(grains[:, :2], axis=0).min())  # the plate under the onigiri (its well), not the rim
    under = np.hypot(*(plate[:, :2] - grains[:, :2].mean(axis=0)).T) < reach
    plate_top = float(plate[under, 2].max())
    # height of the top above the plate, against the pressed onigiri's (a loose one also flings a few grains off
    # the plate at 30 substeps: the top, not the lowest grain, says how far it slumped)
    kept = (rest[1] - plate_top) / (pressed[1] - plate_top)
    if exported:
        return kept, rest[0] - plate_top, plate_gap(tmp_path / "out" / "onigiri.glb")
    return kept, rest[0] - plate_top


@pytest.fixture(scope="module")
def glued(tmp_path_factory):
    return rested(tmp_path_factory.mktemp("glued"), exported=True)


def test_the_glued_onigiri_keeps_its_height_on_its_plate(glued):
    kept, gap, _ = glued
    assert kept >= 0.95, kept
    assert abs(gap) <= 0.5, gap  # its lowest grain rests on the plate: neither floating nor sunk in


def test_the_exported_onigiri_rests_on_its_plate(glued):
    """Issue 26, on the exported meshes: the lowest grain in the .glb within 0.5 mm of the plate under it."""
    _, _, exported = glued
    assert abs(exported) <= 0.5, exported


def test_without_glue_the_same_onigiri_loses_its_pressed_shape(tmp_path, glued):
    """Glue is what holds the pressed shape: unglued, the grains give up the overlaps the press left, at the bounded
    speed of a handed-on state (``settings.HANDOFF_FRAMES``), and the onigiri loses its height: 0.94 of it (glued
    0.98). Placed at the fixed r 1.6 mm it kept 0.97 unglued (issue 46: whether the stuck contacts hold the press's
    overlaps depends on the placement)."""
    kept, _ = rested(tmp_path, "rest.glue=0")
    assert abs(glued[0] - 1.0) < 0.05 < abs(kept - 1.0), (glued[0], kept)
