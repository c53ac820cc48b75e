"""The engine's cost walk (``nodegraph.cost``): each node type's estimate from its parameters and its inputs'
estimates, summed over the graph; ``check`` prints it and refuses what is over a run's limits at the parameter to
change (issue 47: cost is known before the work starts)."""

from pathlib import Path

import pytest

from nodegraph.cli import main
from nodegraph.cost import PROCESS_BYTES, Limits
from nodegraph.errors import RecipeError
from nodegraph.recipe import load_recipe
from nodegraph.registry import Registry

TOY = Path(__file__).with_name("toy_cost_nodes.py")
RECIPE = """\
name: costed
outputs: [step.table]
nodes:
  make:
    type: cost_make
    params: {count: 1000}
  half:
    type: cost_half
    inputs: {table: make.table}
  step:
    type: cost_step
    inputs: {table: half.table}
    params: {steps: 20}
"""


@pytest.fixture(scope="module")
def costed():
    reg = Registry()
    reg.add_plugin_file(TOY)
    return reg


def test_the_elements_flow_through_the_graph_and_the_costs_sum(costed, tmp_path):
    path = tmp_path / "costed.yaml"
    path.write_text(RECIPE)
    cost = load_recipe(path, costed, work=True).cost
    assert cost.costs["half"].elements == 500 and cost.elements == 500  # made 1,000, half kept, stepped
    assert cost.particles == 500 and cost.seconds == pytest.approx(10.0)
    assert cost.peak == (PROCESS_BYTES + 1_000_000, "make")  # the node holding the most
    assert "elements: ≈ 500, kept of those placed (make 1,000)" in cost.lines()
    assert load_recipe(path, costed).cost is None  # weighed only with work (check, run before any work)


def test_over_a_limit_is_refused_at_the_parameter_unless_yes(costed, tmp_path):
    path = tmp_path / "costed.yaml"
    path.write_text(RECIPE)
    with pytest.raises(RecipeError) as refused:
        load_recipe(path, costed, work=True, limits=Limits(max_seconds=5.0))
    text = str(refused.value)
    assert "costed.yaml:13:" in text
    assert "node 'step', steps: its work would take ≈ 10 s of CPU, over a run's limit of 5 s" in text
    assert "(--max-minutes); allowed: steps ≤ 10" in text
    assert "or run with --yes to go ahead" in text
    assert load_recipe(path, costed, work=True, yes=True, limits=Limits(max_seconds=5.0)).cost.seconds == 10.0
    assert load_recipe(path, costed, ["step.steps=10"], work=True, limits=Limits(max_seconds=5.0))  # the value named


def test_a_peak_over_the_available_memory_is_refused_by_the_same_rule_unless_yes(costed, tmp_path):
    """Memory is weighed as time is, for every node (``cost.limit_over``): a peak over the machine's available memory
    is refused (at the node itself where it names no lever), with the node that made the elements; --yes passes."""
    path = tmp_path / "costed.yaml"
    path.write_text(RECIPE)
    tight = Limits(max_bytes=PROCESS_BYTES + 600_000)  # 'make' holds 1,000,000 bytes, 'step' 5,000
    with pytest.raises(RecipeError) as refused:
        load_recipe(path, costed, work=True, limits=tight)
    text = str(refused.value)
    assert "costed.yaml:5:" in text and "node 'make': its work would hold ≈ 49 MiB at its peak, over the" in text
    assert "this machine has available; the elements it holds were made by make 1,000; or run with --yes" in text
    assert "node 'step'" not in text  # the nodes within it are not named
    assert load_recipe(path, costed, work=True, yes=True, limits=tight).cost.peak[1] == "make"


def test_check_prints_the_estimate_and_max_minutes_sets_the_limit(costed, tmp_path, capsys, monkeypatch):
    path = tmp_path / "costed.yaml"
    path.write_text(RECIPE.replace("steps: 20", "steps: 2000"))  # 1,000 s: over the default 10 min
    monkeypatch.setattr("nodegraph.cli.default_registry", lambda plugins=(): costed)
    assert main(["check", str(path)]) == 2
    assert "steps ≤ 1200" in capsys.readouterr().err
    assert main(["check", str(path), "--max-minutes", "20"]) == 0
    out = capsys.readouterr().out
    assert "estimate: elements: ≈ 500, kept of those placed (make 1,000)" in out
    assert "estimate: step: 500 particles" in out


def test_run_weighs_the_same_estimate_before_its_first_node(costed, tmp_path, capsys, monkeypatch):
    path = tmp_path / "costed.yaml"
    path.write_text(RECIPE.replace("steps: 20", "steps: 2000"))
    monkeypatch.setattr("nodegraph.cli.default_registry", lambda plugins=(): costed)
    common = ["--cache-dir", str(tmp_path / "c"), "--out-dir", str(tmp_path / "o"), "--no-rrd"]
    assert main(["run", str(path), *common]) == 2  # refused before any node: nothing computed, nothing cached
    assert "steps ≤ 1200" in capsys.readouterr().err and not (tmp_path / "c").exists()
    assert main(["run", str(path), *common, "--max-minutes", "20"]) == 0
    err = capsys.readouterr().err
    assert "estimate: elements: ≈ 500, kept of those placed (make 1,000); step: 500 particles" in err


def test_a_run_of_one_output_weighs_only_what_it_needs(costed, tmp_path, capsys, monkeypatch):
    path = tmp_path / "costed.yaml"
    path.write_text(RECIPE.replace("steps: 20", "steps: 2000"))  # the stepper is over the limit; --output half is not
    monkeypatch.setattr("nodegraph.cli.default_registry", lambda plugins=(): costed)
    common = ["--cache-dir", str(tmp_path / "c"), "--out-dir", str(tmp_path / "o"), "--no-rrd"]
    assert main(["run", str(path), "--output", "half", *common]) == 0
    assert "estimate: elements: ≈ 500, kept of those placed (make 1,000); peak memory" in capsys.readouterr().err


def test_a_cached_rerun_through_a_node_never_stored_weighs_nothing(costed, tmp_path, capsys, monkeypatch):
    """Issue 47: a no-op re-run of a scene took 3–5 s: its shade node is never stored, so it was never in the cache,
    so every re-run weighed the recipe (its shapes made with trimesh, ≈ 0.7 s). A node never stored is not weighed:
    a re-run whose stored nodes are all cached prints no estimate."""
    path = tmp_path / "costed.yaml"
    path.write_text(
        RECIPE.replace("outputs: [step.table]", "outputs: [again.table]")
        + "  again:\n    type: cost_unstored\n    inputs: {table: step.table}\n"
    )
    monkeypatch.setattr("nodegraph.cli.default_registry", lambda plugins=(): costed)
    common = ["--cache-dir", str(tmp_path / "c"), "--out-dir", str(tmp_path / "o"), "--no-rrd"]
    assert main(["run", str(path), *common]) == 0
    assert "estimate: elements" in capsys.readouterr().err  # the first run weighs
    assert main(["run", str(path), *common]) == 0
    assert "estimate:" not in capsys.readouterr().err
