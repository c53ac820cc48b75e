"""Issue 17's scenes run at reduced sizes through ``--set`` overrides: each recipe's element count and
the mesh-level quality its ``measure`` node reports. The bounds are what the short method reaches today
(see the benchmark, ``benchmarks/bench_scenes.py``); issue 17's target (p95 ≤ 3 %, max ≤ 10 % of the
element length) is asserted for the rice scenes, which meet it."""

from __future__ import annotations

from pathlib import Path

import pytest
from recipe_sizes import quick_sizes

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

REPO = Path(__file__).resolve().parents[2]


QUICK = quick_sizes()


_ROWS: dict[str, dict[str, float]] = {}


def _quick_row(recipe_name: str, tmp_path_factory) -> dict[str, float]:
    """The measure row of a recipe at its reduced size, run once per session."""
    if recipe_name not in _ROWS:
        _ROWS[recipe_name] = _measure(recipe_name, tmp_path_factory.mktemp(recipe_name))
    return _ROWS[recipe_name]


def _measure(recipe_name: str, tmp_path, extra=()) -> dict[str, float]:
    recipe = load_recipe(REPO / "graphs" / f"{recipe_name}.yaml", default_registry(), QUICK[recipe_name] + list(extra))
    result = run_recipe(recipe, cache=Cache(tmp_path / "cache"), out_dir=tmp_path / "out")
    assert "preview.png" in {p.name for p in result.files}
    return {k: float(v[0]) for k, v in result.output("measure.table").columns.items()}


# Per recipe at its reduced size: (fewest, most) elements and the most overlap (p95, max, in element lengths)
# measured today with some room, after the covering clusters and flatten_contacts (issue 17). The rice scenes are
# held to issue 17's target after relaxation, p95 ≤ 3 %, max ≤ 10 % of the element length (without
# flatten_contacts the reduced bowl, then 118 grains before the inset, measured p95 0.134, max 0.205).
EXPECTED = {
    "rice_bowl": ((90, 150), 0.03, 0.10),  # 118 grains (a 39 mm chawan, its top layer on a core): p95 0, max 0.009
    "ikura_don": ((280, 420), 0.03, 0.10),  # 386 elements (the donburi's draft; 347 in the 84 mm bowl): max 0.016
    "onigiri": ((45, 75), 0.03, 0.10),  # 53 grains (a real onigiri's shape, 14.4 mm): p95 0, max 0.016
    "sushi": ((65, 110), 0.03, 0.12),  # 87 grains: p95 0.019, max 0.097
    # 1,406 flakes (the draft: the final's cup, each flake twice the final's 2.25–2.7 × 1.5–1.65 × 0.3 mm):
    # p95 0.0010, max 0.0034
    "kakigori": ((1100, 1700), 0.003, 0.01),
    # 294 elements: p95 0, max 0 with deform_contacts (issue 25); p95 0.077, max 0.096 without it (S: no physics).
    # With the onigiri's straight sides and the cull's priority for the chestnut pieces: 203; max 0.026 while a
    # grain's tip poking into a coarse piece's face (no piece vertex inside the grain) was dented only its half
    # (deform_contacts v4), max 0 with v5. 178 with knife-cut quarters, each a larger share of the small ball
    "rice_chestnut": ((150, 340), 0.003, 0.01),
}
SLOW: set[str] = set()  # each runs in 2–7 s on a calm machine (rice_chestnut, the slowest: 18 s at load 10)


@pytest.mark.parametrize(
    "recipe_name",
    [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in sorted(EXPECTED)],
)
def test_scene_at_reduced_size_counts_and_quality(recipe_name, tmp_path_factory):
    row = _quick_row(recipe_name, tmp_path_factory)
    (low, high), p95, deepest = EXPECTED[recipe_name]
    assert low <= row["elements"] <= high
    assert row["overlap_p95"] <= p95 and row["overlap_max"] <= deepest
    assert row["contacts_per_element"] > 0.5 and 0.05 < row["packing_fraction"] < 1.0
    assert row["outside_vessel"] == 0  # the bowl scenes give measure their vessel (issue 23)


@pytest.mark.slow
def test_sushi_full_method_runs(tmp_path):
    row = _measure("sushi", tmp_path, ["press.mode=full", "press.frames=30"])
    assert 65 <= row["elements"] <= 110


def test_rice_chestnut_keeps_its_chestnut_pieces(tmp_path):
    """Issue 26: the chestnut pieces must show, embedded in the rice. At S's refine range (±0.1 b) every one of the
    38 placed was the deepest of its pairs and the cull removed all of them; a range of ±2 b kept 30, but about half
    had stepped out over the rice, standing out of the onigiri by up to 1.4× their size. Now the cull's priority
    removes the grains in a piece instead, and the refine's shape bound (``refine.protrusion``: 0.5 for the pieces)
    keeps each within half its size of the surface, where a face shows among the grains. Full size up to the cull
    (≈ 8 s)."""
    import igl
    import numpy as np

    recipe = load_recipe(REPO / "graphs" / "rice_chestnut.yaml", default_registry(), [])
    outputs = ["refine.placement", "pile.placement", "onigiri.mesh", "chestnut.library"]
    result = run_recipe(recipe, outputs=outputs, cache=Cache(tmp_path / "cache"))
    placed, kept = result.output("refine.placement"), result.output("pile.placement")
    solid, library = result.output("onigiri.mesh"), result.output("chestnut.library")
    chestnut = kept.kind_names.index("chestnut")
    pieces = np.flatnonzero(kept.kinds == chestnut)
    # 32 with G's isotropic grains (the placement follows the grains), 38 on the round onigiri before shape v5's
    # straight sides
    assert int((placed.kinds == chestnut).sum()) == 30
    assert len(pieces) >= 24  # 27 kept (30 of 38 on the round onigiri)
    vertices, faces = np.asarray(solid.vertices, float), np.asarray(solid.faces, np.int64)
    sign = igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL
    normals = igl.signed_distance(kept.positions[pieces], vertices, faces, sign_type=sign)[3]
    share = []
    for i, normal in zip(pieces, normals / np.linalg.norm(normals, axis=1, keepdims=True)):
        mesh = library.meshes[kept.variants[i] % len(library)]
        world = kept.positions[i] + np.asarray(mesh.vertices) @ kept.rotations[i].T
        height = world @ normal
        reach = igl.signed_distance(world, vertices, faces, sign_type=sign)[0].max()
        share.append(reach / (height.max() - height.min()))
    share = np.array(share)
    assert share.max() <= 0.5 + 0.02  # was 1.40: 17 of 30 wholly outside the onigiri
    assert (share > 0.0).all()  # every one shows a face at the surface (not stepped under the rice)


@pytest.mark.parametrize("recipe_name", ["sushi", "rice_chestnut"])
def test_the_dish_rests_on_its_plate(recipe_name, tmp_path):
    """Issue 48: a dish floating on the backdrop reads as a packshot, not food. Each stands on a plate sized by it:
    no element below the plate's well (nigiri: a grain placed across its mould's floor stayed there, 4 mm through
    the plate), and the lowest within 1 mm of it (resting on it, not hovering). At the reduced size."""
    import numpy as np

    recipe = load_recipe(REPO / "graphs" / f"{recipe_name}.yaml", default_registry(), QUICK[recipe_name])
    result = run_recipe(recipe, outputs=["contact.aggregate", "plate.mesh"], cache=Cache(tmp_path / "cache"))
    aggregate, plate = result.output("contact.aggregate"), result.output("plate.mesh")
    rim = np.hypot(*(plate.vertices[:, :2] - plate.vertices[:, :2].mean(axis=0)).T)
    well = plate.vertices[rim < 0.3 * rim.max(), 2].max()
    lowest = min(float(aggregate.element_mesh(i).vertices[:, 2].min()) for i in range(len(aggregate.placement)))
    assert well <= lowest < well + 1.0
