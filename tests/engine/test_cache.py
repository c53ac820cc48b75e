"""Cache writes are atomic; corrupt entries are detected, reported and recomputed."""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from nodegraph import cache as cache_module
from nodegraph import codec
from nodegraph.cache import Cache
from nodegraph.executor import run_recipe
from nodegraph.recipe import parse_recipe
from nodegraph.report import Reporter
from nodegraph.values import Table

RECIPE = """\
outputs: [shifted]
nodes:
  pts: {type: toy_points, params: {count: 50}}
  shifted: {type: toy_shift, inputs: {spheres: pts.spheres}, params: {dx: 1.0}}
"""
TOY = Path(__file__).with_name("toy_nodes.py")


def run(registry, cache, reporter=None):
    return run_recipe(parse_recipe(RECIPE, registry, file="c.yaml"), cache=cache, reporter=reporter)


def test_store_and_load_round_trip(cache):
    value = Table({"x": np.arange(12.0), "n": np.ones(12, np.int64)})
    cache.store("k" * 64, {"table": value}, "n", "t")
    assert cache.has("k" * 64)
    loaded = cache.load("k" * 64, {"table": Table})["table"]
    assert codec.content_hash(loaded) == codec.content_hash(value)


def test_identical_outputs_share_one_blob(cache):
    value = Table({"x": np.zeros(3)})
    cache.store("a" * 64, {"s": value}, "n1", "t")
    cache.store("b" * 64, {"s": value}, "n2", "t")
    info = cache.info()
    assert info.entries == 2 and info.blobs == 1


def test_crash_between_blob_and_entry_leaves_no_entry(registry, cache, monkeypatch):
    real = cache_module.atomic_write
    calls = []

    def crashing(path, data, durable=True):
        calls.append(path)
        if path.suffix == ".json" and sum(p.suffix == ".json" for p in calls) == 2:  # the second node's entry
            raise KeyboardInterrupt("simulated crash")
        real(path, data, durable)

    monkeypatch.setattr(cache_module, "atomic_write", crashing)
    with pytest.raises(KeyboardInterrupt):
        run(registry, cache)
    monkeypatch.setattr(cache_module, "atomic_write", real)
    assert cache.info().entries == 1  # pts finished; shifted's entry was never made visible
    assert not list(cache.directory.rglob("*.tmp"))
    result = run(registry, cache)
    assert result.status() == {"pts": "cached", "shifted": "ran"}


def test_crash_inside_a_write_leaves_no_partial_file(tmp_path, monkeypatch):
    target = tmp_path / "x" / "entry.json"
    monkeypatch.setattr(os, "replace", lambda *a: (_ for _ in ()).throw(OSError("disk gone")))
    with pytest.raises(OSError):
        cache_module.atomic_write(target, b"{}")
    assert not target.exists() and not list(target.parent.iterdir())


@pytest.mark.parametrize("damage", ["truncate", "flip", "delete", "garbage_entry"])
def test_corrupt_entry_is_detected_reported_and_recomputed(registry, cache, damage):
    first = run(registry, cache)
    entries = list(cache.directory.glob("entries/*/*.json"))
    # the requested output's blob (pull-based: a damaged upstream blob is never read while it is cached)
    manifest = next(json.loads(e.read_text()) for e in entries if json.loads(e.read_text())["node"] == "shifted")
    digest = manifest["outputs"]["spheres"]["blob"]
    blob = cache.directory / "blobs" / digest[:2] / f"{digest}.npz"
    if damage == "truncate":
        blob.write_bytes(blob.read_bytes()[:-20])
    elif damage == "flip":
        data = bytearray(blob.read_bytes())
        data[len(data) // 2] ^= 0xFF
        blob.write_bytes(bytes(data))
    elif damage == "delete":
        blob.unlink()
    else:
        for entry in entries:
            entry.write_text("{not json")
    reporter = Reporter(quiet=True)
    warnings = []
    reporter.warn = warnings.append
    again = run(registry, cache, reporter)
    assert any(s in ("ran", "recomputed (corrupt cache)") for s in again.status().values())
    assert codec.content_hash(again.output("shifted")) == codec.content_hash(first.output("shifted"))
    if damage == "flip":  # size unchanged: only the hash check can find it
        assert warnings and "corrupt" in warnings[0]
    assert set(run(registry, cache).status().values()) == {"cached"}


SLOW = """\
outputs: [slow]
nodes:
  pts: {type: toy_points, params: {count: 5}}
  slow: {type: toy_slow, inputs: {spheres: pts.spheres}, params: {seconds: 30, started: STARTED}}
"""


def test_killed_run_keeps_finished_nodes_and_no_torn_entries(tmp_path, registry, node_started):
    recipe = tmp_path / "slow.yaml"
    recipe.write_text(SLOW.replace("STARTED", str(tmp_path / "started")))
    cache_dir = tmp_path / "cache"
    cmd = [
        sys.executable,
        "-m",
        "nodegraph.cli",
        "run",
        str(recipe),
        "--plugin",
        str(TOY),
        "--cache-dir",
        str(cache_dir),
        "--no-rrd",
        "--out-dir",
        str(tmp_path / "out"),
        "-q",
    ]
    proc = subprocess.Popen(cmd, cwd=tmp_path)
    node_started(tmp_path / "started", proc)  # pts is stored, slow is running
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    cache = Cache(cache_dir)
    assert cache.info().entries == 1  # pts only; slow was killed mid-run
    for entry in cache_dir.glob("entries/*/*.json"):
        key = entry.stem
        spheres_type = registry["toy_points"].outputs["spheres"].type
        assert cache.load(key, {"spheres": spheres_type})["spheres"].centers.shape == (5, 3)


def test_the_cache_does_not_flush_what_it_checks_as_it_reads(cache, tmp_path, monkeypatch):
    """A blob or entry torn by a crash fails its sha256 or JSON check and is computed again, so storing one
    waits for no disk flush (≈ 10 ms a file, more for a large blob); an output file the artist keeps does."""
    from nodegraph.output_files import write_output

    flushes = []
    real = os.fsync
    cache.store("j" * 64, {"table": Table({"x": np.zeros(3)})}, "n", "t")  # the cache's marker is written once
    monkeypatch.setattr(cache_module.os, "fsync", lambda fd: (flushes.append(fd), real(fd)))
    value = Table({"x": np.arange(12.0)})
    cache.store("k" * 64, {"table": value}, "n", "t")
    assert flushes == []
    write_output(value, tmp_path, "table")
    assert len(flushes) == 1


def test_the_default_cache_is_the_same_whichever_folder_a_command_runs_in(tmp_path, monkeypatch):
    """Issue 47: the cache was .nodegraph/cache of the current folder, so a run from another folder began cold."""
    from nodegraph.cache import default_cache_dir

    monkeypatch.delenv("NODEGRAPH_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    seen = set()
    for folder in ("a", "b/c"):
        (tmp_path / folder).mkdir(parents=True)
        monkeypatch.chdir(tmp_path / folder)
        seen.add(default_cache_dir().resolve())
    assert seen == {tmp_path / "xdg" / "nodegraph" / "cache"}
    Cache(tmp_path / "b" / "c" / ".nodegraph" / "cache").store("k" * 64, {}, "n", "t")  # an earlier version's
    assert default_cache_dir() == Path(".nodegraph/cache")  # still used where it is: its results stay warm
    monkeypatch.setenv("NODEGRAPH_CACHE", str(tmp_path / "mine"))
    assert default_cache_dir() == tmp_path / "mine"
