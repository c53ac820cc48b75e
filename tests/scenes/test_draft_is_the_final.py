"""A draft is the final at fewer elements and samples (issue 47): the rice bowl's draft was a 39 mm chawan of 118
grains, each drawn 3× as large against its bowl, the chopsticks out of the frame; the ikura don's a 92 mm donburi
whose eggs looked 1.5× as large. The recipes as loaded, nothing run."""

from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe

GRAPHS = Path(__file__).resolve().parents[2] / "graphs"
# what a draft may change in what the picture shows: the preview's size and samples (at the final's aspect), the
# bowl's segments (48, not 96)
PREVIEW_SIZE = {"width", "height", "samples"}


@pytest.mark.parametrize(
    "name, scenery",
    [("rice_bowl", ("bowl", "chopsticks")), ("ikura_don", ("bowl", "chopsticks", "egg_base", "egg_outer"))],
)
def test_the_draft_keeps_the_finals_bowl_camera_and_elements(name, scenery):
    registry = default_registry()
    full = load_recipe(GRAPHS / f"{name}.yaml", registry, work=True, yes=True)
    draft = load_recipe(GRAPHS / f"{name}.yaml", registry, draft=True, work=True, yes=True)
    for node in scenery:
        given, drafted = full.nodes[node].params, draft.nodes[node].params
        assert {k: v for k, v in drafted.items() if k != "resolution"} == {
            k: v for k, v in given.items() if k != "resolution"
        }, node
    camera, drafted = full.nodes["preview"].params, draft.nodes["preview"].params
    assert {k: v for k, v in drafted.items() if k not in PREVIEW_SIZE} == {
        k: v for k, v in camera.items() if k not in PREVIEW_SIZE
    }
    assert drafted["width"] * camera["height"] == drafted["height"] * camera["width"]
    assert draft.cost.elements < 0.75 * full.cost.elements and drafted["samples"] < camera["samples"]
