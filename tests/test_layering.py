"""Imports point one way: no module of the engine imports one that imports it back (``executor`` and
``pool`` did), no module of the built-in nodes imports one that imports it back (``export.studio`` imported
``export.mitsuba_scene`` inside a function, which imports ``studio`` at its top), and no subpackage of the
built-in nodes imports one that imports it back (the simulation imported the Rerun loggers, which import the
simulation's value types). Every import counts, module-level or inside a function body."""

import ast
from pathlib import Path

import networkx as nx
import pytest

from nodegraph.code_digest import imported_modules

ROOT = Path(__file__).resolve().parents[1]


def import_graph(package: str, depth: int | None = None) -> nx.DiGraph:
    """Static imports between the modules of ``package`` (every import, function bodies included); with
    ``depth``, between its subpackages (module names cut to ``depth`` parts)."""
    graph = nx.DiGraph()
    for path in sorted((ROOT / package).rglob("*.py")):
        parts = path.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        cut = ".".join(name.split(".")[:depth])
        graph.add_node(cut)
        for target in imported_modules(name, path, {package}):
            target = ".".join(target.split(".")[:depth])
            if target != cut:
                graph.add_edge(cut, target)
    return graph


@pytest.mark.parametrize("package, depth", [("nodegraph", None), ("nodes", None), ("nodes", 2)])
def test_no_import_cycles(package, depth):
    cycles = sorted(" -> ".join([*cycle, cycle[0]]) for cycle in nx.simple_cycles(import_graph(package, depth)))
    assert not cycles, "imports that point both ways:\n" + "\n".join(cycles)


def test_no_engine_module_uses_another_objects_private_names():
    """``pool`` called ``executor._sources``: a private name is used only on ``self`` or ``cls``."""
    reaches = []
    for path in sorted((ROOT / "nodegraph").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            private = isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__")
            if private and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")):
                reaches.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    assert not reaches, "\n".join(reaches)
