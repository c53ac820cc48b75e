"""nodegraph: typed, cached, pull-based node graphs for procedural elastic aggregates."""

from .context import Context
from .errors import Issue, NodeFailure, NodegraphError, RecipeError
from .node import In, Moved, NodeSpec, Out, loads_libraries, node
from .params import Param

__version__ = "0.1.0"

__all__ = [
    "Context",
    "In",
    "Moved",
    "Issue",
    "NodeFailure",
    "NodeSpec",
    "NodegraphError",
    "Out",
    "Param",
    "RecipeError",
    "__version__",
    "loads_libraries",
    "node",
]
