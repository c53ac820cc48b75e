"""Find node types: the packages of the ``nodegraph.nodes`` entry points (the built-in ones included,
registered by the project's own pyproject), then plugin files.

Every source is a plain module (or package of modules) whose ``NodeSpec`` attributes are node
types, as pytest finds plugins; the registry is an ordinary object built per command, not global.
"""

from __future__ import annotations

import importlib
import importlib.util
import pkgutil
import sys
from collections.abc import Iterable
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType

from .errors import NodeDeclarationError, NodegraphError
from .node import NodeSpec
from .node_packages import ENTRY_POINT_GROUP


class Registry:
    """Node types by name."""

    def __init__(self, specs: Iterable[NodeSpec] = ()):
        self._specs: dict[str, NodeSpec] = {}
        for spec in specs:
            self.add(spec)

    def add(self, spec: NodeSpec) -> None:
        existing = self._specs.get(spec.type_name)
        if existing is not None and existing is not spec:
            raise NodeDeclarationError(
                f"node type '{spec.type_name}' is declared twice: in {existing.module} and in {spec.module}"
            )
        self._specs[spec.type_name] = spec

    def add_module(self, module: ModuleType) -> None:
        """Register every NodeSpec in the module's namespace that was declared in it or below it.

        A package's ``__init__`` re-exports its node types, so kernel modules are never imported
        just to list nodes (``nodegraph nodes`` stays fast).
        """
        prefix = module.__name__
        for value in vars(module).values():
            if isinstance(value, NodeSpec) and (value.module == prefix or value.module.startswith(prefix + ".")):
                self.add(value)

    def add_package(self, package: ModuleType) -> None:
        """Register a module, or a package and its sub-packages (each exposing its nodes in ``__init__``)."""
        self.add_module(package)
        if hasattr(package, "__path__"):
            for info in pkgutil.iter_modules(package.__path__, prefix=package.__name__ + "."):
                if info.ispkg:
                    self.add_package(importlib.import_module(info.name))

    def add_plugin_file(self, path: str | Path) -> None:
        """Load a user's node module from a .py file (``--plugin path.py``)."""
        path = Path(path).resolve()
        if not path.is_file():
            raise NodegraphError(f"plugin file not found: {path}")
        name = f"nodegraph_plugin_{path.stem}"
        loaded = sys.modules.get(name)
        if loaded is not None and getattr(loaded, "__file__", None) == str(path):
            # once per process: a second import would make new value classes that stored values
            # of the first (cache entries, outputs in memory) are no longer instances of
            self.add_module(loaded)
            return
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or spec.loader is None:
            raise NodegraphError(f"cannot import plugin {path}: not a Python module")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclass values defined in a plugin must be importable by name
        spec.loader.exec_module(module)
        self.add_module(module)

    def __contains__(self, name: str) -> bool:
        return name in self._specs

    def __getitem__(self, name: str) -> NodeSpec:
        return self._specs[name]

    def get(self, name: str) -> NodeSpec | None:
        return self._specs.get(name)

    def names(self) -> list[str]:
        return sorted(self._specs)

    def specs(self) -> list[NodeSpec]:
        return [self._specs[n] for n in self.names()]

    def effects(self) -> set[str]:
        return {e for spec in self._specs.values() for e in spec.effects}


def default_registry(plugins: Iterable[str | Path] = (), entry_point_modules: bool = True) -> Registry:
    """Installed node packages (entry points, the built-in ones among them), then ``--plugin`` files; numba's
    kernel cache is configured first (``runtime.configure``): a module that decorates a kernel as it is imported
    gets the project's cache and locator."""
    from . import runtime

    runtime.configure()
    registry = Registry()
    if entry_point_modules:
        loaded: set[str] = set()
        for ep in sorted(entry_points(group=ENTRY_POINT_GROUP), key=lambda ep: ep.value):
            if ep.value not in loaded:
                registry.add_package(ep.load())
                loaded.add(ep.value)
    for plugin in plugins:
        registry.add_plugin_file(plugin)
    return registry
