from pathlib import Path

import pytest

from nodegraph.cache import Cache
from nodegraph.registry import Registry

TOY = Path(__file__).with_name("toy_nodes.py")


@pytest.fixture(scope="session")
def registry():
    reg = Registry()
    reg.add_plugin_file(TOY)
    return reg


@pytest.fixture
def cache(tmp_path):
    return Cache(tmp_path / "cache")


@pytest.fixture
def recipe_file(tmp_path):
    def write(text, name="recipe.yaml"):
        path = tmp_path / name
        path.write_text(text)
        return path

    return write
