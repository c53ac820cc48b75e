"""Built-in node types, one subpackage per step family; registered through the ``nodegraph.nodes``
entry point like any plugin package. Importing the package also registers how its value types
(``values``) are logged to Rerun (``rerun_loggers``) and written as outputs (``output_writers``)."""

import nodegraph  # noqa: F401  (points numba's cache at this source state before any kernel module loads)

from . import output_writers, rerun_loggers  # noqa: F401  (registrations on the engine's dispatchers)
