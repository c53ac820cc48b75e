"""The accuracy studies under graphs/sweeps/ stay valid recipes, and docs/accuracy.md runs every one.

Loading validates the recipe and its ``sweeps:`` block (file:line:column); every grid point is then
validated as the sweep command does before it runs anything (a value out of a parameter's range names
its point). Seconds: nothing is computed.
"""

import importlib.util
from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe
from nodegraph.sweep import _point_recipes

ROOT = Path(__file__).resolve().parents[2]
RECIPES = sorted((ROOT / "graphs" / "sweeps").glob("*.yaml"))


def report():
    spec = importlib.util.spec_from_file_location("accuracy_report", ROOT / "benchmarks" / "accuracy_report.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("path", RECIPES, ids=[p.stem for p in RECIPES])
def test_sweep_recipe_and_every_point_validate(path):
    registry = default_registry()
    recipe = load_recipe(path, registry, [])
    assert recipe.sweeps, f"{path.name} declares no sweeps: block"
    for decl in recipe.sweeps.values():
        points = _point_recipes(path, registry, decl, [])
        assert len(points) == len(decl.points()) > 1
        assert decl.metrics, f"{path.name}: sweep {decl.name} reads no metric"


def test_accuracy_report_runs_every_sweep_recipe():
    assert sorted(report().SWEEPS) == [p.stem for p in RECIPES]


def test_quick_grids_hold_the_recipe_setting():
    """A quick report's sweep keeps the recipe's own setting among its points (the row the report bolds)."""
    registry = default_registry()
    for name, args in report().SWEEPS.items():
        recipe = load_recipe(ROOT / "graphs" / "sweeps" / f"{name}.yaml", registry, [])
        grids = [args[i + 1] for i, a in enumerate(args) if a == "--grid"]
        assert grids, f"{name}: the quick report runs the recipe's whole grid"
        for grid in grids:
            target, values = grid.split("=")
            node, param = target.split(".")
            assert str(recipe.nodes[node].params[param]) in values.split(","), f"{name}: {grid}"
