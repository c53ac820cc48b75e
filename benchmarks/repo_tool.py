"""A script of ``tools/`` loaded from its file, for benchmarks run as ``python benchmarks/NAME.py``: ``tools`` is no
package on their path (the repository root is not on it), and sys.path is left as it is."""

import importlib.util
from pathlib import Path
from types import ModuleType

TOOLS = Path(__file__).resolve().parents[1] / "tools"


def load_tool(name: str) -> ModuleType:
    """``tools/<name>.py`` as a module."""
    spec = importlib.util.spec_from_file_location(name, TOOLS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
