"""Every recipe problem is reported before anything runs, with file:line:column, node, parameter."""

import pytest

from nodegraph.errors import RecipeError
from nodegraph.params import Param
from nodegraph.recipe import load_recipe, parse_recipe

VALID = """\
name: toy
seed: 3
effects: [gravity]
outputs: [merge.spheres]
nodes:
  pts:
    type: toy_points
    params: {count: 20, scale: 2.0}
  shifted:
    type: toy_shift
    inputs: {spheres: pts.spheres}
    params:
      dx: 1.5
  phys:
    type: toy_physics
    inputs: {spheres: shifted.spheres}
  merge:
    type: toy_merge
    inputs: {parts: [pts.spheres, phys.spheres]}
"""


def issues_of(text, registry, overrides=()):
    with pytest.raises(RecipeError) as info:
        parse_recipe(text, registry, file="r.yaml", overrides=list(overrides))
    return info.value.issues


def test_valid_recipe_loads(registry):
    recipe = parse_recipe(VALID, registry, file="r.yaml")
    assert set(recipe.nodes) == {"pts", "shifted", "phys", "merge"}
    assert recipe.nodes["shifted"].params == {"dx": 1.5}
    assert recipe.nodes["pts"].params == {"count": 20, "scale": 2.0, "mode": "cube"}
    assert recipe.order() == ["pts", "shifted", "phys", "merge"]


def test_unknown_top_level_key_suggests_nearest(registry):
    (issue,) = issues_of(VALID.replace("effects:", "efects:"), registry)
    assert (issue.location.line, issue.location.column) == (3, 1)
    assert issue.suggestion == "effects"
    assert "r.yaml:3:1" in str(issue)


def test_unknown_node_type_suggests(registry):
    (issue,) = issues_of(VALID.replace("type: toy_shift", "type: toy_shfit"), registry)
    assert issue.location.line == 10 and issue.node == "shifted"
    assert issue.suggestion == "toy_shift"


def test_unknown_parameter_suggests(registry):
    (issue,) = issues_of(VALID.replace("dx: 1.5", "dz: 1.5"), registry)
    assert issue.location.line == 13 and issue.location.column == 7
    assert issue.suggestion == "dx" and issue.node == "shifted"


def test_out_of_range_names_range_and_units(registry):
    (issue,) = issues_of(VALID.replace("dx: 1.5", "dx: 15"), registry)
    assert issue.location.line == 13 and issue.param == "dx" and issue.given == 15
    assert "-10.0 ≤ value ≤ 10.0" in issue.allowed and "mm" in issue.allowed


def test_wrong_type_and_bool_for_number(registry):
    issues = issues_of(VALID.replace("count: 20", "count: many").replace("dx: 1.5", "dx: true"), registry)
    by_param = {i.param: i for i in issues}
    assert by_param["count"].location.line == 8 and "int" in by_param["count"].allowed
    assert by_param["dx"].location.line == 13 and "boolean" in by_param["dx"].message


def test_choice_not_allowed(registry):
    (issue,) = issues_of(VALID.replace("scale: 2.0}", "scale: 2.0, mode: cone}"), registry)
    assert issue.param == "mode" and "'cube'" in issue.allowed and issue.location.line == 8


def test_missing_required_input(registry):
    text = VALID.replace("    inputs: {spheres: shifted.spheres}\n", "")
    (issue,) = issues_of(text, registry)
    assert issue.node == "phys" and "missing required input 'spheres'" in issue.message
    assert issue.location.line == 14


def test_unknown_wire_source_node_and_port(registry):
    issues = issues_of(
        VALID.replace("{spheres: pts.spheres}", "{spheres: pst.spheres}").replace("phys.spheres]", "phys.sphers]"),
        registry,
    )
    messages = sorted((i.location.line, i.suggestion) for i in issues)
    assert messages == [(11, "pts"), (19, "spheres")]


def test_type_mismatch_at_load_time(registry):
    text = VALID + "  mesh:\n    type: toy_measure\n    inputs: {mesh: pts.spheres}\n"
    (issue,) = issues_of(text, registry)
    assert "type mismatch" in issue.message and "SphereSet" in issue.message and "Mesh" in issue.message
    assert issue.location.line == 22


def test_cycle_detected(registry):
    text = VALID.replace("{spheres: pts.spheres}", "{spheres: phys.spheres}")
    issues = issues_of(text, registry)
    assert any("cycle" in i.message and "shifted" in i.message and "phys" in i.message for i in issues)


def test_unknown_effect_and_unimplemented_effect(registry):
    issues = issues_of(VALID.replace("[gravity]", "[gravty, tearing]"), registry)
    assert issues[0].suggestion == "gravity" and issues[0].location.line == 3
    # tearing is unknown to the toy registry as well
    assert "unknown effect 'tearing'" in issues[1].message
    text = VALID.replace("type: toy_physics", "type: toy_shift")  # gravity asked for, no node implements it
    (issue,) = issues_of(text, registry)
    assert "no node in this recipe implements it" in issue.message and "toy_physics" in issue.allowed


def test_duplicate_key_reported(registry):
    text = VALID.replace(
        "    params: {count: 20, scale: 2.0}\n", "    params: {count: 20, scale: 2.0}\n    type: toy_points\n"
    )
    (issue,) = issues_of(text, registry)
    assert "duplicate key 'type'" in issue.message and issue.location.line == 9


def test_yaml_syntax_error_has_line():
    with pytest.raises(RecipeError) as info:
        parse_recipe("nodes:\n  a: [1, 2\n", None, file="bad.yaml")
    (issue,) = info.value.issues
    assert issue.location.file == "bad.yaml" and issue.location.line >= 2 and "syntax" in issue.message


def test_all_problems_reported_at_once(registry):
    text = (
        VALID.replace("dx: 1.5", "dx: 99").replace("type: toy_merge", "type: toy_merg").replace("count: 20", "count: 0")
    )
    issues = issues_of(text, registry)
    assert len(issues) >= 3
    assert sorted(i.location.line for i in issues)[:3] == [8, 13, 18]


def test_outputs_must_exist(registry):
    issues = issues_of(VALID.replace("outputs: [merge.spheres]", "outputs: [merge.sphere, nope]"), registry)
    assert issues[0].suggestion == "spheres" and issues[0].location.line == 4
    assert "unknown node 'nope'" in issues[1].message


def test_variant_families_must_agree(registry):
    text = VALID.replace(
        "    params: {count: 20, scale: 2.0}\n", "    variants: 4\n    params: {count: 20, scale: 2.0}\n"
    )
    text = text.replace(
        "    inputs: {spheres: pts.spheres}\n    params:\n      dx: 1.5\n",
        "    variants: 3\n    inputs: {spheres: pts.spheres}\n    params:\n      dx: 1.5\n",
    )
    (issue,) = issues_of(text, registry)
    assert issue.node == "shifted" and "different sizes" in issue.message and "4 from pts" in issue.message


def test_set_override_is_validated(registry):
    recipe = parse_recipe(VALID, registry, file="r.yaml", overrides=["shifted.dx=-2.5", "seed=11"])
    assert recipe.nodes["shifted"].params["dx"] == -2.5 and recipe.seed == 11
    issues = issues_of(VALID, registry, overrides=["shifted.dx=50", "shifted.dy=1", "shiftd.dx=1"])
    assert [str(i.location) for i in issues] == ["--set:1", "--set:2", "--set:3"]
    assert "out of range" in issues[0].message
    assert issues[1].suggestion == "dx" and issues[2].suggestion == "shifted.dx=1"


def test_a_parameter_set_without_its_node_lists_the_nodes_that_have_it(registry):
    """Issue 47: ``--set water_content=22`` said only "cannot read"; now it names the nodes with that parameter,
    and with one such node the setting meant."""
    two = VALID.replace(
        "      dx: 1.5\n", "      dx: 1.5\n  again:\n    type: toy_shift\n    inputs: {spheres: pts.spheres}\n"
    )
    (issue,) = issues_of(two, registry, overrides=["dx=2"])
    assert str(issue.location) == "--set:1" and issue.allowed == "the nodes that have it: shifted.dx, again.dx"
    assert issue.suggestion is None
    (issue,) = issues_of(VALID, registry, overrides=["dx=2"])
    assert issue.suggestion == "shifted.dx=2" and "did you mean 'shifted.dx=2'?" in str(issue)
    (issue,) = issues_of(VALID, registry, overrides=["dz=2"])  # no node has it: the form is what is wrong
    assert "cannot read 'dz=2'" in issue.message


def test_load_recipe_from_file_names_file(registry, recipe_file):
    path = recipe_file(VALID.replace("dx: 1.5", "dx: 15"))
    with pytest.raises(RecipeError) as info:
        load_recipe(path, registry)
    assert f"{path}:13:11" in str(info.value)
    assert load_recipe(recipe_file(VALID), registry).name == "toy"


def test_value_failing_every_union_member_is_one_issue(registry):
    text = "outputs: [a]\nnodes:\n  a: {type: toy_shift, inputs: {spheres: 3}, variants: x}\n"
    issues = issues_of(text, registry)
    assert [(i.location.line, i.location.column, i.param) for i in issues] == [(3, 42, "spheres"), (3, 56, "variants")]
    assert issues[0].allowed == "str or list[str]" and issues[0].given == 3


def test_a_moved_parameter_names_where_it_lives_now_and_recipe_checks_see_every_node(registry):
    """``Moved``: a recipe still setting a parameter the node type gave up is told which node holds it now (at its
    line); ``check_recipe``: a node's check across the recipe reports at the offending parameter's line."""
    from nodegraph.node import In, Moved, Out, node
    from nodegraph.registry import Registry

    spheres = registry.get("toy_points").outputs["spheres"].type

    @node("toy_step", outputs={"spheres": Out(spheres, "")}, params={"dx": Param(float, 1.0, "")})
    def toy_step(ctx, *, dx):
        return None

    def wider_than_every_step(node_id, nodes):
        steps = [e.params["dx"] for e in nodes.values() if e.spec.type_name == "toy_step"]
        return [("dx", f"{nodes[node_id].params['dx']} exceeds a step")] if any(s < 1.0 for s in steps) else []

    @node(
        "toy_mover",
        inputs={"step": In(spheres, "", optional=True)},
        outputs={"spheres": Out(spheres, "")},
        params={"dx": Param(float, 1.0, "")},
        moved={"speed": Moved("step", "dx", "toy_step")},
        check_recipe=wider_than_every_step,
    )
    def toy_mover(ctx, step=None, *, dx):
        return None

    reg = Registry([toy_step, toy_mover])
    text = "outputs: [m.spheres]\nnodes:\n  s:\n    type: toy_step\n    params: {dx: 2.0}\n  m:\n    type: toy_mover\n"
    wired = text + "    inputs: {step: s.spheres}\n    params: {speed: 3.0}\n"
    (issue,) = issues_of(wired, reg)
    assert str(issue.location) == "r.yaml:9:14" and issue.node == "m"
    assert "moved to parameter 'dx' of the toy_step node wired into input 'step'" in issue.message
    assert "that node is 's' at r.yaml:5:18" in issue.message and "--set s.dx=3.0" in issue.message
    (issue,) = issues_of(text + "    params: {speed: 3.0}\n", reg)
    assert "wire a toy_step node into input 'step'" in issue.message
    parse_recipe(text, reg, file="r.yaml")
    (issue,) = issues_of(text, reg, ["s.dx=0.5"])
    assert (issue.node, issue.param, str(issue.location)) == ("m", "dx", "r.yaml:7:5")  # m itself: dx unset


def test_an_unknown_parameter_is_matched_on_its_words_across_the_recipes_nodes():
    """Issue 47: ``--set shade.rice_color=...`` suggested ``scenery_color`` (edit distance, the node's own names); the
    rice's colour follows the cooked material's water content, whose doc names rice and colour both."""
    from nodegraph.recipe import nearest_params

    params = {
        "shade": {"scenery_color": "glaze colour of scenery meshes (the bowl)", "presets": "preset per element kind"},
        "cooked": {"water_content": "water absorbed: the rice material (its colour and gloss) follows it"},
        "preview": {"samples": "samples per pixel"},
    }
    assert nearest_params("shade", "rice_color", params) == ("cooked.water_content", "shade.scenery_color")
    assert nearest_params("shade", "scenery_colr", params) == ("scenery_color",)  # a typo stays a typo
    assert nearest_params("preview", "sampels", params) == ("samples",)
    assert nearest_params("preview", "zzz", params) == ()


def test_several_suggestions_are_each_named(registry):
    (issue,) = issues_of(VALID, registry, ["pts.counts_number=3"])
    assert issue.suggestion == "count" and "did you mean 'count'?" in str(issue)


def test_a_top_level_error_does_not_hide_the_others(registry):
    """Issue 47: a misspelt top-level key (``efects:``) hid a bad output name until the next check; every
    independent error is reported in one pass."""
    text = (
        VALID.replace("effects:", "efects:")
        .replace("outputs: [merge.spheres]", "outputs: [merge.sphere]")
        .replace("name: toy", "name: a/b")
        .replace("seed: 3", "seed: three")
    )
    found = {(i.location.line, i.message.split(" (")[0].split(":")[0]) for i in issues_of(text, registry)}
    assert found == {
        (1, "the recipe name names its output folder and recording, so it must be a plain name"),
        (2, "Input should be a valid integer, unable to parse string as an integer"),
        (3, "unknown key 'efects'"),
        (4, "'merge' has no output 'sphere'"),
    }


def test_a_setting_on_a_node_not_in_the_recipe_suggests_the_node_that_has_the_setting():
    """Issue 47: ``--set egg.diameter=8`` on the ikura don suggested ``egg_sim``, which has no diameter: the nearest
    name among all the nodes. Among the nodes that have the setting, the nearest by name is the one meant."""
    from pathlib import Path

    from nodegraph.api import default_registry

    ikura = Path(__file__).resolve().parents[2] / "graphs" / "ikura_don.yaml"
    with pytest.raises(RecipeError) as info:
        load_recipe(ikura, default_registry(), overrides=["egg.diameter=8", "bowel.size=30", "xyz.foo=1"])
    egg, bowl, nothing = info.value.issues
    assert egg.suggestion == "egg_base.diameter=8" and "did you mean 'egg_base.diameter=8'?" in str(egg), str(egg)
    assert bowl.suggestion == "bowl.size=30"
    assert nothing.suggestion is None
