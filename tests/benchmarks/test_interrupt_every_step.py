"""Ctrl-C or SIGTERM ends a run of the main job within 2 s whichever step runs, nothing left running (issue 47: up
to 2.8 s, measured in one step). The first step of each node type of the ikura draft in turn (two steps of one type
run the same code), one signal each (SIGINT and SIGTERM alternating), 0.3 s after it starts, with its recording as a
user's run has: ``bench_interrupt.py steps --steps types --assert-s 2``, the steps before it cached. Slow: a run
started and stopped per node type (about 3 s each)."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RECIPE = "graphs/ikura_don.yaml"
BOUND_S = 2.0


@pytest.mark.slow
def test_every_step_of_the_main_job_stops_within_2_s(tmp_path):
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    cache = tmp_path / "cache"
    warm = [sys.executable, "-m", "nodegraph.cli", "run", RECIPE, "--draft", "--cache-dir", str(cache), "-q"]
    done = subprocess.run([*warm, "--out-dir", str(tmp_path / "out")], cwd=ROOT, env=env, capture_output=True)
    assert done.returncode == 0, done.stderr[-2000:]
    bench = [sys.executable, "benchmarks/bench_interrupt.py", "steps", RECIPE, "--draft", "--cache-dir", str(cache)]
    bench += ["--steps", "types", "--alternate", "--delay", "0.3", "--rrd", "--assert-s", str(BOUND_S)]
    done = subprocess.run(bench, cwd=ROOT, env=env, capture_output=True, text=True)
    rows = [json.loads(line) for line in done.stdout.splitlines()]
    assert done.returncode == 0, done.stderr[-2000:]
    nodes = load_recipe(ROOT / RECIPE, default_registry(), draft=True).nodes
    assert {nodes[row["step"]].spec.type_name for row in rows} == {node.spec.type_name for node in nodes.values()}
    stopped = [row for row in rows if row.get("signal")]
    assert len(stopped) >= 0.9 * len(rows), rows  # a run that ended before its signal is no measurement
    # stopped (130, its 'interrupted' line said), or finished: a signal landing as the last steps end lets them
    # end (one run in three, signalled in export: status 0, 1.4 s, nothing said); either within the bound
    finished = [row for row in stopped if row["status"] == 0 and not row["said"]]
    late = [
        row
        for row in stopped
        if row["exit_s"] > BOUND_S or row["left"] or (row["status"] != 130 and row not in finished)
    ]
    assert not late, json.dumps(late)  # whole rows: the status, the seconds and the run's last lines
    assert len(finished) <= 2, finished  # the others were stopped, not finished
