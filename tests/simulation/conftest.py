"""Test setup for the xpbd node.

The shared scene builders (``xpbd_scenes``) are importable by name (pytest runs with --import-mode=importlib).
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
