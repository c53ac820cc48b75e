"""A node's cache key covers the code it runs: editing a helper module it imports (inside its function,
relative or absolute, at any depth) re-runs it; editing a module it does not import does not."""

import ast
import os
import subprocess
import sys
import textwrap
import time
import weakref
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest

from nodegraph import code_digest, node_packages
from nodegraph import registry as registry_module
from nodegraph.cache import Cache
from nodegraph.code_digest import import_statements, project_modules
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
    for module in (registry_module, node_packages):  # the registry loads them, node_package_names names them
        monkeypatch.setattr(
            module, "entry_points", lambda group: fake if group == node_packages.ENTRY_POINT_GROUP else []
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


@pytest.fixture
def new_process(monkeypatch):
    """Forget the digests made in this process and remember none across processes, so that an edit to an engine
    module (already loaded, its digest made once per process) is seen as a new process would see it."""
    monkeypatch.setenv(code_digest.MEMORY_ENV_VAR, "off")
    monkeypatch.setattr(code_digest, "_MEMORY", None)

    def forget():
        monkeypatch.setattr(code_digest, "_DIGESTS", weakref.WeakKeyDictionary())

    forget()
    return forget


@pytest.mark.parametrize(
    "library, reruns",
    [("numpy", True), ("scipy", False)],  # boil imports numpy, not scipy
)
def test_a_library_upgrade_reruns_the_nodes_that_import_it(kitchen, tmp_path, monkeypatch, library, reruns):
    _, load = kitchen
    cache = Cache(tmp_path / "cache")
    assert run(load(), cache) == ("ran", 40.0)
    installed = dict(code_digest.installed_distributions())
    assert installed[library] and "numpy" in code_digest.node_libraries(load()["boil"])
    installed[library] = [f"{library}==999.0"]
    monkeypatch.setattr(code_digest, "_INSTALLED", installed)
    assert run(load(), cache)[0] == ("ran" if reruns else "cached")


@pytest.mark.parametrize(
    "module, reruns",
    [
        ("nodegraph.values", True),  # boil imports it
        ("nodegraph.node", True),  # through ``from nodegraph import node``
        ("nodegraph.codec", True),  # every node's outputs are stored through it (ENGINE_ROOTS)
        ("nodegraph.cli", False),  # decides nothing about a result
    ],
)
def test_an_edit_to_the_engine_reruns_the_nodes_whose_results_it_decides(
    kitchen, tmp_path, monkeypatch, new_process, module, reruns
):
    _, load = kitchen
    __import__(module)
    copy = tmp_path / "engine" / Path(sys.modules[module].__file__).name
    copy.parent.mkdir()
    copy.write_bytes(Path(sys.modules[module].__file__).read_bytes())
    monkeypatch.setattr(sys.modules[module], "__file__", str(copy))
    cache = Cache(tmp_path / "cache")
    assert run(load(), cache) == ("ran", 40.0)
    new_process()
    assert run(load(), cache)[0] == "cached"
    copy.write_text(copy.read_text() + "# edited\n")
    new_process()
    assert run(load(), cache)[0] == ("ran" if reruns else "cached")


def test_the_libraries_installed_are_remembered_across_processes(memory, monkeypatch, tmp_path):
    """Reading every distribution's metadata takes ≈ 0.4 s: a new process reads the answer remembered for its
    sys.path (one record per sys.path: the CLI's and python -c's differ), unless a folder on it changed (a
    distribution installed, upgraded or removed)."""
    import importlib.metadata

    real = importlib.metadata.packages_distributions
    reads = []
    monkeypatch.setattr(importlib.metadata, "packages_distributions", lambda: reads.append(1) or real())

    def new_process(search_path):
        monkeypatch.setattr(sys, "path", search_path)
        monkeypatch.setattr(code_digest, "_INSTALLED", None)
        memory()
        return code_digest.installed_distributions()

    path = list(sys.path)
    first = new_process(path)
    assert any(item.startswith("numpy==") for item in first["numpy"]) and len(reads) == 1
    assert new_process(path) == first and len(reads) == 1
    other = tmp_path / "site"
    other.mkdir()
    new_process([str(other), *path])
    assert new_process(path) == first and new_process([str(other), *path]) and len(reads) == 2
    info = other / "pepper-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: pepper\nVersion: 1.0\n")
    (info / "top_level.txt").write_text("pepper\n")
    assert new_process([str(other), *path])["pepper"] == ["pepper==1.0"] and len(reads) == 3


TRICKY = b'''
import a.b as c, d
from . import e
from .f import (g,  # a comment with ) in it
    h)
from..i import j
if x: import k
try: import l
except ImportError: pass
x = 1; import m
def f():
    from n import \\
        o
    class C:
        import p
match v:
    case 1: import q
text = """
from r import s
"""
'''


def every_import(source: bytes) -> set:
    """The reference: every import node of the whole syntax tree."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update((alias.name, ()) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            found.add(("." * node.level + (node.module or ""), tuple(alias.name for alias in node.names)))
    return found


@pytest.mark.parametrize("where", ["tricky", "repository"])
def test_the_import_scan_finds_every_import_of_the_syntax_tree(where):
    root = Path(__file__).resolve().parents[2]
    files = [
        p for folder in ("nodegraph", "nodes", "tests", "benchmarks", "tools") for p in (root / folder).rglob("*.py")
    ]
    sources = [TRICKY] if where == "tricky" else [p.read_bytes() for p in sorted(files)]
    for source in sources:
        missed = every_import(source) - import_statements(source)
        assert not missed  # an import in a string may add a module; a real one is never dropped
    assert ("r", ("s",)) in import_statements(TRICKY) and len(every_import(TRICKY)) == 11


def test_an_installed_plugin_package_reruns_after_its_helper_is_edited(tmp_path):
    """End to end, as a user meets it: a package installed with an entry point (its dist-info on the path),
    run by the command line in a new process each time."""
    site = tmp_path / "site"
    (site / PACKAGE).mkdir(parents=True)
    for name, text in FILES.items():
        (site / PACKAGE / name).write_text(textwrap.dedent(text))
    info = site / f"{PACKAGE}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {PACKAGE}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{registry_module.ENTRY_POINT_GROUP}]\nkitchen = {PACKAGE}\n")
    (tmp_path / "kitchen.yaml").write_text(RECIPE)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(site), os.environ.get("PYTHONPATH")]))}
    cache = tmp_path / "cache"

    def entries_after_a_run() -> int:
        command = [sys.executable, "-m", "nodegraph.cli", "run", "kitchen.yaml", "--cache-dir", str(cache), "-q"]
        subprocess.run([*command, "--no-rrd"], cwd=tmp_path, env=env, check=True)
        return len(list(cache.glob("entries/*/*.json")))

    assert entries_after_a_run() == 1
    (site / PACKAGE / "unrelated.py").write_text("SALT = 2.0\n")
    assert entries_after_a_run() == 1  # cached: the node does not import it
    (site / PACKAGE / "stove.py").write_text("POWER = 30.0\n")
    assert entries_after_a_run() == 2  # ran again: a module its helper imports changed


@pytest.fixture
def memory(tmp_path, monkeypatch):
    """Digests remembered in a file of the test's own; files count as settled at once (``RACY_S`` 0)."""
    monkeypatch.setenv(code_digest.MEMORY_ENV_VAR, str(tmp_path / "digests.json"))
    monkeypatch.setattr(code_digest, "RACY_S", 0.0)
    monkeypatch.setattr(code_digest, "_MEMORY", None)

    def next_process():
        """As a new process meets it: nothing in memory but the file, and no source may be read."""
        code_digest._MEMORY = None
        code_digest._PARSED.clear()

    return next_process


def digest_reading(monkeypatch) -> tuple[str, int]:
    """The boil node's digest and how many source files computing it read."""
    reads = []
    parse = code_digest._parse
    monkeypatch.setattr(code_digest, "_parse", lambda path: reads.append(path) or parse(path))
    found = code_digest._digest(f"{PACKAGE}.boil", {PACKAGE})
    monkeypatch.setattr(code_digest, "_parse", parse)
    return found, len(set(reads))


def test_a_new_process_reads_no_source_of_unchanged_code_and_rereads_changed_code(kitchen, memory, monkeypatch):
    package, load = kitchen
    load()
    first, reads = digest_reading(monkeypatch)
    assert reads == 3  # boil, heat, stove
    memory()
    assert digest_reading(monkeypatch) == (first, 0)
    (package / "stove.py").write_text("POWER = 30.0\n")  # same size as before: the stamp's times tell
    memory()
    edited, reads = digest_reading(monkeypatch)
    assert edited != first and reads == 3


def test_a_module_added_beside_the_code_is_read_again(kitchen, memory, monkeypatch):
    """``from . import heat`` may name a new module ``heat.py`` or a package's attribute: a folder that gains a
    file is read again."""
    package, load = kitchen
    load()
    first, _ = digest_reading(monkeypatch)
    (package / "spices.py").write_text("PEPPER = 1\n")
    memory()
    assert digest_reading(monkeypatch) == (first, 3)


def test_a_file_written_just_now_is_not_remembered(kitchen, memory, monkeypatch):
    """Two writes within one timestamp tick look alike: a file younger than ``RACY_S`` is read each time."""
    _, load = kitchen
    load()
    monkeypatch.setattr(code_digest, "RACY_S", 60.0)
    digest_reading(monkeypatch)
    memory()
    assert digest_reading(monkeypatch)[1] == 3


def test_bytes_read_soon_after_a_change_are_not_remembered_however_late_the_digest(kitchen, memory, monkeypatch):
    """A long-lived process (a watch) may hold bytes it read within a timestamp tick of a write: a second write
    in that tick leaves the stamp as it was, so those bytes must not be remembered for other processes, even
    when the digest is made long after (the guard once looked at the clock when storing, not when reading)."""
    package, load = kitchen
    load()
    monkeypatch.setattr(code_digest, "RACY_S", 1.0)
    code_digest._parse(package / "stove.py")  # read within a second of the fixture's write
    time.sleep(1.2)
    digest_reading(monkeypatch)  # stove's bytes come from the read above
    memory()
    assert digest_reading(monkeypatch)[1] == 3


def test_a_change_to_how_digests_are_made_voids_the_remembered_ones(kitchen, memory, monkeypatch, tmp_path):
    """A record made by another version of the digest scheme (which may have followed fewer imports) is not used."""
    _, load = kitchen
    load()
    scheme = tmp_path / "scheme.py"
    scheme.write_text("VERSION = 1\n")
    monkeypatch.setattr(code_digest, "__file__", str(scheme))
    first, _ = digest_reading(monkeypatch)
    memory()
    assert digest_reading(monkeypatch) == (first, 0)
    scheme.write_text("VERSION = 2\n")
    memory()
    assert digest_reading(monkeypatch) == (first, 3)
