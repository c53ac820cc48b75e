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
