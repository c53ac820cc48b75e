"""``nodegraph check`` refuses a ratio list that does not match the libraries wired to ``mix_ratio`` (issue 47: a
new user's ``mix.ratios=[10]`` failed the run after its grains were built)."""

from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe
from nodegraph.errors import RecipeError

GRAPHS = Path(__file__).resolve().parents[2] / "graphs"


def test_one_ratio_per_library_is_checked_before_any_work():
    registry = default_registry()
    with pytest.raises(RecipeError) as info:
        load_recipe(GRAPHS / "rice_chestnut.yaml", registry, ["mix.ratios=[10]"])
    assert "node 'mix', ratios: 1 value(s) for the 2 libraries wired; allowed: 2 values, or none" in str(info.value)
    load_recipe(GRAPHS / "rice_chestnut.yaml", registry, ["mix.ratios=[10, 1]"])  # one per library: accepted
