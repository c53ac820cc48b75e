"""A cached re-run loads what reading the cache needs and nothing a computation needs (issue 27: ≤ 1.5 s): no
geometry, kernel, recording or rendering library, and no sweep declarations for a recipe that has none."""

import subprocess
import sys

from module_listing import RUN_AND_LIST

from .test_cli_and_rerun import RECIPE, TOY

# what a computation or a sweep brings in; each costs 0.1–2 s of a process start
NOT_FOR_A_CACHED_RUN = [
    "trimesh",
    "scipy",
    "numba",
    "rerun",
    "pyarrow",
    "mitsuba",
    "pxr",
    "pandas",
    "nodegraph.sweep_decl",
    "rich.progress",
]


def test_a_cached_rerun_imports_no_library_a_computation_needs(tmp_path):
    recipe = tmp_path / "toy.yaml"
    recipe.write_text(RECIPE)
    args = ["--plugin", TOY, "--cache-dir", str(tmp_path / "cache"), "--out-dir", str(tmp_path / "out"), "-q"]
    command = [sys.executable, "-c", RUN_AND_LIST, str(recipe), *args]
    subprocess.run(command, cwd=tmp_path, check=True, capture_output=True)  # computes and records
    loaded = set(subprocess.run(command, cwd=tmp_path, check=True, capture_output=True, text=True).stdout.split())
    assert "nodegraph.cache" in loaded  # the listing is of the run's process
    assert [m for m in NOT_FOR_A_CACHED_RUN if m in loaded] == []
