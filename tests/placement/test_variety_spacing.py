"""Every recipe that places rice in a volume places it at an r that follows the variety (issue 47): at a fixed
r = 1.6 mm indica's grains, 1.8× japonica's length, were placed as many as japonica's and burst out of the rice
bowl's heap. The estimate ``nodegraph check`` prints, nothing run."""

from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe

GRAPHS = Path(__file__).resolve().parents[2] / "graphs"
RICE_RECIPES = sorted(
    path.relative_to(GRAPHS).as_posix()
    for path in [*GRAPHS.glob("*.yaml"), *GRAPHS.glob("sweeps/*.yaml")]
    if "type: rice_variety" in path.read_text() and "mode: volume" in path.read_text()
)


def filled(recipe: str, variety: str) -> dict[str, float]:
    """The grain volume (mm³) each volume placement of ``recipe`` puts in its shape at ``variety``: the elements it
    makes × the rice grains' mean volume, estimated."""
    loaded = load_recipe(GRAPHS / recipe, default_registry(), [f"variety.variety={variety}"], work=True, yes=True)
    costs, nodes = loaded.cost.costs, loaded.nodes
    places = [
        n
        for n, e in nodes.items()
        if e.spec.type_name == "poisson_place"
        and e.params["mode"] == "volume"
        and {w.node for w in e.inputs.get("elements", [])} <= {"rice"}  # the eggs' placement is not the rice's
    ]
    return {n: costs[n].made * costs["rice"].volume for n in places}  # each recipe's grain library is 'rice'


def test_the_recipes_that_place_rice_are_found():
    assert {"rice_bowl.yaml", "ikura_don.yaml", "onigiri.yaml", "sushi.yaml"} <= set(RICE_RECIPES)


@pytest.mark.parametrize("variety", ["indica", "aromatic"])
@pytest.mark.parametrize("recipe", RICE_RECIPES)
def test_every_variety_fills_the_same_share(recipe, variety):
    # indica's grain holds 1.78× japonica's volume where P is the recipe's (57.6 / 32.4 mm³ in the rice bowl),
    # 0.92× where the variety's P is wired; aromatic's 0.7×: as many grains at one r filled 30–78 % more or less
    japonica, other = filled(recipe, "japonica"), filled(recipe, variety)
    assert japonica and japonica.keys() == other.keys()
    for node, volume in japonica.items():
        assert other[node] == pytest.approx(volume, rel=0.1), node
