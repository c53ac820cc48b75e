"""The distance-field node's cache key covers its kernels: they are imported inside the node function."""

from nodegraph.code_digest import project_modules
from nodegraph.registry import default_registry


def test_the_distance_field_node_is_keyed_on_the_kernel_module_it_imports():
    spec = default_registry()["distance_field"]
    found = project_modules(spec.module)
    assert {"nodes.elements.distance_field", "nodes.elements.distance_fields", "nodes.values"} <= set(found)
    assert "nodes.simulation.solver" not in found  # only what it imports
