"""Errors that used to mislead a new user: each says what is wrong and what to do, never a traceback."""

from pathlib import Path

import pytest

from nodegraph.cli import doc_summary, main
from nodegraph.errors import RecipeError
from nodegraph.recipe import load_recipe, parse_recipe

from .conftest import TOY
from .test_validation import VALID

REPO = Path(__file__).resolve().parents[2]


def test_nodes_lists_what_each_node_does_in_words_without_equations(capsys):
    """Issue 47: the listing showed "R = [u v w]·R_zyx(γ, β, α)" and "G eq. 5 …"; equations and citations are for
    ``describe``, which still shows them."""
    import re

    assert main(["nodes"]) == 0
    out = capsys.readouterr().out
    assert "rotate             Random rotation per P_num in a local uvw frame." in out
    assert "distance_field     Signed distance to the element surface." in out
    assert "expand             The cooked grain's swelling." in out
    for line in out.splitlines():
        assert not re.search(r"[=·→∪]|SPEC|§|\beqs?\.|``|\(G\b", line), line
    assert main(["describe", "rotate"]) == 0
    assert "R = [u v w]·R_zyx" in capsys.readouterr().out


def test_doc_summary_cuts_at_a_sentence_end_only():
    assert (
        doc_summary("One thing (e.g. a grain)\nspans lines. Second sentence.")
        == "One thing (e.g. a grain) spans lines."
    )
    assert doc_summary("No full stop, but\ntwo lines\n\nsecond paragraph") == "No full stop, but two lines"


@pytest.mark.parametrize(
    "head, kind", [(b"\x89PNG\r\n\x1a\n", "a PNG image"), (b"glTF\x02\x00", "a glTF binary (.glb)"), (b"", "empty")]
)
def test_inspect_refuses_a_file_that_is_not_a_recording(tmp_path, capsys, head, kind):
    path = tmp_path / "preview.png"
    path.write_bytes(head + b"\0" * 8 if head else b"")
    assert main(["inspect", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"is {kind}, not a Rerun recording" in err and "Traceback" not in err


def test_a_missing_recipe_suggests_the_one_in_graphs(monkeypatch):
    monkeypatch.chdir(REPO)
    for given in ("ikura_don", "ikura_don.yaml", "graphs/ikura_do.yaml"):
        with pytest.raises(RecipeError) as info:
            load_recipe(given, registry=None)
        assert info.value.issues[0].suggestion == "graphs/ikura_don.yaml", given


@pytest.mark.parametrize(
    "old, new, line, words",
    [
        ("    params: {count", "   params: {count", 8, "check the indentation of line 8: it starts at column 4"),
        ("    params:\n      dx", "      params:\n      dx", 12, "check the indentation of line 12"),
        ("    params: {count", "\tparams: {count", 8, "line 8 is indented with a tab"),
    ],
)
def test_yaml_indentation_mistakes_get_a_hint(registry, old, new, line, words):
    assert old in VALID
    with pytest.raises(RecipeError) as info:
        parse_recipe(VALID.replace(old, new, 1), registry, file="r.yaml")
    (issue,) = info.value.issues
    assert issue.location.line == line and words in issue.message


def test_node_keys_indented_too_little_are_named(registry):
    text = VALID.replace("  merge:\n    type: toy_merge\n    inputs", "  merge:\n  type: toy_merge\n  inputs")
    with pytest.raises(RecipeError) as info:
        parse_recipe(text, registry, file="r.yaml")
    messages = [str(i) for i in info.value.issues]
    assert any("node 'merge': nothing under it" in m for m in messages)
    assert any(
        "'type' is a key of a node, not a node: check the indentation; indent it under node 'merge'" in m
        for m in messages
    )


def test_params_indented_as_a_node_get_one_indentation_hint(registry):
    """``params:`` two spaces too far out reads as a node named 'params' holding the parameters: one issue
    that names the indentation and the node it belongs to, not one per parameter ("unknown key 'count'")."""
    old = "    params: {count: 20, scale: 2.0}"
    assert old in VALID
    with pytest.raises(RecipeError) as info:
        parse_recipe(VALID.replace(old, old[2:]), registry, file="r.yaml")
    (issue,) = info.value.issues
    assert issue.location.line == 8
    assert "'params' is a key of a node, not a node: check the indentation; indent it under node 'pts'" in str(issue)


def test_a_failed_first_run_does_not_claim_an_older_recording(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "40")  # a narrow terminal: warnings must not be hard-wrapped mid-phrase
    recipe = tmp_path / "my_don.yaml"
    recipe.write_text(
        "outputs: [boom.spheres]\nnodes:\n  pts: {type: toy_points}\n"
        "  boom: {type: toy_fail, inputs: {spheres: pts.spheres}}\n"
    )
    rrd = tmp_path / "my_don.rrd"
    args = ["run", str(recipe), "--plugin", str(TOY), "--cache-dir", str(tmp_path / "c"), "--rrd", str(rrd)]
    assert main([*args, "--out-dir", str(tmp_path / "out")]) == 1
    err = capsys.readouterr().err
    assert "no complete recording" in err and "left as it was" not in err
    rrd.write_bytes(b"an older complete recording")
    assert main([*args, "--out-dir", str(tmp_path / "out")]) == 1
    assert "left as it was" in capsys.readouterr().err


def test_a_misspelt_output_suggests_the_nearest_node_and_port(registry):
    """Issue 47: ``--output previw`` listed the nodes but, unlike every other error, did not say 'did you mean'."""
    from nodegraph.errors import NodegraphError
    from nodegraph.executor import resolve_outputs

    recipe = parse_recipe(VALID, registry, file="r.yaml")
    with pytest.raises(NodegraphError, match=r"no node 'shfted' in recipe r.yaml; did you mean 'shifted'\?; nodes: "):
        resolve_outputs(recipe, ["shfted"])
    with pytest.raises(NodegraphError, match=r"has no output 'sphere'; did you mean 'merge.spheres'\?; outputs: "):
        resolve_outputs(recipe, ["merge.sphere"])


@pytest.mark.parametrize(
    "old, new, where, words",
    [
        ("{count: 20, scale: 2.0}", "{count: 20, scale: 2.0", "r.yaml:8:13", "`{` opened on line 8 is never closed"),
        ("effects: [gravity]", "effects: [gravity", "r.yaml:3:10", "the `[` opened on line 3 is never closed"),
        ("[pts.spheres, phys.spheres]", "[pts.spheres, phys.spheres", "r.yaml:19:47", "inside the `[…]` list opened"),
        ("{count: 20, scale: 2.0}", "{count: 20 scale: 2.0}", "r.yaml:8:29", "inside the `{…}` mapping opened"),
        ("name: toy", 'name: "toy', "r.yaml:1:7", "the quote opened on line 1 is never closed"),
    ],
)
def test_a_yaml_syntax_error_points_where_the_bracket_or_quote_opened(registry, old, new, where, words):
    """Issue 47: a `}` removed on line 28 was reported at 31:3 as "expected ',' or '}', but got '?'": the place to
    fix is where the `{` opened, and the words are plain ones, not the parser's token names."""
    assert old in VALID
    with pytest.raises(RecipeError) as info:
        parse_recipe(VALID.replace(old, new, 1), registry, file="r.yaml")
    (issue,) = info.value.issues
    assert str(issue.location) == where and words in issue.message, str(issue)
    assert "'?'" not in issue.message and "got" not in issue.message


def test_a_misspelt_option_gets_its_commands_usage_and_the_nearest_option(capsys):
    """Issue 47: ``run … --drfat`` printed the top-level usage, without a did-you-mean."""
    with pytest.raises(SystemExit) as info:
        main(["run", "graphs/ikura_don.yaml", "--drfat"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("usage: nodegraph run ") and "--max-minutes" in err
    assert "nodegraph run: error: unrecognized arguments: --drfat; --drfat: did you mean --draft?" in err


def test_a_set_without_equals_is_shown_joined(capsys):
    """Issue 47: ``--set rice_sim.frames 3`` said only "unrecognized arguments: 3"."""
    with pytest.raises(SystemExit) as info:
        main(["run", "graphs/ikura_don.yaml", "--set", "rice_sim.frames", "3"])
    assert info.value.code == 2
    assert "unrecognized arguments: 3; 3: did you mean --set rice_sim.frames=3?" in capsys.readouterr().err
