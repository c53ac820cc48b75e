"""Every benchmark still imports against today's code (nothing else runs them; one rotted unnoticed)."""

import importlib.util
import sys
from pathlib import Path

import pytest

BENCHMARKS = sorted((Path(__file__).resolve().parents[2] / "benchmarks").glob("*.py"))
HELPERS = {"machine", "scene_builders"}  # sibling modules the benchmarks import, with no main of their own


@pytest.mark.parametrize("path", BENCHMARKS, ids=[p.stem for p in BENCHMARKS])
def test_benchmark_imports(path, monkeypatch):
    monkeypatch.syspath_prepend(str(path.parent))  # benchmarks import their sibling helpers (HELPERS)
    spec = importlib.util.spec_from_file_location(f"benchmark_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    if path.stem not in HELPERS:  # a helper loads from its file alone, as a script or a checker loads it
        monkeypatch.setitem(sys.modules, spec.name, module)
    spec.loader.exec_module(module)
    assert hasattr(module, "main") or path.stem in HELPERS
