"""Test setup for the xpbd node.

numba's workqueue threading layer: OpenMP collapsed on this 2-core machine when the other core was
busy (ENVIRONMENT.md); it must be set before the first parallel kernel runs. The shared scene
builders (``xpbd_scenes``) are importable by name (pytest runs with --import-mode=importlib).
"""

import sys
from pathlib import Path

import numba

numba.config.THREADING_LAYER = "workqueue"
sys.path.insert(0, str(Path(__file__).parent))
