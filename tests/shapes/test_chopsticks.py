"""The main job's chopsticks (issue 48: a food photograph stages its props): two closed tapered sticks of an adult's
length, flat on the table beside the bowl, clear of it; refused before any work when they taper the wrong way or
cross."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from nodes.shapes import chopsticks, shape

ROOT = Path(__file__).resolve().parents[2]


def test_the_main_jobs_chopsticks_lie_closed_on_the_table_beside_the_bowl():
    from nodegraph.api import default_registry, load_recipe

    recipe = load_recipe(ROOT / "graphs" / "ikura_don.yaml", default_registry(), [])
    bowl = shape.call(**recipe.nodes["bowl"].params)["container"]
    pair = chopsticks.call(dish=bowl, **recipe.nodes["chopsticks"].params)
    assert pair.name == "chopsticks"
    sticks = trimesh.Trimesh(pair.vertices, pair.faces, process=False).split(only_watertight=False)
    assert len(sticks) == 2 and all(s.is_watertight and s.volume > 0 for s in sticks)
    for stick in sticks:  # 230 mm from head to tip, 7 mm across the head
        extent = stick.vertices.max(axis=0) - stick.vertices.min(axis=0)
        assert np.hypot(extent[0], extent[1]) == pytest.approx(230.0, abs=8.0) and extent[2] == pytest.approx(7.0)
    assert pair.vertices[:, 2].min() == pytest.approx(bowl.vertices[:, 2].min())  # on the table
    centre = 0.5 * (bowl.vertices.min(axis=0) + bowl.vertices.max(axis=0))
    rim = np.linalg.norm(bowl.vertices[:, :2] - centre[:2], axis=1).max()
    assert np.linalg.norm(pair.vertices[:, :2] - centre[:2], axis=1).min() > rim  # clear of the bowl


def test_sticks_that_taper_backwards_or_cross_are_refused_before_any_work(tmp_path):
    from nodegraph.api import default_registry, load_recipe
    from nodegraph.errors import RecipeError

    for setting, param in (("chopsticks.tip=9", "tip"), ("chopsticks.gap=3", "gap")):
        with pytest.raises(RecipeError, match=param):
            load_recipe(ROOT / "graphs" / "ikura_don.yaml", default_registry(), [setting])
