"""A first run compiles the kernels of its later nodes in a second process while it computes the earlier ones
(issue 27; nodegraph/compile_ahead.py): the worker compiles exactly the kernels recorded for the node types and
effects the run will compute, the run then loads them from numba's cache, and a worker that fails, or cannot
start, costs the run nothing but the time to compile them itself."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from numba import types

from nodegraph import compile_ahead
from nodegraph.compile_ahead import CompileAhead, encode_types

KERNELS = """
from numba import njit


@njit(cache=True)
def early_kernel(values):
    return values + 1.0


@njit(cache=True)
def late_kernel(values):
    return values * 3.0


@njit(cache=True)
def wet_kernel(values):
    return values - 1.0
"""

PLUGIN = '''
import glob
import os
import time

import numpy as np

from nodegraph import In, Out, node
from nodegraph.values import Table


@node("ahead_early", outputs={"table": Out(Table, "numbers")})
def ahead_early(ctx):
    """Waits (≤ 20 s) until the late node's kernel is in numba's cache: compiled by the run's second process."""
    from ahead_kernels import early_kernel

    waited = time.monotonic() + float(os.environ.get("AHEAD_WAIT", "20"))
    pattern = os.path.join(os.environ.get("NUMBA_CACHE_DIR", "."), "**", "*late_kernel*.nbi")
    while not glob.glob(pattern, recursive=True) and time.monotonic() < waited:
        time.sleep(0.1)
    return Table({"x": early_kernel(np.arange(4.0))})


@node("ahead_late", effects=("moisture",), inputs={"table": In(Table, "numbers")},
      outputs={"table": Out(Table, "tripled")})
def ahead_late(ctx, table):
    """Runs one kernel, and a second with effect 'moisture'."""
    from ahead_kernels import late_kernel, wet_kernel

    x = late_kernel(np.array(table.columns["x"], dtype=np.float64))
    return Table({"x": wet_kernel(x) if ctx.wants("moisture") else x})
'''

RECIPE = """\
name: ahead
seed: 1
effects: [{effects}]
outputs: [late.table]
nodes:
  early:
    type: ahead_early
  late:
    type: ahead_late
    inputs: {{table: early.table}}
"""


@pytest.fixture(autouse=True)
def _whatever_the_load(monkeypatch):
    """The worker starts here whatever the machine's load (by default only onto a free core: ``core_free``); the
    runs these tests start inherit it."""
    monkeypatch.setenv(compile_ahead.ENV_VAR, "on")


def _setup(tmp_path: Path, effects: str = "") -> None:
    (tmp_path / "ahead.py").write_text(PLUGIN)
    (tmp_path / "ahead_kernels.py").write_text(KERNELS)
    (tmp_path / "recipe.yaml").write_text(RECIPE.format(effects=effects))
    vector = encode_types((types.Array(types.float64, 1, "C"),))
    late = ["ahead_kernels", "late_kernel", vector]
    record = {
        "ahead_late": [
            {"effects": [], "kernels": [late]},
            {"effects": ["moisture"], "kernels": [late, ["ahead_kernels", "wet_kernel", vector]]},
        ]
    }
    (tmp_path / compile_ahead.RECORD).write_text(json.dumps(record))


def _run(tmp_path: Path, **env) -> subprocess.CompletedProcess:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"), **env)
    command = [sys.executable, "-m", "nodegraph.cli", "run", str(tmp_path / "recipe.yaml"), "--plugin"]
    command += [str(tmp_path / "ahead.py"), "--no-cache", "--no-rrd", "--out-dir", str(tmp_path / "out")]
    done = subprocess.run(command, capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    return done


def _cached(tmp_path: Path, kernel: str) -> bool:
    return any((tmp_path / "numba").rglob(f"*{kernel}*.nbi"))


@pytest.mark.parametrize("effects", ["", "moisture"])
def test_the_late_kernels_compile_ahead_and_load(tmp_path, effects):
    """The late node's kernels, and only those its effects need, compile in the worker; the run loads them
    (no compile event in the run's process) and prints nothing of the worker's."""
    _setup(tmp_path, effects)
    done = _run(tmp_path)
    assert "ahead_kernels.early_kernel" in done.stderr  # the early node compiles its own, in the run
    assert "compiling ahead_kernels.late_kernel" not in done.stderr  # loaded: the worker compiled it
    assert _cached(tmp_path, "late_kernel")
    assert _cached(tmp_path, "wet_kernel") == (effects == "moisture")  # only for a recipe asking for moisture
    assert "wet_kernel" not in done.stderr
    assert "Traceback" not in done.stderr and done.stdout.count("\n") == _run(tmp_path).stdout.count("\n")


def test_off_compiles_in_the_run(tmp_path):
    _setup(tmp_path)
    done = _run(tmp_path, NODEGRAPH_COMPILE_AHEAD="off", AHEAD_WAIT="0")
    assert "ahead_kernels.late_kernel" in done.stderr


def test_a_failing_worker_does_not_fail_the_run(tmp_path, monkeypatch):
    """A worker that dies at once (the run then writes to a closed pipe) and a record naming a kernel that does
    not exist: the run compiles its kernels itself and succeeds."""
    from nodegraph.executor import run_recipe
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    _setup(tmp_path)
    record = json.loads((tmp_path / compile_ahead.RECORD).read_text())
    record["ahead_late"][0]["kernels"].insert(0, ["ahead_kernels", "no_such_kernel", "bm90IHR5cGVz"])
    (tmp_path / compile_ahead.RECORD).write_text(json.dumps(record))
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("AHEAD_WAIT", "0")
    monkeypatch.setattr(CompileAhead, "command", [sys.executable, "-c", "import sys; sys.exit(3)"])
    ended = []
    close = CompileAhead.close

    def closing(self):
        process = self.process
        close(self)
        ended.append(process.returncode)

    monkeypatch.setattr(CompileAhead, "close", closing)
    recipe = load_recipe(tmp_path / "recipe.yaml", default_registry(plugins=[tmp_path / "ahead.py"]))
    result = run_recipe(recipe)
    assert ended == [3]  # the worker ran, and died
    assert list(result.output("late.table").columns["x"]) == [3.0, 6.0, 9.0, 12.0]


def test_a_worker_that_cannot_start_does_not_fail_the_run(tmp_path, monkeypatch):
    def refuse(*args, **kwargs):
        raise OSError("no processes left")

    monkeypatch.setattr(compile_ahead.subprocess, "Popen", refuse)
    monkeypatch.setattr(compile_ahead, "plan_jobs", lambda *a: [compile_ahead.Job(0, "m", "k", "")])
    assert CompileAhead.start(None, [], set()) is None


def test_the_worker_stops_with_the_run(tmp_path):
    """``close`` ends a worker still compiling (here one that would run for a minute)."""
    ahead = CompileAhead([compile_ahead.Job(0, "m", "k", "")])
    ahead.command = [sys.executable, "-c", "import time; time.sleep(60)"]
    ahead.spawn()
    process = ahead.process
    ahead.close()
    assert process.poll() is not None


def test_the_record_names_kernels_that_exist():
    """Each kernel of nodes/kernel_signatures.json is a numba kernel of that name, its argument types load, and
    its node type implements the effects it is recorded under (rewrite: bench_compile.py --record)."""
    import importlib
    from functools import reduce

    from numba.core.dispatcher import Dispatcher

    import nodes
    from nodegraph.registry import default_registry

    registry = default_registry()
    record = json.loads((Path(nodes.__file__).parent / compile_ahead.RECORD).read_text())
    assert record
    for type_name, entries in record.items():
        assert set().union(*(entry["effects"] for entry in entries)) <= registry[type_name].effects
        for entry in entries:
            for module, name, args in entry["kernels"]:
                kernel = reduce(getattr, name.split("."), importlib.import_module(module))
                assert isinstance(kernel, Dispatcher), f"{module}.{name}"
                assert all(isinstance(t, types.Type) for t in compile_ahead.decode_types(args))


def test_the_worker_starts_from_the_end():
    """The run compiles from its first node's first kernel on; the worker from the last node's last kernel."""
    jobs = [compile_ahead.Job(position, "m", name, "") for position, name in [(3, "a"), (3, "b"), (7, "c"), (9, "d")]]
    assert [job.name for job in compile_ahead.latest_first(jobs)] == ["d", "c", "b", "a"]


def test_kernels_this_process_has_are_not_compiled_ahead(tmp_path, monkeypatch):
    """A second run in one process (``nodegraph watch``) hands the worker only kernels it has not loaded."""
    import numpy as np

    from nodegraph.plan import Instance
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    _setup(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "ahead_kernels", raising=False)  # loaded by another test of this process
    recipe = load_recipe(tmp_path / "recipe.yaml", default_registry(plugins=[tmp_path / "ahead.py"]))
    order = [Instance("early"), Instance("late")]
    assert [job.name for job in compile_ahead.plan_jobs(recipe, order, set(order))] == ["late_kernel"]
    assert compile_ahead.plan_jobs(recipe, order, {order[0]}) == []  # the late node is cached: nothing to compile
    import ahead_kernels

    ahead_kernels.late_kernel(np.zeros(2))
    assert compile_ahead.plan_jobs(recipe, order, set(order)) == []


def test_a_run_whose_kernels_are_all_cached_starts_no_worker(tmp_path, monkeypatch):
    """A run that had every kernel of its worker's jobs (compiled or loaded; with a worker or without) leaves a mark
    in numba's cache folder: the next run with the same kernels starts no worker (it would only load them, 1.6 CPU s
    of the main job's run), and its estimate says no kernel is left to compile; a change to a kernel's module, or a
    cleared cache, starts it again."""
    from nodegraph.plan import Instance
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    _setup(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "ahead_kernels", raising=False)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    recipe = load_recipe(tmp_path / "recipe.yaml", default_registry(plugins=[tmp_path / "ahead.py"]))
    order = [Instance("early"), Instance("late")]
    spawned = []
    monkeypatch.setattr(CompileAhead, "spawn", lambda self: spawned.append(self.jobs))
    assert CompileAhead.start(recipe, order, set(order)) is not None and len(spawned) == 1  # nothing cached yet
    assert compile_ahead.kernels_due(recipe)  # what check and run say beside the estimate
    _run(tmp_path, **{compile_ahead.ENV_VAR: "off"})  # compiles them, no worker, and marks them cached
    assert CompileAhead.start(recipe, order, set(order)) is None and len(spawned) == 1
    assert not compile_ahead.kernels_due(recipe)  # issue 47: "a first run compiles kernels" was said every time
    (tmp_path / "ahead_kernels.py").write_text(KERNELS + "\n# edited\n")
    assert CompileAhead.start(recipe, order, set(order)) is not None and len(spawned) == 2


@pytest.mark.parametrize("load, starts", [(0.3, True), (1.6, False), (9.0, False)])
def test_by_default_the_worker_starts_only_onto_a_free_core(tmp_path, monkeypatch, load, starts):
    """Unset, the worker starts only when the load average leaves a core idle besides the run's own: on a busy
    machine it only took a share of the run's cores (the main job's first run at load 8-12: 1.08x and 1.20x the
    wall). Failed when it started at any load."""
    from nodegraph.plan import Instance
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    _setup(tmp_path)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "ahead_kernels", raising=False)  # not loaded by an earlier test: jobs to plan
    monkeypatch.delenv(compile_ahead.ENV_VAR)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))
    monkeypatch.setattr(os, "getloadavg", lambda: (load, load, load))
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1})
    recipe = load_recipe(tmp_path / "recipe.yaml", default_registry(plugins=[tmp_path / "ahead.py"]))
    order = [Instance("early"), Instance("late")]
    spawned = []
    monkeypatch.setattr(CompileAhead, "spawn", lambda self: spawned.append(self.jobs))
    assert (CompileAhead.start(recipe, order, set(order)) is not None) == starts
    assert len(spawned) == (1 if starts else 0)
