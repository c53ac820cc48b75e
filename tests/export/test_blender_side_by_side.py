"""``tools/blender_side_by_side.py`` says what it does: without the Blender venv, or with a Python that has no bpy,
a clear error that names where it looked and how to make one, before the recipe runs (issue 47: it ran the recipe
for minutes, then failed with bpy's traceback)."""

import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("python", ["/nonexistent/bin/python", sys.executable], ids=["missing", "without bpy"])
def test_a_missing_blender_venv_is_named_before_anything_runs(python, tmp_path):
    env = {"NODEGRAPH_BLENDER_PYTHON": python, "PATH": "/usr/bin:/bin", "PYTHONPATH": str(REPO)}
    done = subprocess.run(
        [sys.executable, str(REPO / "tools" / "blender_side_by_side.py"), str(REPO / "graphs" / "rice_bowl.yaml")],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=60,
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("error: ") and python in done.stderr
    assert "tools/make_blender_venv.sh" in done.stderr and "Traceback" not in done.stderr
    assert "1/3" not in done.stderr  # the recipe never started
