"""Fixtures shared by several test folders: a small synthetic aggregate (capsule grains + ikura eggs with
membrane/yolk parts, a bowl) and that aggregate shaded, for the shading and the export tests."""

import pytest


@pytest.fixture(scope="session")
def scene_inputs():
    from nodes.simulation.scenes import small_food_scene

    return small_food_scene()


@pytest.fixture(scope="session")
def shaded(scene_inputs):
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade

    return shade.call(**scene_inputs, material=cooked_material())
