"""The installed node packages, by their entry points (group ``nodegraph.nodes``), without importing any: what the
registry loads and what the kernel cache, the code digests and the shipped kernels treat as the project's code. A
leaf module, so that the modules ``runtime`` sets up can ask for the names without importing the registry."""

from __future__ import annotations

from importlib.metadata import entry_points

ENTRY_POINT_GROUP = "nodegraph.nodes"


def node_package_names() -> list[str]:
    """Top-level module names of the installed node packages (entry points; nothing is imported)."""
    return sorted({ep.value.split(":")[0].split(".")[0] for ep in entry_points(group=ENTRY_POINT_GROUP)})


def project_packages() -> set[str]:
    """The project's code: the installed node packages and the engine."""
    return set(node_package_names()) | {"nodegraph"}
