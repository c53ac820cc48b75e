"""A real Dask cluster: a ``dask scheduler`` and two ``dask worker`` processes started here run a sweep of
the toy nodes; the outputs hash-identical to the in-process sweep; a worker killed mid-node loses nothing
(its task runs again on the other worker) and the sweep completes."""

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

distributed = pytest.importorskip("distributed")

from nodegraph.cache import Cache  # noqa: E402
from nodegraph.dask_pool import DaskPool  # noqa: E402
from nodegraph.executor import run_recipe  # noqa: E402
from nodegraph.recipe import load_recipe  # noqa: E402
from nodegraph.registry import Registry  # noqa: E402
from nodegraph.sweep import run_sweep, sweep_from_args  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TOY = str(Path(__file__).with_name("toy_nodes.py"))
RECIPE = """\
name: toy_cluster
seed: 5
outputs: [merge.spheres, merge.stats]
nodes:
  pts:
    type: toy_points
    variants: 3
    params: {count: 50}
  shift:
    type: toy_shift
    inputs: {spheres: pts.spheres}
  slow:
    type: toy_slow
    inputs: {spheres: shift.spheres}
    params: {seconds: 0.3, started: STARTED}
  merge:
    type: toy_merge
    inputs: {parts: [slow.spheres, pts.spheres]}
sweeps:
  shift:
    grid: {shift.dx: [0.0, 0.5, 1.0, 1.5]}
    metrics: [merge.stats.count:sum]
    outputs: [merge.spheres]
"""


def _start(args, env, log):
    return subprocess.Popen([sys.executable, "-m", *args], env=env, stdout=log, stderr=subprocess.STDOUT)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """``dask scheduler`` + two single-threaded ``dask worker`` processes (no nanny: killing one kills the
    worker itself), each with one numba thread; yields the scheduler address and the worker processes."""
    tmp = tmp_path_factory.mktemp("dask")
    env = dict(
        os.environ,
        PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
        NUMBA_NUM_THREADS="1",
        DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES="3",
    )
    scheduler_file = tmp / "scheduler.json"
    log = open(tmp / "cluster.log", "w")
    procs = [
        _start(
            ["distributed.cli.dask_scheduler", "--scheduler-file", str(scheduler_file), "--port", "0"]
            + ["--dashboard-address", ":0", "--host", "127.0.0.1"],
            env,
            log,
        )
    ]
    try:
        deadline = time.time() + 30
        while not scheduler_file.exists() and time.time() < deadline:
            time.sleep(0.1)
        assert scheduler_file.exists(), (tmp / "cluster.log").read_text()
        workers = [
            _start(
                ["distributed.cli.dask_worker", "--scheduler-file", str(scheduler_file), "--nthreads", "1"]
                + ["--no-nanny", "--no-dashboard", "--host", "127.0.0.1", "--name", f"w{i}"],
                env,
                log,
            )
            for i in range(2)
        ]
        procs += workers
        with distributed.Client(scheduler_file=str(scheduler_file), timeout="30s") as client:
            client.wait_for_workers(2, timeout=30)
            address = client.scheduler.address
        yield address, workers, scheduler_file
    finally:
        for proc in reversed(procs):
            if proc.poll() is None:
                proc.terminate()
        for proc in procs:
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
        log.close()


@pytest.fixture
def setup(tmp_path):
    path = tmp_path / "toy_cluster.yaml"
    path.write_text(RECIPE.replace("STARTED", str(tmp_path / "started")))  # each slow instance's process id
    registry = Registry()
    registry.add_plugin_file(TOY)
    decl = sweep_from_args(load_recipe(path, registry), None, [], [], [])
    reference = run_sweep(path, registry, decl, cache=Cache(tmp_path / "in-process"))
    return path, registry, decl, reference


def test_sweep_on_a_cluster_is_bit_identical_to_in_process(cluster, setup, tmp_path):
    address, _, _ = cluster
    path, registry, decl, reference = setup
    cache = Cache(tmp_path / "shared")
    with DaskPool(address=address) as pool:
        remote = run_sweep(path, registry, decl, cache=cache, pool=pool, plugins=[TOY])
        assert remote.executor.startswith("Dask tcp://127.0.0.1") and remote.executor.endswith("2 worker(s)")
        # a plain run on the cluster: a variant family spread over the workers, same files as in-process
        run = run_recipe(load_recipe(path, registry), cache=cache, pool=pool, plugins=[TOY], out_dir=tmp_path / "a")
    assert [p.hashes for p in remote.points] == [p.hashes for p in reference.points]
    assert len({p.digest for p in remote.points}) == 4
    # the shared upstream (pts ×3) ran once, on a worker; every point's own 7 instances ran there too
    assert remote.common_instances == 3 and all(p.ran == 7 for p in remote.points)
    assert {r.status for r in run.records} == {"cached"}  # the sweep already computed the recipe's setting
    local = run_recipe(load_recipe(path, registry), out_dir=tmp_path / "b")
    for name in ("merge.spheres.npz", "merge.stats.csv"):
        if (tmp_path / "b" / name).exists():
            assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == sorted(p.name for p in (tmp_path / "b").iterdir())
    assert local.files


def test_cli_run_and_sweep_on_the_scheduler(cluster, setup, tmp_path, capsys):
    from nodegraph.cli import main

    address, _, _ = cluster
    path = setup[0]
    common = ["--plugin", TOY, "--cache-dir", str(tmp_path / "shared")]
    outputs = {}
    for name, extra in (("cluster", ["--scheduler", address]), ("local", ["--cache-dir", str(tmp_path / "own")])):
        out = tmp_path / name
        assert main(["run", str(path), *common, *extra, "--out-dir", str(out), "--no-rrd", "-q"]) == 0
        outputs[name] = {p.name: p.read_bytes() for p in out.iterdir() if p.name != "manifest.json"}
    assert outputs["cluster"] == outputs["local"] and outputs["local"]
    assert main(["sweep", str(path), *common, "--scheduler", address, "--out-dir", str(tmp_path / "s"), "-q"]) == 0
    assert (tmp_path / "s" / "shift.csv").is_file()
    assert main(["run", str(path), "--plugin", TOY, "--workers", "2", "--no-cache", "--no-rrd", "-q"]) == 2
    assert "drop --no-cache" in capsys.readouterr().err


def test_a_worker_killed_mid_node_loses_nothing(cluster, setup, tmp_path):
    address, workers, scheduler_file = cluster
    path, registry, decl, reference = setup
    cache = Cache(tmp_path / "shared")
    killed = []

    def kill_a_busy_worker():
        """SIGKILL the first worker process that writes a toy_slow instance's start file: mid-node (the node
        writes it as it starts, then sleeps 0.3 s), not merely assigned the task."""
        with distributed.Client(address, timeout="20s") as client:
            pids = {pid: worker for worker, pid in client.run(os.getpid).items()}
        started = tmp_path / "started"
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not killed:
            running = [int(p.name) for p in started.glob("*")] if started.is_dir() else []
            for pid in running:
                if pid in pids:  # not this process's (the in-process reference run wrote one too)
                    os.kill(pid, signal.SIGKILL)
                    killed.append(pids[pid])
                    break
            time.sleep(0.005)

    killer = threading.Thread(target=kill_a_busy_worker)
    killer.start()
    with DaskPool(address=address) as pool:
        result = run_sweep(path, registry, decl, cache=cache, pool=pool, plugins=[TOY])
    killer.join()
    assert killed, "no worker was killed: the test did not exercise a death"
    assert sum(w.poll() is not None for w in workers) == 1
    assert [p.hashes for p in result.points] == [p.hashes for p in reference.points]
    assert not list(cache.directory.rglob("*.tmp"))  # no partial entry or blob left behind
