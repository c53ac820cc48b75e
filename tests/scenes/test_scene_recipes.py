"""Issue 17's scenes run at reduced sizes through ``--set`` overrides: each recipe's element count and
the mesh-level quality its ``measure`` node reports. The bounds are what the short method reaches today
(see the benchmark, ``benchmarks/bench_scenes.py``); issue 17's targets (p95 ≤ 3 %, max ≤ 10 % of the
element length) are checked as expected failures so that meeting them shows up as an XPASS."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

REPO = Path(__file__).resolve().parents[2]


def _quick_sizes() -> dict[str, list[str]]:
    """The benchmark's reduced sizes: one list of overrides per recipe, shared by both."""
    path = REPO / "benchmarks" / "bench_scenes.py"
    spec = importlib.util.spec_from_file_location("bench_scenes_sizes", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.QUICK


QUICK = _quick_sizes()


_ROWS: dict[str, dict[str, float]] = {}


def _quick_row(recipe_name: str, tmp_path_factory) -> dict[str, float]:
    """The measure row of a recipe at its reduced size, run once per session."""
    if recipe_name not in _ROWS:
        _ROWS[recipe_name] = _measure(recipe_name, tmp_path_factory.mktemp(recipe_name))
    return _ROWS[recipe_name]


def _measure(recipe_name: str, tmp_path, extra=()) -> dict[str, float]:
    recipe = load_recipe(REPO / "graphs" / f"{recipe_name}.yaml", default_registry(), QUICK[recipe_name] + list(extra))
    result = run_recipe(recipe, cache=Cache(tmp_path / "cache"), out_dir=tmp_path / "out")
    assert "preview.png" in {p.name for p in result.files}
    return {k: float(v[0]) for k, v in result.output("measure.table").columns.items()}


# Per recipe at its reduced size: (fewest, most) elements and the most overlap (p95, max, in element lengths)
# measured today with some room; issue 17's target is p95 ≤ 0.03, max ≤ 0.10 (below, as expected failures).
EXPECTED = {
    "rice_bowl": ((90, 150), 0.22, 0.32),  # 118 grains: p95 0.167, max 0.241
    "ikura_don": ((140, 220), 0.17, 0.20),  # 179 elements: p95 0.120, max 0.139
    "onigiri": ((45, 75), 0.21, 0.29),  # 60 grains: p95 0.157, max 0.216
    "sushi": ((65, 110), 0.21, 0.26),  # 87 grains: p95 0.161, max 0.195
    "kakigori": ((220, 350), 0.06, 0.07),  # 283 flakes: p95 0.039, max 0.049
    "rice_chestnut": ((200, 340), 0.10, 0.13),  # 268 elements: p95 0.077, max 0.096 (S: no physics)
}
SLOW: set[str] = set()  # each runs in 2–7 s on a calm machine (rice_chestnut, the slowest: 18 s at load 10)


@pytest.mark.parametrize(
    "recipe_name",
    [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in sorted(EXPECTED)],
)
def test_scene_at_reduced_size_counts_and_quality(recipe_name, tmp_path_factory):
    row = _quick_row(recipe_name, tmp_path_factory)
    (low, high), p95, deepest = EXPECTED[recipe_name]
    assert low <= row["elements"] <= high
    assert row["overlap_p95"] <= p95 and row["overlap_max"] <= deepest
    assert row["contacts_per_element"] > 0.5 and 0.05 < row["packing_fraction"] < 1.0


@pytest.mark.xfail(
    strict=True,
    reason="issue 17's target (p95 ≤ 3 %, max ≤ 10 %) is not met after XPBD: the clusters' spheres now reach the "
    "surface (nodes/simulation/clusters.py), but the relaxed pile still rests ≈ 10–15 % of a length deep in its "
    "neighbours' meshes (the solver's tolerated contact overlap under the pile's weight); a mesh-level pass on the "
    "element distance fields (branch overlap-pass) met it on a 118-grain bowl but did not converge in time on "
    "the 2,087-grain one",
)
def test_rice_bowl_meets_the_overlap_target(tmp_path_factory):
    row = _quick_row("rice_bowl", tmp_path_factory)
    assert row["overlap_p95"] <= 0.03 and row["overlap_max"] <= 0.10


@pytest.mark.slow
def test_sushi_full_method_runs(tmp_path):
    row = _measure("sushi", tmp_path, ["press.mode=full", "press.frames=30"])
    assert 65 <= row["elements"] <= 110
