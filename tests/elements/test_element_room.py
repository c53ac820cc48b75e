"""Issue 47: ``nodegraph check`` refuses an element larger than the shape it is placed in, from the recipe alone:
a 200 mm chestnut piece on a 76 mm onigiri and an 80 mm egg in a 35 mm deep bowl passed the check and failed, or
made nonsense, in the run."""

from __future__ import annotations

from pathlib import Path

import pytest

from nodegraph.api import default_registry, load_recipe
from nodegraph.errors import RecipeError

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(
    ("recipe_file", "override", "param", "allowed"),
    [
        ("rice_chestnut.yaml", "chestnut_base.size=[200,180,150]", "size", "each side ≤ 68.4 mm"),
        ("ikura_don.yaml", "egg_base.diameter=100", "diameter", "diameter ≤ 74.8 mm"),
    ],
)
def test_check_refuses_an_element_larger_than_its_shape(recipe_file, override, param, allowed):
    """The problem names where the value was given, the node and parameter, and the largest value that fits."""
    with pytest.raises(RecipeError) as caught:
        load_recipe(ROOT / "graphs" / recipe_file, default_registry(), [override], work=True)
    text = str(caught.value)
    node = override.partition(".")[0]
    assert f"--set:1: node '{node}', {param}:" in text
    assert f"allowed: {allowed}" in text


def test_the_line_in_the_file_is_named(tmp_path):
    """Set in the recipe itself, the problem points at the line that sets it."""
    text = (ROOT / "graphs" / "rice_chestnut.yaml").read_text()
    recipe = tmp_path / "rice_chestnut.yaml"
    recipe.write_text(text.replace("size: [26.0, 23.0, 17.0]", "size: [200, 180, 150]"))
    line = next(i for i, row in enumerate(recipe.read_text().splitlines(), 1) if "[200, 180, 150]" in row)
    with pytest.raises(RecipeError, match=rf"rice_chestnut.yaml:{line}:\d+: node 'chestnut_base', size: "):
        load_recipe(recipe, default_registry(), work=True)


def test_an_element_that_fits_passes():
    """The recipes as written, and an egg as large as fits, pass."""
    load_recipe(ROOT / "graphs" / "ikura_don.yaml", default_registry(), ["egg_base.diameter=30"], work=True)


@pytest.mark.parametrize("recipe_file", ["rice_chestnut.yaml", "ikura_don.yaml"])
def test_each_draft_fits_its_elements(recipe_file):
    """A draft shrinks the shape, not the elements: its chestnut quarters (up to 22 mm) must still fit the draft's
    onigiri (at 22.8 mm its smallest span was 20.5 mm, and ``--draft`` refused to run)."""
    load_recipe(ROOT / "graphs" / recipe_file, default_registry(), draft=True, work=True)
