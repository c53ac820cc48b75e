"""``--draft``: a recipe's ``draft:`` block applied as overrides (``--set`` wins), located at its own lines;
its keys are checked whenever the recipe loads."""

from pathlib import Path

import numpy as np
import pytest

from nodegraph.cli import main
from nodegraph.errors import RecipeError
from nodegraph.recipe import load_recipe

from .test_validation import VALID

DRAFT = VALID.replace("nodes:\n", "draft:\n  pts.count: 4\n  shifted.dx: 0.5\nnodes:\n", 1)


def test_draft_applies_its_block_and_set_wins(registry, recipe_file):
    path = recipe_file(DRAFT)
    full = load_recipe(path, registry)
    assert full.nodes["pts"].params["count"] == 20 and full.draft == ("pts.count=4", "shifted.dx=0.5")
    draft = load_recipe(path, registry, draft=True)
    assert draft.nodes["pts"].params["count"] == 4 and draft.nodes["shifted"].params["dx"] == 0.5
    assert draft.overrides == ("pts.count=4", "shifted.dx=0.5")  # a worker reloading it gets the same recipe
    both = load_recipe(path, registry, ["pts.count=7"], draft=True)
    assert both.nodes["pts"].params["count"] == 7 and both.overrides[-1] == "pts.count=7"
    assert load_recipe(path, registry, list(draft.overrides)).digest() == draft.digest()


def test_a_bad_draft_key_is_reported_at_its_line_without_draft(registry, recipe_file):
    path = recipe_file(DRAFT.replace("shifted.dx", "shifted.dz").replace("pts.count", "ptz.count"))
    with pytest.raises(RecipeError) as info:
        load_recipe(path, registry)
    issues = {i.location.line: i for i in info.value.issues}
    assert set(issues) == {6, 7}
    assert "no node 'ptz'" in issues[6].message and issues[6].suggestion == "pts"
    assert "no parameter 'dz'" in issues[7].message and issues[7].suggestion == "dx"


def test_a_bad_draft_value_is_reported_at_its_line(registry, recipe_file):
    path = recipe_file(DRAFT.replace("pts.count: 4", "pts.count: -4"))
    load_recipe(path, registry)  # the value applies only in draft mode
    with pytest.raises(RecipeError) as info:
        load_recipe(path, registry, draft=True)
    (issue,) = info.value.issues
    assert (issue.location.file, issue.location.line) == (str(path), 6) and issue.param == "count"


def test_draft_without_a_block_says_what_to_add(registry, recipe_file, capsys):
    path = recipe_file(VALID)
    with pytest.raises(RecipeError, match="no draft: block"):
        load_recipe(path, registry, draft=True)
    from tests.engine.conftest import TOY

    assert main(["check", str(path), "--draft", "--plugin", str(TOY)]) == 2
    assert "draft: {" in capsys.readouterr().err


def test_check_reports_the_draft(recipe_file, capsys):
    from tests.engine.conftest import TOY

    assert main(["check", str(recipe_file(DRAFT)), "--plugin", str(TOY)]) == 0
    assert "draft: 2 settings" in capsys.readouterr().out


DRAFT_MIN_WIDTH = 640  # px: a draft's preview at least this wide (or the final's width, where that is less)
GRAPHS = sorted((Path(__file__).resolve().parents[2] / "graphs").glob("*.yaml"))


@pytest.mark.parametrize("path", GRAPHS, ids=lambda p: p.stem)
def test_every_recipe_has_a_draft_that_is_its_final_at_fewer_elements_and_samples(path):
    """Issue 47: 7 of the recipes had no draft, and drafts' previews were 160 × 90 to 480 × 270, some of another
    aspect than the final's (sushi, rice + chestnut: 16:9 drafts of 4:3 finals, so framed otherwise). Each recipe
    has a draft that loads; each image its draft renders keeps the final's camera, lens, framing and studio (every
    setting but the size and the samples), the final's aspect, and is at least 640 px wide (or the final's width);
    the draft changes no material and no light."""
    from nodegraph.registry import default_registry

    final = load_recipe(path, default_registry())
    draft = load_recipe(path, default_registry(), draft=True)
    assert final.draft, f"{path.name}: no draft: block"
    for node_id, entry in final.nodes.items():
        kind = entry.spec.type_name
        if kind == "preview":
            before, after = entry.params, draft.nodes[node_id].params
            look = {k: v for k, v in before.items() if k not in ("width", "height", "samples")}
            assert {k: after[k] for k in look} == look, node_id
            assert after["width"] >= min(DRAFT_MIN_WIDTH, before["width"]), node_id
            assert after["width"] * before["height"] == after["height"] * before["width"], node_id
            assert after["samples"] <= before["samples"], node_id
        if kind in ("cooked_rice", "material"):
            assert draft.nodes[node_id].params == entry.params, node_id
        if kind == "shade":
            lights = ("light_directions", "light_colors", "light_intensities", "presets", "scenery_color")
            assert {k: draft.nodes[node_id].params[k] for k in lights} == {k: entry.params[k] for k in lights}


def test_the_ikura_draft_is_the_final_at_fewer_elements():
    """Issue 47: the ikura draft was a 160 × 90 sparse scatter with the bowl floor showing. Now the final's
    camera, framing and materials, a preview large enough to judge a look (≥ 480 px wide, the final's aspect),
    and the same elements at the same spacing (fewer, in a smaller bowl whose regions follow it: not sparser)."""
    from pathlib import Path

    from nodegraph.registry import default_registry

    path = Path(__file__).resolve().parents[2] / "graphs" / "ikura_don.yaml"
    final = load_recipe(path, default_registry())
    draft = load_recipe(path, default_registry(), draft=True)
    look = {k: v for k, v in final.nodes["preview"].params.items() if k not in ("width", "height", "samples")}
    assert {k: draft.nodes["preview"].params[k] for k in look} == look  # camera, framing, lens, studio
    width, height = (draft.nodes["preview"].params[k] for k in ("width", "height"))
    final_width, final_height = (final.nodes["preview"].params[k] for k in ("width", "height"))
    assert width >= 480 and width * final_height == height * final_width  # the final's framing, smaller
    for node_id in ("cooked", "shade", "egg_base", "grain_base", "rice_place", "egg_place", "rice_refine"):
        assert draft.nodes[node_id].params == final.nodes[node_id].params, node_id  # materials, elements, spacing
    for entry in draft.nodes.values():  # the regions are derived from the bowl, so they follow it
        if entry.spec.type_name == "vessel_region":
            assert [w.node for w in entry.inputs["vessel"]] == ["bowl"]


def test_the_kakigori_draft_is_the_final_with_fewer_larger_flakes():
    """Issue 47: the kakigori draft shrank the cup to 3/8, so it did not frame as the final (the camera closer, the
    table's grain and the depth of field other than the final's). A draft is the final at fewer elements and
    samples: the cup, the syrup, the camera and the materials are the final's; every length of the flakes, their
    spacing and the cull's D scale by one factor, so fewer fill the same heap; the preview the final's aspect."""
    from pathlib import Path

    from nodegraph.registry import default_registry

    path = Path(__file__).resolve().parents[2] / "graphs" / "kakigori.yaml"
    final = load_recipe(path, default_registry())
    draft = load_recipe(path, default_registry(), draft=True)
    factor = draft.nodes["place"].params["r"] / final.nodes["place"].params["r"]
    assert factor > 1
    flakes = [n for n, e in final.nodes.items() if e.spec.type_name == "base_mesh"]
    lengths = {"place": ("r",), "refine": ("r",), "pile": ("threshold",)} | {n: ("size",) for n in flakes}
    for node_id, names in lengths.items():
        for name in names:
            assert draft.nodes[node_id].params[name] == pytest.approx(
                factor * np.asarray(final.nodes[node_id].params[name])
            ), (node_id, name)
        rest = {k: v for k, v in final.nodes[node_id].params.items() if k not in names}
        assert {k: draft.nodes[node_id].params[k] for k in rest} == rest, node_id
    for node_id in ("cup", "shade", "implicit", "crossed", "apart"):
        assert draft.nodes[node_id].params == final.nodes[node_id].params, node_id
    look = {k: v for k, v in final.nodes["preview"].params.items() if k not in ("width", "height", "samples")}
    assert {k: draft.nodes["preview"].params[k] for k in look} == look
    width, height = (draft.nodes["preview"].params[k] for k in ("width", "height"))
    assert (
        width >= 480
        and width * final.nodes["preview"].params["height"] == height * final.nodes["preview"].params["width"]
    )


def test_the_sushi_draft_slice_follows_its_smaller_block():
    """A new user's draft of the sushi showed a full-size salmon slice arching over a block 0.6 its size: the draft
    shrank the block, not the slice that dresses it. The slice keeps its overhang: its length and width over the
    block's are the final's, its thickness the final's."""
    from pathlib import Path

    from nodegraph.registry import default_registry

    path = Path(__file__).resolve().parents[2] / "graphs" / "sushi.yaml"
    final = load_recipe(path, default_registry())
    draft = load_recipe(path, default_registry(), draft=True)
    block = [np.asarray(r.nodes["nigiri"].params["extents"][:2], float) for r in (final, draft)]
    fish = [np.asarray(r.nodes["fish"].params["size"], float) for r in (final, draft)]
    assert fish[1][:2] / block[1] == pytest.approx(fish[0][:2] / block[0], rel=0.03)
    assert fish[1][2] == fish[0][2]
