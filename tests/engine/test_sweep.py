"""``nodegraph sweep``: a grid of runs over one cache, the recipe's own ``sweeps:`` block validated like
the rest of the recipe, the table, CSV and plot with the Pareto front, and the in-process pool."""

import csv
import sys
from pathlib import Path

import numpy as np
import pytest

from nodegraph.cache import Cache
from nodegraph.cli import main
from nodegraph.errors import RecipeError
from nodegraph.pool import SerialPool
from nodegraph.recipe import parse_recipe
from nodegraph.sweep import pareto_front, run_sweep, sweep_from_args

TOY = str(Path(__file__).with_name("toy_nodes.py"))
SWEEP_RECIPE = """\
name: toy_sweep
seed: 1
outputs: [merge.stats]
nodes:
  pts:
    type: toy_points
    variants: 2
    params: {count: 20}
  shift:
    type: toy_shift
    inputs: {spheres: pts.spheres}
  slow:
    type: toy_slow
    inputs: {spheres: shift.spheres}
  merge:
    type: toy_merge
    inputs: {parts: [slow.spheres, pts.spheres]}
sweeps:
  shift:
    doc: a toy study
    grid:
      shift.dx: [0.0, 1.0]
      pts.count: [20, 30]
    set: {slow.seconds: 0.0}
    metrics: [merge.stats.count:sum]
    outputs: [merge.spheres]
"""


@pytest.fixture
def sweep_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "toy_sweep.yaml"
    path.write_text(SWEEP_RECIPE)
    return path


def test_pareto_front_lower_is_better():
    assert pareto_front([1, 2, 3, 4], [4, 2, 3, 1]) == [True, True, False, True]
    assert pareto_front([1, None, 1], [1, 0, float("nan")]) == [True, False, False]
    assert pareto_front([1, 1], [2, 2]) == [True, True]  # equal points do not dominate each other


def test_sweeps_block_validated_with_file_line_column(registry):
    bad = SWEEP_RECIPE.replace("shift.dx: [0.0, 1.0]", "shift.dx: [0.0, 99.0]").replace(
        "pts.count: [20, 30]", "pts.cuont: [20, 30]\n      nowhere.x: [1]"
    )
    bad = bad.replace("metrics: [merge.stats.count:sum]", "metrics: [merge.spheres, merge.stats.count:median]")
    bad = bad.replace("doc: a toy study", "doc: a toy study\n    grdi: {}")
    with pytest.raises(RecipeError) as info:
        parse_recipe(bad, registry, file="s.yaml")
    text = str(info.value)
    issues = [str(i) for i in info.value.issues]
    assert len(issues) == 6, text
    assert issues[0].startswith("s.yaml:21:5: unknown key 'grdi'"), text  # and the rest is checked all the same
    assert issues[1].startswith("s.yaml:23:23: node 'shift', dx: out of range (given: 99.0)"), text
    assert issues[2].startswith("s.yaml:24:7: node 'pts': unknown parameter 'cuont'") and "'count'?" in issues[2]
    assert issues[3].startswith("s.yaml:25:7: no node 'nowhere' in the recipe"), text
    assert issues[4].startswith("s.yaml:27:15: 'merge.spheres' is not a Table"), text
    assert issues[5].startswith("s.yaml:27:30: unknown aggregate 'median'"), text


def test_recipe_sweep_runs_every_point_and_shares_the_cache(sweep_file, registry, tmp_path):
    recipe = parse_recipe(SWEEP_RECIPE, registry, file=str(sweep_file))
    decl = sweep_from_args(recipe, None, [], [], [])
    assert [p for p in decl.points()] == [
        {"shift.dx": 0.0, "pts.count": 20},
        {"shift.dx": 0.0, "pts.count": 30},
        {"shift.dx": 1.0, "pts.count": 20},
        {"shift.dx": 1.0, "pts.count": 30},
    ]
    cache = Cache(tmp_path / "cache")
    result = run_sweep(sweep_file, registry, decl, cache=cache)
    assert [p.metrics["merge.stats.count:sum"] for p in result.points] == [80, 120, 80, 120]
    assert [p.recipe_setting for p in result.points] == [True, False, False, False]
    assert result.common_instances == 0  # pts.count changes the root: nothing is common to every point
    # 2 pts + 2 shift + 2 slow + merge = 7 instances per point, all computed during the sweep (point 3's
    # pts[·] by point 1, with that time counted in both)
    assert [(p.ran, p.cached) for p in result.points] == [(7, 0)] * 4
    assert all(p.seconds is not None and p.seconds >= 0 for p in result.points)
    again = run_sweep(sweep_file, registry, decl, cache=cache)  # all cached: times come from the entries
    assert [(p.ran, p.cached) for p in again.points] == [(0, 7)] * 4
    assert [p.seconds for p in again.points] == pytest.approx([p.seconds for p in result.points], abs=1e-5)
    assert [p.digest for p in again.points] == [p.digest for p in result.points]
    assert len({p.digest for p in result.points}) == 4  # merge.spheres differs at every point
    assert set(result.points[0].hashes) == {"merge.stats", "merge.spheres"}


def test_serial_pool_matches_the_in_process_sweep(sweep_file, registry, tmp_path):
    decl = sweep_from_args(parse_recipe(SWEEP_RECIPE, registry, file=str(sweep_file)), None, [], [], [])
    plain = run_sweep(sweep_file, registry, decl, cache=Cache(tmp_path / "a"))
    pooled = run_sweep(sweep_file, registry, decl, cache=Cache(tmp_path / "b"), pool=SerialPool(), plugins=[TOY])
    assert [p.hashes for p in pooled.points] == [p.hashes for p in plain.points]
    assert [(p.ran, p.cached) for p in pooled.points] == [(p.ran, p.cached) for p in plain.points]


def test_cli_sweep_grid_writes_table_csv_and_plot(sweep_file, tmp_path, capsys):
    code = main(
        [
            "sweep",
            str(sweep_file),
            "--grid",
            "shift.dx=0,0.5,1",
            "--metric",
            "merge.stats.count:sum",
            "--set",
            "slow.seconds=0",
            "--cache-dir",
            str(tmp_path / "cache"),
            "--plugin",
            TOY,
            "-q",
        ]
    )
    assert code == 0
    out = tmp_path / "outputs" / "toy_sweep" / "sweeps"
    grid = "grid_shift.dx=0,0.5,1"  # named by its grid: another grid's sweep keeps its own files
    rows = list(csv.DictReader((out / f"{grid}.csv").open()))
    assert [r["shift.dx"] for r in rows] == ["0", "0.5", "1"]
    assert [r["recipe setting"] for r in rows] == ["yes", "", ""]
    assert all(r["merge.stats.count:sum"] == "80" for r in rows)
    assert int(rows[1]["ran"]) == 5 and int(rows[1]["cached"]) == 0  # shift, slow ×2, merge; pts is common
    text = (out / f"{grid}.md").read_text()
    assert "2 node instances common to every point" in text and "| **1** | **0** |" in text
    assert "merge.stats.count:sum is 80 at every point: it does not vary with this grid" in text  # said, not hidden
    assert main(["sweep", str(sweep_file), "--grid", "shift.dx=0,1", "--set", "slow.seconds=0", "-q", "--cache-dir",
                 str(tmp_path / "cache"), "--plugin", TOY]) == 0  # fmt: skip
    assert (out / f"{grid}.csv").exists() and (out / "grid_shift.dx=0,1.csv").exists()  # the first one kept
    pytest.importorskip("matplotlib")
    assert (out / f"{grid}.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_sweep_errors_exit_2(sweep_file, tmp_path, capsys):
    args = ["--cache-dir", str(tmp_path / "cache"), "--plugin", TOY]
    assert main(["sweep", str(sweep_file), "--grid", "shift.dx", *args]) == 2
    assert "--grid:1: cannot read 'shift.dx'" in capsys.readouterr().err
    assert main(["sweep", str(sweep_file), "--grid", "shift.dx=0,50", *args]) == 2
    err = capsys.readouterr().err
    assert "sweep point 2 (shift.dx=50): node 'shift', dx: out of range" in err
    assert main(["sweep", str(sweep_file), "--grid", "shift.dx=0", "--metric", "shift.spheres", *args]) == 2
    assert "--metric:1" in capsys.readouterr().err
    # a column a Table output declares is checked before any work too (it was found missing after every point ran)
    rice = str(Path(__file__).resolve().parents[2] / "graphs" / "rice_bowl.yaml")
    assert main(["sweep", rice, "--grid", "rice_sim.frames=1,2", "--metric", "measure.table.overlap_p9", *args]) == 2
    err = capsys.readouterr().err
    assert "--metric:1" in err and "has no column 'overlap_p9'" in err and "overlap_p95" in err
    assert main(["sweep", str(sweep_file), "--sweep", "nope", *args]) == 2
    assert "declares shift" in capsys.readouterr().err


def test_cli_sweep_rrd_holds_one_recording_per_point_with_its_id(sweep_file, registry, tmp_path, capsys):
    from rerun.chunk import RrdReader

    from nodegraph.executor import recording_id
    from nodegraph.recipe import load_recipe

    out = tmp_path / "sweeps"
    assert main(["sweep", str(sweep_file), "--plugin", TOY, "--out-dir", str(out), "-q", "--rrd"]) == 0
    assert "4 recordings, one per point" in capsys.readouterr().out
    rrd = out / "shift.rrd"  # --rrd without a path: beside the table, named after the sweep
    reader = RrdReader(str(rrd))
    found = {entry.recording_id for entry in reader.recordings()}
    expected = set()
    for dx in ("0.0", "1.0"):
        for count in ("20", "30"):
            overrides = ["slow.seconds=0.0", f"shift.dx={dx}", f"pts.count={count}"]
            expected.add(recording_id(load_recipe(sweep_file, registry, overrides)))
    assert len(expected) == 4 and found == expected
    for entry in reader.recordings():  # each point's recording is whole: its entities and the sim steps
        names = set(reader.stream(store=entry).collect().schema().entity_paths())
        assert {"/pts/0/spheres", "/shift/0/spheres", "/slow/0/log/energy", "/merge/spheres"} <= names, names
    again = tmp_path / "again.rrd"  # deterministic ids: the same sweep again gives the same recordings
    assert main(["sweep", str(sweep_file), "--plugin", TOY, "--out-dir", str(out), "-q", "--rrd", str(again)]) == 0
    assert {entry.recording_id for entry in RrdReader(str(again)).recordings()} == found
    assert not [p.name for p in out.iterdir() if "partial" in p.name or p.suffix == ".tmp"]


def test_a_metric_can_be_better_higher():
    from nodegraph.sweep import PointResult, SweepResult
    from nodegraph.sweep_decl import SweepDecl, parse_metric

    assert parse_metric("place.stats.elements:higher").higher and not parse_metric("m.t.error:max").higher
    assert parse_metric("place.stats.elements:max:higher").aggregate == "max"
    with pytest.raises(ValueError, match="higher"):
        parse_metric("m.t.c:better")
    points = [PointResult({}, (), s, 1, 0, {"n": n}, {}) for s, n in ((1.0, 100.0), (2.0, 200.0), (3.0, 150.0))]
    result = SweepResult("r", SweepDecl("s", (), (), (), ()), points, None, 0, 0.0, metric_names=["n"])
    assert result.front("n") == [True, False, False]  # read as an error, more elements look worse
    result.higher_better = {"n"}
    assert result.front("n") == [True, True, False]  # more elements are better: 200 for 2 s is on the front


def test_cli_sweep_lays_the_previews_out_on_a_contact_sheet(sweep_file, tmp_path):
    from PIL import Image as PILImage

    recipe = SWEEP_RECIPE.replace(
        "sweeps:", "  picture:\n    type: toy_picture\n    inputs: {spheres: shift.spheres}\nsweeps:"
    )
    sweep_file.write_text(recipe)
    args = ["sweep", str(sweep_file), "--grid", "shift.dx=0,1,2", "--output", "picture.image", "-q"]
    args += ["--metric", "merge.stats.count:sum:higher", "--cache-dir", str(tmp_path / "cache"), "--plugin", TOY]
    assert main(args) == 0
    out = tmp_path / "outputs" / "toy_sweep" / "sweeps"
    sheet = np.asarray(PILImage.open(out / "grid_shift.dx=0,1,2_picture_image.png"))
    assert sheet.shape[1] > 3 * 2 * 32 and sheet.shape[0] > 24  # three tiles (two variants each), captions
    reds = sorted({int(v) for v in sheet[8 + 12, :, 0]} - {255})  # the tiles' middle row, white gaps left out
    assert len(reds) == 6  # each point's own pictures (two variants each), not one repeated
    text = (out / "grid_shift.dx=0,1,2.md").read_text()
    sheet_name = "grid_shift.dx=0,1,2_picture_image.png"
    assert f"![{sheet_name}]({sheet_name})" in text and "merge.stats.count:sum ↑" in text


def test_a_sweep_without_matplotlib_says_it_drew_no_plot(sweep_file, tmp_path, capsys, monkeypatch):
    """Issue 47: the plot was skipped silently when matplotlib was missing."""
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed: its import fails
    args = ["sweep", str(sweep_file), "--grid", "shift.dx=0,1", "--metric", "merge.stats.count:sum"]
    args += ["--set", "slow.seconds=0", "--cache-dir", str(tmp_path / "cache"), "--plugin", TOY]
    assert main(args) == 0
    out = tmp_path / "outputs" / "toy_sweep" / "sweeps"
    assert not (out / "grid_shift.dx=0,1.png").exists()
    assert "no plot: matplotlib is not installed" in capsys.readouterr().err
    assert "no plot: matplotlib is not installed" in (out / "grid_shift.dx=0,1.md").read_text()


def test_a_draft_sweep_writes_beside_the_draft_runs_not_the_full_ones(sweep_file, tmp_path):
    """Issue 47: ``--draft`` sweeps wrote into the full run's sweeps folder, mixing draft and full contact sheets."""
    sweep_file.write_text(SWEEP_RECIPE.replace("sweeps:", "draft: {pts.count: 5}\nsweeps:", 1))
    args = ["sweep", str(sweep_file), "--cache-dir", str(tmp_path / "cache"), "--plugin", TOY, "-q"]
    assert main([*args, "--draft"]) == 0
    assert (tmp_path / "outputs" / "toy_sweep_draft" / "sweeps" / "shift.csv").is_file()
    assert not (tmp_path / "outputs" / "toy_sweep").exists()
