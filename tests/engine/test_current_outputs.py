"""A cached re-run whose files are still as the last run left them writes nothing (issue 27: cached re-run
≤ 1.5 s); anything that could change a byte of them (a setting, a touched file, the writers' code, the
recording asked for or not) writes them again."""

import os
from pathlib import Path

import pytest

import nodegraph.executor
from nodegraph.cache import Cache
from nodegraph.executor import run_recipe
from nodegraph.recipe import load_recipe

from .test_cli_and_rerun import RECIPE, TOY, cli


@pytest.fixture
def recipe(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("NODEGRAPH_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "toyrun.yaml"
    path.write_text(RECIPE)
    return path


def stamps(folder):
    """Each file's (inode, modification time): a rewrite (atomic: a new file renamed in) changes both."""
    return {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in sorted(folder.iterdir())}


def test_a_cached_rerun_with_current_outputs_writes_nothing(recipe, tmp_path, capsys):
    out = tmp_path / "outputs" / "toyrun"
    assert cli("run", str(recipe)) == 0
    first = stamps(out)
    assert {"merge.spheres.npz", "surf.ply", "toyrun.rrd", "manifest.json"} <= set(first)
    capsys.readouterr()
    assert cli("run", str(recipe)) == 0
    assert stamps(out) == first  # outputs, recording and manifest untouched
    captured = capsys.readouterr()
    assert "wrote" not in captured.out and "up to date:" in captured.out and "toyrun.rrd" in captured.out
    assert "cached" in captured.err and "ran" not in captured.err.replace("nodegraph run", "")


def test_a_setting_an_edited_file_or_other_writers_write_again(recipe, tmp_path, monkeypatch):
    out = tmp_path / "outputs" / "toyrun"
    assert cli("run", str(recipe)) == 0
    surf = (out / "surf.ply").read_bytes()

    (out / "surf.ply").write_bytes(b"edited by hand")  # a file changed since: written again
    assert cli("run", str(recipe)) == 0
    assert (out / "surf.ply").read_bytes() == surf

    before = stamps(out)
    os.utime(out / "toyrun.rrd", ns=(0, 0))  # the recording touched: the run writes files and recording again
    assert cli("run", str(recipe)) == 0
    assert stamps(out)["toyrun.rrd"] != before["toyrun.rrd"] and stamps(out)["surf.ply"] != before["surf.ply"]

    before = stamps(out)
    assert cli("run", str(recipe), "--set", "phys.dt=0.5", "--out-dir", str(out)) == 0  # another setting
    assert stamps(out)["surf.ply"] != before["surf.ply"]

    before = stamps(out)
    monkeypatch.setattr(nodegraph.executor, "dispatch_digest", lambda *a: "other writers")
    assert cli("run", str(recipe), "--set", "phys.dt=0.5", "--out-dir", str(out)) == 0
    assert stamps(out)["surf.ply"] != before["surf.ply"]

    before = stamps(out)
    assert cli("run", str(recipe), "--set", "phys.dt=0.5", "--out-dir", str(out), "--no-rrd") == 0
    assert stamps(out)["surf.ply"] != before["surf.ply"]  # the manifest no longer vouches for a recording


def test_a_reused_result_still_gives_its_values(recipe, tmp_path):
    from nodegraph.registry import default_registry

    loaded = load_recipe(recipe, default_registry(plugins=[TOY]))
    cache, out = Cache(tmp_path / "cache"), tmp_path / "out"
    first = run_recipe(loaded, cache=cache, out_dir=out)
    again = run_recipe(loaded, cache=cache, out_dir=out)
    assert again.values == {} and again.files == first.files  # nothing loaded, nothing written
    assert (again.output("surf").vertices == first.output("surf").vertices).all()  # loaded when asked


def test_outputs_of_other_settings_never_sit_beside_a_run(recipe, tmp_path, capsys):
    """Issue 47: ``--output surf`` rewrote surf but left the merged spheres of an earlier, different run beside it."""
    import json

    out = tmp_path / "outputs" / "toyrun"
    assert cli("run", str(recipe), "--no-rrd") == 0
    (out / "notes.txt").write_text("mine")
    capsys.readouterr()
    # the same settings, one output asked for: the other is still this setting's, kept and listed as earlier
    assert cli("run", str(recipe), "--no-rrd", "--output", "surf") == 0
    err = capsys.readouterr().err
    assert (out / "merge.spheres.npz").exists() and "merge.spheres.npz" not in err
    assert "notes.txt" in err  # not nodegraph's: left, and said
    manifest = json.loads((out / "manifest.json").read_text())
    assert set(manifest["files"]) == {"surf.ply"} and set(manifest["earlier"]) == {"merge.spheres.npz"}
    # other settings: the earlier outputs go, and the run says so
    assert cli("run", str(recipe), "--no-rrd", "--output", "surf", "--set", "pts.count=9", "--out-dir", str(out)) == 0
    err = capsys.readouterr().err
    assert not (out / "merge.spheres.npz").exists() and (out / "surf.ply").exists() and (out / "notes.txt").exists()
    assert "removed 1 stale output(s)" in err and "merge.spheres.npz" in err
    assert "earlier" not in json.loads((out / "manifest.json").read_text())


TWO = "name: two\noutputs: [a, b]\nnodes:\n  a: {type: toy_points, params: {count: 5}}\n  b: {type: toy_points}\n"


def test_a_file_is_stale_only_when_the_step_it_came_from_changed(tmp_path, monkeypatch, capsys):
    """Issue 47: ``--output`` with another setting removed every earlier file, those the setting does not touch
    too; a file goes when the step it was written from has another key now, and the run names it."""
    import json

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("NODEGRAPH_CACHE", str(tmp_path / "cache"))
    (tmp_path / "two.yaml").write_text(TWO)
    out = tmp_path / "outputs" / "two"
    assert cli("run", "two.yaml", "--no-rrd") == 0
    (out / "notes.txt").write_text("mine")
    a = stamps(out)["a.npz"]
    capsys.readouterr()
    same = (
        "--out-dir",
        str(Path("outputs") / "two"),
    )  # one folder for every setting (without it, each --set has its own)
    assert cli("run", "two.yaml", "--no-rrd", "--output", "b", "--set", "b.count=7", *same) == 0  # a's step unchanged
    assert stamps(out)["a.npz"] == a and "stale" not in capsys.readouterr().err
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["files"]["b.npz"]["from"] == "b" and manifest["earlier"]["a.npz"]["from"] == "a"
    assert cli("run", "two.yaml", "--no-rrd", "--output", "b", "--set", "a.count=9", *same) == 0  # a's step changed
    err = capsys.readouterr().err
    assert not (out / "a.npz").exists() and (out / "b.npz").exists() and (out / "notes.txt").read_text() == "mine"
    assert f"removed 1 stale output(s) from {Path('outputs') / 'two'}" in err and "a.npz" in err


def test_a_quiet_run_still_names_each_stale_output_it_removes_and_keeps_its_own(tmp_path, monkeypatch, capsys):
    """Issue 47: after ``--output ... -q`` files vanished with nothing said (-q silenced the line naming them). The
    line is said under -q too, with every file and the step that changed; what the run writes and a file the user
    made stay."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("NODEGRAPH_CACHE", str(tmp_path / "cache"))
    (tmp_path / "two.yaml").write_text(TWO)
    out = tmp_path / "outputs" / "two"
    assert cli("run", "two.yaml", "--no-rrd", "-q") == 0
    (out / "notes.txt").write_text("mine")
    capsys.readouterr()
    here = ("--out-dir", str(out), "-q")
    assert cli("run", "two.yaml", "--no-rrd", "--output", "b", "--set", "a.count=9", *here) == 0  # a's step changed
    err = capsys.readouterr().err
    assert not (out / "a.npz").exists() and (out / "b.npz").is_file() and (out / "notes.txt").read_text() == "mine"
    assert "removed 1 stale output(s)" in err and "a.npz" in err and "their step has changed since (a)" in err, err
    assert "b.npz" not in err and "notes.txt" not in err
