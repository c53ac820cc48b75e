"""Every benchmark still imports against today's code (nothing else runs them; one rotted unnoticed), and as
``python benchmarks/NAME.py`` runs it: its own folder first on the path, the repository root not on it."""

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

import pytest

BENCHMARKS = sorted((Path(__file__).resolve().parents[2] / "benchmarks").glob("*.py"))
HELPERS = {"machine", "scene_builders", "repo_tool"}  # sibling modules the benchmarks import, with no main of their own


@pytest.mark.parametrize("path", BENCHMARKS, ids=[p.stem for p in BENCHMARKS])
def test_benchmark_imports(path, monkeypatch):
    monkeypatch.syspath_prepend(str(path.parent))  # benchmarks import their sibling helpers (HELPERS)
    spec = importlib.util.spec_from_file_location(f"benchmark_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    if path.stem not in HELPERS:  # a helper loads from its file alone, as a script or a checker loads it
        monkeypatch.setitem(sys.modules, spec.name, module)
    spec.loader.exec_module(module)
    assert hasattr(module, "main") or path.stem in HELPERS


def test_every_benchmark_imports_as_its_command_runs_it():
    # thin_wall.py imported ``tools.vessel_check``, which only a PYTHONPATH holding the root found (pytest's does,
    # so the test above passed): ``repo_tool.load_tool`` loads a tool from its file
    code = (
        "import importlib, pathlib\n"
        "for path in sorted(pathlib.Path('.').glob('*.py')):\n"
        "    try:\n"
        "        importlib.import_module(path.stem)\n"
        "    except Exception as error:\n"
        "        print(f'{path.name}: {type(error).__name__}: {error}')\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=BENCHMARKS[0].parent, env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert not done.stdout.strip(), done.stdout
