"""Built-in node types, one subpackage per step family; found by ``nodegraph.registry``."""
