"""``nodegraph check`` estimates every recipe it accepts before any work: its elements, its peak memory and its
CPU time (issue 47: none for the rice bunny and the sweeps, whose elements were not known from the recipe)."""

import re
from pathlib import Path

import pytest

from nodegraph.cli import main

GRAPHS = Path(__file__).resolve().parents[2] / "graphs"
RECIPES = sorted(GRAPHS.glob("*.yaml")) + sorted((GRAPHS / "sweeps").glob("*.yaml"))


@pytest.mark.parametrize("path", RECIPES, ids=lambda p: p.stem)
def test_check_estimates_elements_memory_and_time_of_every_recipe(path, capsys):
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert re.search(r"estimate: elements: ≈ [\d,]+", out), out
    assert re.search(r"estimate: peak memory: ≈ [\d.,]+ (MiB|GiB)", out), out
    assert re.search(r"estimate: time: ≈ (< 1 s|[\d.]+ (s|min)) CPU", out), out
    if "sweeps:" in path.read_text():
        assert re.search(r"estimate: sweep \w+: \d+ points, ≈ [\d.]+ (s|min) CPU in all", out), out


def test_the_time_estimate_follows_the_preview_and_the_elements():
    """Twice the samples, more time in the pictures; a bigger bowl, more elements and more time."""
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    def cost(*overrides):
        return load_recipe(GRAPHS / "rice_bowl.yaml", default_registry(), list(overrides), work=True, yes=True).cost

    base = cost()
    assert cost("preview.samples=6").cpu_seconds > base.cpu_seconds
    bigger = cost("bowl.size=65")
    assert bigger.elements > base.elements and bigger.other_seconds > base.other_seconds


def test_the_kakigori_estimate_counts_the_flakes_its_culls_keep():
    """Issue 47: ``check`` said ≈ 17,860 elements for the kakigori, which keeps 11,031 (its draft 1,406): its ice
    shavings lose a third to the cull (0.66 kept, the grains 0.95) and its two cull_crossing steps 14 % more."""
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    def elements(draft):
        recipe = load_recipe(GRAPHS / "kakigori.yaml", default_registry(), draft=draft, work=True, yes=True)
        return recipe.cost.elements

    assert abs(elements(False) / 11_031 - 1) < 0.1, elements(False)  # measure.csv of a full run
    assert abs(elements(True) / 1_406 - 1) < 0.1, elements(True)
    bowl = load_recipe(GRAPHS / "rice_bowl.yaml", default_registry(), work=True, yes=True).cost
    assert bowl.elements == round(0.95 * bowl.costs["rice_place"].made)  # the grains' share stays
