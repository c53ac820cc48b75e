"""Recordings are safe and readable: a partial run never replaces a complete recording, no temp files
after any signal, a blueprint names the views, a node's own logs never sit under a static output."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import datafusion
import pytest
from rerun.chunk import RrdReader

from nodegraph.cli import main

TOY = str(Path(__file__).with_name("toy_nodes.py"))
RECIPE = """\
name: slowrun
seed: 2
effects: []
outputs: [slow, surf]
nodes:
  pts: {type: toy_points, params: {count: 6}}
  slow: {type: toy_slow, inputs: {spheres: pts.spheres}, params: {seconds: SECONDS, started: "STARTED"}}
  surf: {type: toy_sphere_mesh, inputs: {spheres: slow.spheres}}
"""


def write(tmp_path, seconds=0.0, started="") -> Path:
    path = tmp_path / "slowrun.yaml"
    path.write_text(RECIPE.replace("SECONDS", str(seconds)).replace("STARTED", str(started)))
    return path


def command(tmp_path, *extra, quiet=True):
    return [
        sys.executable,
        "-m",
        "nodegraph.cli",
        "run",
        str(tmp_path / "slowrun.yaml"),
        "--plugin",
        TOY,
        "--cache-dir",
        str(tmp_path / "cache"),
        *(["-q"] if quiet else []),
        *extra,
    ]


def blueprint_view_names(path: Path) -> set[str]:
    reader = RrdReader(str(path))
    names = set()
    for chunk in reader.stream(store=reader.blueprints()[0]).to_chunks():
        batch = chunk.to_record_batch()
        if "ViewBlueprint:display_name" in batch.schema.names:
            names.update(v for row in batch.column("ViewBlueprint:display_name").to_pylist() for v in row)
    return names


def hidden_or_temp(directory: Path) -> list[str]:
    return [p.name for p in directory.rglob("*") if p.name.startswith(".") or p.suffix == ".tmp"]


def test_complete_run_has_a_blueprint_naming_its_views_and_logs_apart_from_outputs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write(tmp_path)
    assert main(["run", "slowrun.yaml", "--plugin", TOY, "--cache-dir", str(tmp_path / "cache"), "-q"]) == 0
    rrd = tmp_path / "outputs" / "slowrun" / "slowrun.rrd"
    reader = RrdReader(str(rrd))
    assert len(reader.recordings()) == 1 and len(reader.blueprints()) == 1
    names = blueprint_view_names(rrd)
    assert {"final scene (surf)", "surf", "pts", "slow: energy"} <= names, names
    ctx = datafusion.SessionContext()
    store = reader.stream().collect()
    steps = store.reader("sim_step", contents="/slow/log/energy", ctx=ctx).to_arrow_table()
    assert steps.column("sim_step").to_pylist() == list(range(10))
    assert not list(tmp_path.glob("outputs/slowrun/*.partial.rrd")) and not hidden_or_temp(tmp_path / "outputs")


def test_recording_ids_differ_between_settings_and_repeat_for_one(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write(tmp_path)
    ids = []
    for name, extra in (("a", []), ("b", []), ("c", ["--set", "pts.count=7"])):
        assert (
            main(
                [
                    "run",
                    "slowrun.yaml",
                    "--plugin",
                    TOY,
                    "--cache-dir",
                    str(tmp_path / "cache"),
                    "-q",
                    "--rrd",
                    f"{name}.rrd",
                    *extra,
                ]
            )
            == 0
        )
        ids.append(RrdReader(f"{name}.rrd").recordings()[0].recording_id)
    assert ids[0] == ids[1] != ids[2]


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGKILL], ids=["INT", "TERM", "KILL"])
def test_an_interrupted_run_keeps_the_complete_recording_and_leaves_no_partial_or_temp_files(
    tmp_path, sig, node_started
):
    write(tmp_path)
    rrd = tmp_path / "outputs" / "slowrun" / "slowrun.rrd"
    subprocess.run(command(tmp_path), check=True, cwd=tmp_path)
    complete = rrd.read_bytes()
    write(tmp_path, seconds=20.0, started=tmp_path / "started")
    # a run started in the background of a non-interactive shell (as CI may start the suite) inherits SIGINT
    # ignored; the user at a terminal, whom this test stands for, has it at its default
    proc = subprocess.Popen(
        command(tmp_path, quiet=False),
        cwd=tmp_path,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    node_started(tmp_path / "started", proc)  # the slow node is running (20 s to go): the signal lands inside it
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    partials = lambda: list(rrd.parent.glob("slowrun.*.partial.rrd"))  # named by the pid of the run's process
    assert proc.returncode != 0
    assert rrd.read_bytes() == complete  # the last complete recording is untouched
    if sig != signal.SIGKILL:  # stopped on purpose: what it recorded is not wanted, and not left (issue 47)
        assert "interrupted" in err and not partials()
    else:  # killed outright, the run leaves its recording named as partial
        assert len(partials()) == 1
    assert not hidden_or_temp(tmp_path / "outputs"), hidden_or_temp(tmp_path / "outputs")
    write(tmp_path)  # the next complete run replaces the recording and leaves no partial beside it
    subprocess.run(command(tmp_path), check=True, cwd=tmp_path)
    assert not partials() and len(RrdReader(str(rrd)).recordings()) == 1


def test_spawn_without_a_display_says_so_first_and_still_writes_the_file(tmp_path):
    write(tmp_path)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run(
        command(tmp_path, "--spawn", quiet=False), cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert "no display" in done.stderr
    assert done.stderr.index("no display") < done.stderr.index("pts")  # before the run's table of nodes
    assert (tmp_path / "outputs" / "slowrun" / "slowrun.rrd").is_file()
    assert not hidden_or_temp(tmp_path / "outputs")


@pytest.mark.parametrize("flags", [["--spawn", "--no-rrd"], ["--rrd", "x.rrd", "--no-rrd"]])
def test_contradictory_recording_flags_are_refused_before_anything_runs(tmp_path, monkeypatch, capsys, flags):
    monkeypatch.chdir(tmp_path)
    write(tmp_path)
    assert main(["run", "slowrun.yaml", "--plugin", TOY, "--cache-dir", str(tmp_path / "cache"), *flags]) == 2
    assert "--no-rrd contradicts" in capsys.readouterr().err
    assert not (tmp_path / "cache").exists() and not (tmp_path / "outputs").exists()


def test_two_runs_at_once_each_write_and_move_their_own_partial_recording(tmp_path, monkeypatch):
    """Two identical runs started together (two processes, here one process as two pids): each writes its own
    partial file, so the one that ends second still finds its file to move (it raised FileNotFoundError when
    both wrote ``name.partial.rrd``), and neither removes the other's while it is still being written."""
    from nodegraph import rerun_log

    rrd = tmp_path / "out" / "bowl.rrd"
    monkeypatch.setattr(rerun_log.os, "getpid", os.getppid)  # the parent is alive as long as this test
    first = rerun_log.RunRecording(rrd, "bowl", recording_id="r")
    monkeypatch.undo()
    second = rerun_log.RunRecording(rrd, "bowl", recording_id="r")
    assert first.partial != second.partial
    assert second.close() == rrd and first.partial.exists()  # the first, still running, keeps its file
    assert first.close() == rrd and not list(rrd.parent.glob("*.partial.rrd"))


def test_a_complete_run_removes_the_partial_recordings_of_ended_runs_and_keeps_running_ones(tmp_path):
    """What a killed run left (its process gone, or a zombie no one reaps, as in a container) goes with the next
    complete run; a partial file a running process writes stays."""
    from nodegraph import rerun_log

    rrd = tmp_path / "bowl.rrd"
    ended = subprocess.Popen(["true"])  # never waited for while the run closes: a zombie
    while not Path(f"/proc/{ended.pid}/stat").read_text().rpartition(")")[2].split()[0] == "Z":
        time.sleep(0.01)
    left, running = rerun_log.partial_path(rrd, ended.pid), rerun_log.partial_path(rrd, os.getppid())
    left.write_bytes(b"x")
    running.write_bytes(b"x")
    rerun_log.RunRecording(rrd, "bowl", recording_id="r").close()
    ended.wait()
    assert not left.exists() and running.exists()
