"""Fixtures shared by several test folders: a small synthetic aggregate (capsule grains + ikura eggs with
membrane/yolk parts, a bowl) and that aggregate shaded, for the shading and the export tests."""

import os
import tempfile

import pytest

from nodegraph import runtime

# the suite remembers code digests in a file of its own, not in the user's cache (``nodegraph.code_digest``);
# processes it starts inherit the choice
os.environ.setdefault("NODEGRAPH_CODE_DIGESTS", os.path.join(tempfile.mkdtemp(prefix="nodegraph-digests-"), "d.json"))
# numba's kernel cache and per-module locator, as a run has them (``import nodegraph`` sets nothing), before a test
# imports a kernel module; processes the tests start inherit them
runtime.configure()


@pytest.fixture(scope="session")
def scene_inputs():
    from nodes.simulation.scenes import small_food_scene

    return small_food_scene()


@pytest.fixture(scope="session")
def shaded(scene_inputs):
    from nodes.material.cooked import cooked_material
    from nodes.shading import shade

    return shade.call(**scene_inputs, material=cooked_material())
