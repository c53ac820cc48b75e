"""A node's cache key covers the code it runs: editing a helper module it imports (inside its function,
relative or absolute, at any depth) re-runs it; editing a module it does not import does not."""

import sys
import textwrap
from importlib.metadata import EntryPoint

import pytest

from nodegraph import registry as registry_module
from nodegraph.cache import Cache
from nodegraph.code_digest import project_modules
from nodegraph.executor import run_recipe
from nodegraph.recipe import parse_recipe

PACKAGE = "kitchen_nodes"
FILES = {
    "__init__.py": "from .boil import boil  # noqa: F401\n",
    "boil.py": '''
        from nodegraph import Out, Param, node
        from nodegraph.values import Table


        @node("boil", outputs={"table": Out(Table, "the water's temperature")},
              params={"minutes": Param(float, 1.0, "how long")})
        def boil(ctx, *, minutes):
            """Heat water (the helper is imported inside the function, as the built-in nodes do)."""
            import numpy as np

            from . import heat

            return Table({"celsius": np.array([heat.temperature(minutes)])})
        ''',
    "heat.py": """
        import kitchen_nodes.stove as stove


        def temperature(minutes):
            return min(100.0, 20.0 + stove.POWER * minutes)
        """,
    "stove.py": "POWER = 10.0\n",
    "unrelated.py": "SALT = 1.0\n",
}
RECIPE = "outputs: [water]\nnodes:\n  water: {type: boil, params: {minutes: 2.0}}\n"


@pytest.fixture
def kitchen(tmp_path, monkeypatch):
    """A node package on sys.path, registered through a (fake) entry point like an installed plugin;
    ``load()`` imports it afresh, as a new process would after an edit."""
    package = tmp_path / PACKAGE
    package.mkdir()
    for name, text in FILES.items():
        (package / name).write_text(textwrap.dedent(text))
    monkeypatch.syspath_prepend(str(tmp_path))
    fake = [EntryPoint("kitchen", PACKAGE, registry_module.ENTRY_POINT_GROUP)]
    monkeypatch.setattr(
        registry_module, "entry_points", lambda group: fake if group == registry_module.ENTRY_POINT_GROUP else []
    )

    def forget():
        for name in [n for n in sys.modules if n == PACKAGE or n.startswith(PACKAGE + ".")]:
            del sys.modules[name]

    def load():
        forget()
        return registry_module.default_registry()

    yield package, load
    forget()


def run(registry, cache):
    result = run_recipe(parse_recipe(RECIPE, registry, file="kitchen.yaml"), cache=cache)
    return result.status()["water"], float(result.output("water.table").columns["celsius"][0])


@pytest.mark.parametrize(
    "edited, reruns",
    [("heat.py", True), ("stove.py", True), ("boil.py", True), ("unrelated.py", False), ("__init__.py", False)],
)
def test_an_edit_to_the_code_a_node_runs_reruns_it(kitchen, tmp_path, edited, reruns):
    package, load = kitchen
    cache = Cache(tmp_path / "cache")
    assert run(load(), cache) == ("ran", 40.0)
    assert run(load(), cache) == ("cached", 40.0)
    (package / edited).write_text((package / edited).read_text() + "# edited\n")
    assert run(load(), cache)[0] == ("ran" if reruns else "cached")


def test_a_changed_helper_gives_the_new_result_not_the_cached_one(kitchen, tmp_path):
    package, load = kitchen
    cache = Cache(tmp_path / "cache")
    assert run(load(), cache) == ("ran", 40.0)
    (package / "stove.py").write_text("POWER = 30.0\n")  # no version bumped anywhere
    assert run(load(), cache) == ("ran", 80.0)


def test_imports_are_followed_inside_functions_relative_and_absolute_within_the_project(kitchen):
    _, load = kitchen
    load()
    found = project_modules(f"{PACKAGE}.boil", packages=set())
    assert sorted(found) == [f"{PACKAGE}.boil", f"{PACKAGE}.heat", f"{PACKAGE}.stove"]  # not nodegraph, numpy


def test_the_declared_version_still_enters_the_key(kitchen, tmp_path):
    package, load = kitchen
    cache = Cache(tmp_path / "cache")
    run(load(), cache)
    boil = package / "boil.py"
    boil.write_text(boil.read_text().replace('@node("boil", ', '@node("boil", version=2, '))
    assert run(load(), cache)[0] == "ran"
