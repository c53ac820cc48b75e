"""``nodegraph check`` refuses a shape kind that lacks what the recipe reads of it (issue 47, item 2c): said at
once, not by the simulation after the placement's minutes."""

from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe
from nodegraph.errors import RecipeError

GRAPHS = Path(__file__).resolve().parents[2] / "graphs"


@pytest.fixture(scope="module")
def registry():
    return default_registry()


# grains settled in a bowl's container, the simulation reading it directly (the rice bowl's recipe settles its top
# layer on a region derived from the bowl, which refuses a box first)
SETTLED = """
name: settled
nodes:
  bowl: {type: shape, params: {kind: bowl, size: 14.0, depth: 12.0, mound: 5.0}}
  grain: {type: base_mesh, params: {shape: rice}}
  rice: {type: element_library, inputs: {meshes: grain.mesh}}
  implicit: {type: medial_spheres, inputs: {library: rice.library}}
  place: {type: poisson_place, inputs: {shape: bowl.mesh}, params: {mode: volume, r: 1.6}}
  mix: {type: mix_ratio, inputs: {placement: place.placement, libraries: rice.library}}
  pile: {type: cull, inputs: {placement: mix.placement, libraries: implicit.library}}
  rice_sim: {type: xpbd, inputs: {aggregate: pile.aggregate, colliders: bowl.container}}
"""


def test_a_kind_without_a_container_is_refused_where_a_simulation_collides_with_it(registry, tmp_path):
    recipe = tmp_path / "settled.yaml"
    recipe.write_text(SETTLED)
    with pytest.raises(RecipeError) as info:
        load_recipe(recipe, registry, ["bowl.kind=box"])
    text = str(info.value)
    assert "--set:1: node 'bowl', kind: a shape of kind 'box' has no container" in text
    assert "'rice_sim' reads bowl.container as its colliders; allowed: bowl, block" in text


def test_a_region_derived_from_a_shape_that_is_not_a_bowl_is_refused(registry):
    with pytest.raises(RecipeError) as info:
        load_recipe(GRAPHS / "ikura_don.yaml", registry, ["bowl.kind=sphere"])
    assert "derives its region from bowl.vessel, the numbers of a bowl" in str(info.value)


def test_the_kinds_the_recipes_use_pass(registry):
    load_recipe(GRAPHS / "rice_bowl.yaml", registry)
    load_recipe(GRAPHS / "sushi.yaml", registry)
