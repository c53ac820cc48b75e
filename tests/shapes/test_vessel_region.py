"""Regions derived from their vessel (``vessel_region``) follow it; a bowl region stated apart that does not fit
its vessel is refused by validation (file:line, parameter) — issue 23."""

from pathlib import Path

import numpy as np
import pytest

from nodegraph.api import default_registry, load_recipe, parse_recipe, run_recipe
from nodegraph.errors import RecipeError
from nodes.shapes import shape, vessel_region

REPO = Path(__file__).resolve().parents[2]


def _bowl(size):
    return shape.call(kind="bowl", size=size, depth=35.0, wall=4.0, fill=0.8, mound=6.0, resolution=2)["vessel"]


@pytest.mark.parametrize("size", [42.0, 30.0])
def test_derived_regions_follow_the_vessel(size):
    vessel = _bowl(size)
    cavity = vessel_region.call(vessel=vessel, fill=1.0, mound=9.5, inset=2.5).vertices
    core = vessel_region.call(vessel=vessel, surface="outer", lower=5.0).vertices
    assert np.hypot(cavity[:, 0], cavity[:, 1]).max() == pytest.approx(size - 2.5, rel=1e-3)
    assert cavity[:, 2].min() == pytest.approx(-35.0, abs=1e-3) and cavity[:, 2].max() == pytest.approx(9.5, abs=1e-3)
    fill_radius = (size + 4.0) * np.sqrt(1.0 - (12.0 / 39.0) ** 2)  # the outer surface (+ wall) at z = −12
    assert np.hypot(core[:, 0], core[:, 1]).max() == pytest.approx(fill_radius, rel=1e-3)
    assert core[:, 2].max() == pytest.approx(-7.0 - 5.0 + 6.0, abs=1e-3)  # 5 mm under the fill plane, + the mound
    assert not vessel.outside(cavity, margin=1e-3).any()
    assert not vessel.outside(core, margin=4.0 + 1e-3).any()  # within the wall
    with pytest.raises(ValueError, match="fill plane"):
        vessel_region.call(vessel=vessel, lower=40.0)


def test_ikura_don_regions_follow_a_smaller_bowl(tmp_path):
    """``--set bowl.size=30`` (the issue's new-user try): every region the rice and the eggs are placed in lies in
    the 30 mm bowl (before, they came from three shapes sized for the 42 mm one)."""
    recipe = load_recipe(REPO / "graphs" / "ikura_don.yaml", default_registry(), ["bowl.size=30"])
    for node in ("rice_core", "egg_outer", "egg_floor"):
        assert recipe.nodes[node].spec.type_name == "vessel_region"
        assert [(w.node, w.port) for w in recipe.nodes[node].inputs["vessel"]] == [("bowl", "vessel")]
    # egg_place reads the egg layer as a closed solid: a cut whose slivers trimesh merged open was refused there
    outputs = ["rice_layer.mesh", "egg_layer.mesh", "rice_core.mesh", "bowl.vessel", "egg_place.placement"]
    result = run_recipe(recipe, outputs=outputs)
    assert len(result.output("egg_place.placement").positions) > 30  # 42 eggs in its middle heap (docs/sizes.md)
    vessel = result.output("bowl.vessel")
    assert vessel.radius == 30.0
    for region in ("rice_layer.mesh", "egg_layer.mesh", "rice_core.mesh"):
        vertices = result.output(region).vertices
        assert not vessel.outside(vertices, margin=vessel.wall + 1e-3).any(), region
    eggs = result.output("egg_layer.mesh").vertices
    params = recipe.nodes["egg_outer"].params
    inset = params["inset"] + params["inset_share"] * 30.0  # the heap keeps its share of the smaller bowl
    assert np.hypot(eggs[:, 0], eggs[:, 1]).max() == pytest.approx(30.0 - inset, rel=1e-3)  # in from the rim


CONTRADICTION = """\
effects: [gravity, collider]
outputs: [sim.aggregate]
nodes:
  bowl:
    type: shape
    params: {kind: bowl, size: 30.0, depth: 35.0, wall: 4.0, fill: 0.8, mound: 6.0}
  eggs_region:
    type: shape
    params: {kind: bowl, size: 39.5, depth: 35.0, fill: 1.0, mound: 9.5}
  egg:
    type: base_mesh
    params: {shape: ikura}
  ikura:
    type: element_library
    inputs: {meshes: egg.mesh}
    params: {kind: ikura}
  place:
    type: poisson_place
    inputs: {shape: eggs_region.mesh}
  mix:
    type: mix_ratio
    inputs: {placement: place.placement, libraries: ikura.library}
  sim:
    type: xpbd
    inputs: {aggregate: mix.aggregate, colliders: bowl.container}
"""


def test_a_region_that_does_not_fit_its_vessel_is_refused_at_its_line():
    with pytest.raises(RecipeError) as caught:
        parse_recipe(CONTRADICTION, default_registry(), file="don.yaml")
    (issue,) = caught.value.issues
    assert (issue.node, issue.param) == ("eggs_region", "size")
    assert str(issue.location) == "don.yaml:9:32"  # the region's size value
    assert "does not fit in the vessel 'bowl'" in issue.message and "vessel_region" in issue.message
    parse_recipe(CONTRADICTION.replace("size: 30.0", "size: 42.0"), default_registry())  # fits: valid
    with pytest.raises(RecipeError, match="--set:1: node 'eggs_region', size: the bowl region"):
        parse_recipe(
            CONTRADICTION.replace("size: 30.0", "size: 42.0"), default_registry(), overrides=["eggs_region.size=50"]
        )


# The main job's egg layer at full size (it starts above the settled rice and stays in the bowl) is checked in
# the suite's one full-size run of the main job: tests/shading/test_recipes.py
# (test_the_main_job_runs_at_full_size_and_its_eggs_start_above_the_settled_rice).
