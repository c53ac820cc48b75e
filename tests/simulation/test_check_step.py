"""Issue 46: ``nodegraph check`` refuses a step in which gravity alone sinks resting grains into each other
(``step_limits.check_gravity_step``), from the recipe alone: at 2 substeps the rice bowl passed the check and was
refused only at ``rice_sim``'s start, after its grains were built and placed."""

from __future__ import annotations

from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe
from nodegraph.errors import RecipeError

ROOT = Path(__file__).resolve().parents[2]


def test_check_refuses_two_substeps_and_names_the_remedy():
    with pytest.raises(RecipeError) as caught:
        load_recipe(ROOT / "graphs" / "rice_bowl.yaml", default_registry(), ["rice_sim.substeps=2"], work=True)
    text = str(caught.value)
    assert "--set:1: node 'rice_sim', substeps: dt / substeps" in text
    assert "use substeps ≥ 3 or iterations ≥ 3" in text


@pytest.mark.parametrize("overrides", [["rice_sim.substeps=3"], ["rice_sim.substeps=2", "rice_sim.iterations=3"]])
def test_the_remedies_pass(overrides):
    load_recipe(ROOT / "graphs" / "rice_bowl.yaml", default_registry(), overrides, work=True)


def test_a_slender_run_is_estimated_at_its_particles_and_substeps():
    """Issue 47: indica in the rice bowl (``slender``: m = 2) was estimated at 10 substeps and 8 particles a grain
    (≈ 1 s CPU) and ran 80 substeps of 32 (29 s): the estimate takes m from the grains' length over width."""
    registry = default_registry()
    costs = {}
    for variety in ("japonica", "indica"):
        recipe = load_recipe(
            ROOT / "graphs" / "rice_bowl.yaml", registry, [f"variety.variety={variety}"], draft=True, work=True
        )
        costs[variety] = recipe.cost.costs["rice_sim"]
    assert "× 10 substeps" in costs["japonica"].what and costs["japonica"].particles == 8 * costs["japonica"].elements
    assert "× 80 substeps" in costs["indica"].what and costs["indica"].particles == 32 * costs["indica"].elements
