"""Node types come from the built-in package, entry points and plugin files, with no global state."""

import sys
import textwrap
from importlib.metadata import EntryPoint

import pytest

from nodegraph import node_packages
from nodegraph import registry as registry_module
from nodegraph.errors import NodeDeclarationError
from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh, Table

PLUGIN = textwrap.dedent('''
    from nodegraph import Out, Param, node
    from nodegraph.values import Table
    import numpy as np

    @node("user_constant", outputs={"table": Out(Table, "one value")},
          params={"value": Param(float, 1.0, "the value", range=(0, 10))})
    def user_constant(ctx, *, value):
        """A user's node: a one-row table."""
        return Table({"value": np.array([value])})
''')


def test_entry_point_package_is_scanned_through_its_init(tmp_path, monkeypatch):
    package = tmp_path / "my_food_nodes"
    (package / "sub").mkdir(parents=True)
    (package / "sub" / "consts.py").write_text(PLUGIN)
    (package / "sub" / "__init__.py").write_text("from .consts import user_constant\n")
    (package / "__init__.py").write_text("")
    (package / "unrelated_kernel.py").write_text(
        "raise RuntimeError('kernel modules are not imported to list nodes')\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    fake = [EntryPoint("mine", "my_food_nodes", registry_module.ENTRY_POINT_GROUP)]
    for module in (registry_module, node_packages):  # the registry loads them, node_package_names names them
        monkeypatch.setattr(
            module, "entry_points", lambda group: fake if group == node_packages.ENTRY_POINT_GROUP else []
        )
    reg = registry_module.default_registry()
    assert "user_constant" in reg
    sys.modules.pop("my_food_nodes", None)


def test_plugin_file(tmp_path):
    path = tmp_path / "plug.py"
    path.write_text(PLUGIN)
    reg = registry_module.default_registry(plugins=[path], entry_point_modules=False)
    assert reg["user_constant"].params["value"].range == (0, 10)


def test_duplicate_type_names_are_refused(tmp_path):
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text(PLUGIN)
    b.write_text(PLUGIN)
    with pytest.raises(NodeDeclarationError, match="declared twice"):
        registry_module.default_registry(plugins=[a, b], entry_point_modules=False)


def test_declaration_errors_are_caught_when_declared():
    with pytest.raises(NodeDeclarationError, match="both as input and parameter"):
        node("bad", inputs={"x": In(Mesh)}, outputs={"y": Out(Mesh)}, params={"x": Param(int, 1)})(lambda ctx, x: x)
    with pytest.raises(NodeDeclarationError, match="lacks arguments"):
        node("bad", inputs={"mesh": In(Mesh)}, outputs={"y": Out(Table)})(lambda ctx: None)
