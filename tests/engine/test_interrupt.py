"""Ctrl-C and SIGTERM stop a run within 2 s, whichever node is running, and leave nothing half-written (issue 47)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

TOY = str(Path(__file__).with_name("toy_nodes.py"))
RECIPE = """\
name: spinrun
seed: 2
effects: []
outputs: [spin]
nodes:
  pts: {type: toy_points, params: {count: 6}}
  spin: {type: toy_spin, inputs: {spheres: pts.spheres}, params: {steps: STEPS, started: "STARTED"}}
"""


def leftovers(folder: Path) -> list[str]:
    """Partial recordings and temporary files under ``folder``."""
    return sorted(str(p) for p in folder.rglob("*") if ".partial" in p.name or p.name.endswith(".tmp"))


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["INT", "TERM"])
def test_a_signal_stops_a_run_inside_a_numba_kernel_within_2_s_and_leaves_no_partial_files(tmp_path, sig, node_started):
    started = tmp_path / "started"
    (tmp_path / "spin.yaml").write_text(RECIPE.replace("STEPS", str(10**12)).replace("STARTED", str(started)))
    command = [sys.executable, "-m", "nodegraph.cli", "run", str(tmp_path / "spin.yaml"), "--plugin", TOY]
    command += ["--cache-dir", str(tmp_path / "cache"), "-q"]
    proc = subprocess.Popen(
        command,
        cwd=tmp_path,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # as at a terminal (see test_recordings)
    )
    try:
        runner = node_started(started, proc)
        time.sleep(0.2)  # inside the loop, which holds the GIL
        sent = time.monotonic()
        proc.send_signal(sig)
        try:
            proc.wait(timeout=2.0)
        except subprocess.TimeoutExpired:
            pytest.fail("the run was still going 2 s after the signal")
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = proc.stderr.read()
    assert proc.returncode == 130, err
    assert took < 2.0
    assert "interrupted" in err
    with pytest.raises(ProcessLookupError):  # the process that ran the node is gone too
        os.kill(runner, 0)
    assert not leftovers(tmp_path), leftovers(tmp_path)
    assert (tmp_path / "cache" / "entries").is_dir()  # what finished (pts) is cached
