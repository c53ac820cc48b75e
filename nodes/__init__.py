"""Built-in node types, one subpackage per step family; found by ``nodegraph.registry``."""

import nodegraph  # noqa: F401  (points numba's cache at this source state before any kernel module loads)
