"""``nodegraph clean RECIPE`` prunes the outputs of a recipe's earlier runs and the partial recordings of stopped runs,
never a file a user made or changed; a run says in one line how much can be pruned (issue 47: stale and partial
outputs piled up, 313 MB a rice-bowl run)."""

import os
import subprocess
import sys
from pathlib import Path

from nodegraph.cli import main

from .test_cli_and_rerun import RECIPE, TOY


def run(recipe: Path, cache: Path, *more: str) -> int:
    return main(["run", str(recipe), "--plugin", TOY, "--cache-dir", str(cache), "--no-rrd", *more])


def dead_pid() -> int:
    """The id of a process that has ended."""
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_clean_removes_earlier_runs_outputs_and_dead_partials_only(tmp_path, monkeypatch, capsys):
    (tmp_path / "pyproject.toml").write_text("[project]\nname = 'mine'\n")
    recipe = tmp_path / "toyrun.yaml"
    recipe.write_text(RECIPE)
    monkeypatch.chdir(tmp_path)
    plain = tmp_path / "outputs" / "toyrun"
    assert run(recipe, tmp_path / "c") == 0
    assert "nodegraph clean" not in capsys.readouterr().out  # nothing to prune yet: no line
    earlier = sorted(p.name for p in plain.iterdir())
    assert "surf.ply" in earlier and "manifest.json" in earlier
    assert run(recipe, tmp_path / "c", "--set", "pts.count=9") == 0  # the latest run: its own folder
    latest = plain / "set_pts.count=9"
    assert "nodegraph clean" not in capsys.readouterr().out  # the recipe's own folder keeps its last run's files
    mine = plain / "notes.txt"  # a user's own file, no manifest lists it
    mine.write_text("keep me")
    changed = plain / "merge.spheres.npz"  # written by a run, then changed by the user
    assert changed.is_file()
    os.utime(changed, ns=(changed.stat().st_atime_ns, changed.stat().st_mtime_ns + 10**9))
    stopped = plain / f"toyrun.{dead_pid()}.partial.rrd"  # what a killed run left
    stopped.write_bytes(b"x" * 100)
    running = latest / f"toyrun.{os.getpid()}.partial.rrd"  # a run in progress writes it
    running.write_bytes(b"y")

    assert run(recipe, tmp_path / "c", "--set", "pts.count=9") == 0  # a run now says what can be pruned
    line = [x for x in capsys.readouterr().out.splitlines() if "nodegraph clean" in x]
    assert len(line) == 1 and line[0].startswith("earlier runs' outputs and partial recordings: "), line
    assert main(["clean", str(recipe), "--dry-run"]) == 0
    listed = capsys.readouterr().out
    named = {line.split(" (")[0].removeprefix("would remove ") for line in listed.splitlines()[:-1]}
    # the recipe's own folder keeps its last run's files though a --set run came after it (a new user's first clean
    # removed the main job's picture after a draft): only what a stopped run left goes
    assert named == {str(stopped.relative_to(tmp_path))}, listed
    assert listed.splitlines()[-1].startswith("would free "), listed
    assert stopped.is_file()  # a dry run removes nothing

    assert main(["clean", str(recipe)]) == 0
    capsys.readouterr()
    left = sorted(p.name for p in plain.iterdir() if p.is_file())
    assert "surf.ply" in left and "manifest.json" in left and "notes.txt" in left and stopped.name not in left, left
    assert running.is_file() and (latest / "surf.ply").is_file() and (latest / "manifest.json").is_file()
    assert main(["clean", str(recipe)]) == 0
    assert capsys.readouterr().out.startswith("nothing to prune")
    assert run(recipe, tmp_path / "c", "--set", "pts.count=9") == 0  # the latest run, again: still current
    assert "nodegraph clean" not in capsys.readouterr().out


def test_clean_keeps_the_latest_runs_files_and_prunes_what_it_kept_from_an_earlier_one(tmp_path, monkeypatch, capsys):
    """A run of one output (``--output surf``) keeps the other files of an earlier run of the same settings (listed as
    ``earlier`` in its manifest): not written by the latest run, they are pruned."""
    recipe = tmp_path / "toyrun.yaml"
    recipe.write_text(RECIPE)
    monkeypatch.chdir(tmp_path)
    folder = tmp_path / "outputs" / "toyrun"
    assert run(recipe, tmp_path / "c") == 0
    assert run(recipe, tmp_path / "c", "--output", "surf") == 0
    capsys.readouterr()
    assert main(["clean", str(recipe)]) == 0
    said = capsys.readouterr().out
    assert f"removing {Path('outputs/toyrun/merge.spheres.npz')}" in said and "surf.ply" not in said, said
    assert sorted(p.name for p in folder.iterdir()) == ["manifest.json", "surf.ply"]


def test_clean_at_a_terminal_asks_first(tmp_path, monkeypatch, capsys):
    """A new user's ``nodegraph clean`` removed their earlier results without a word: at a terminal it lists what
    would go and removes it only on a yes (``--yes``: without asking)."""
    recipe = tmp_path / "toyrun.yaml"
    recipe.write_text(RECIPE)
    monkeypatch.chdir(tmp_path)
    assert run(recipe, tmp_path / "c") == 0
    assert run(recipe, tmp_path / "c", "--output", "surf") == 0
    earlier = tmp_path / "outputs" / "toyrun" / "merge.spheres.npz"
    monkeypatch.setattr(sys.stdin, "isatty", lambda: True)
    answers = iter(["", "y"])
    monkeypatch.setattr("builtins.input", lambda prompt: next(answers))
    capsys.readouterr()
    assert main(["clean", str(recipe)]) == 1  # Enter: no
    assert earlier.is_file() and "nothing removed" in capsys.readouterr().out
    assert main(["clean", str(recipe)]) == 0 and not earlier.exists()


def test_clean_of_a_missing_recipe_says_so(tmp_path, capsys):
    assert main(["clean", str(tmp_path / "nope.yaml")]) == 2
    assert "no such recipe file" in capsys.readouterr().err


def test_an_earlier_runs_recording_is_pruned_named_as_its_folder(tmp_path, monkeypatch, capsys):
    """The manifest keeps the recording's path absolute: it was listed so, and counted as a folder of its own. An
    earlier --set folder goes whole; the recipe's own folder, run last, keeps its files."""
    recipe = tmp_path / "toyrun.yaml"
    recipe.write_text(RECIPE)
    monkeypatch.chdir(tmp_path)
    for more in (["--set", "pts.count=9"], ["--set", "pts.count=7"]):
        assert main(["run", str(recipe), "--plugin", TOY, "--cache-dir", str(tmp_path / "c"), *more]) == 0
    capsys.readouterr()
    assert main(["clean", str(recipe), "--dry-run"]) == 0
    listed = capsys.readouterr().out
    assert f"would remove {Path('outputs/toyrun/set_pts.count=9/toyrun.rrd')} (" in listed, listed
    assert "set_pts.count=7" not in listed, listed
    assert listed.splitlines()[-1].endswith("file(s) in 1 folder(s)"), listed
