"""The cache's size limit: least recently used entries go first (last stored or loaded), a blob goes with
the last entry naming it, what a run just used stays, and ``nodegraph cache`` shows and sets the limit."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from nodegraph.cache import DEFAULT_LIMIT, Cache, format_size, parse_size
from nodegraph.cli import main
from nodegraph.errors import NodegraphError
from nodegraph.values import Table

TOY = Path(__file__).with_name("toy_nodes.py")


def _store(cache: Cache, name: str, value: float, when: float, n: int = 10_000) -> str:
    key = name * 64
    cache.store(key, {"t": Table({"x": np.full(n, value)})}, name, "toy")
    os.utime(cache._entry_path(key), (when, when))
    return key


def test_least_recently_used_entries_go_first(tmp_path):
    cache = Cache(tmp_path / "c")
    a, b, c = (_store(cache, k, v, 1000.0 + i) for i, (k, v) in enumerate([("a", 1.0), ("b", 2.0), ("c", 3.0)]))
    cache.load(a, {"t": Table})  # used now: the newest
    entry = cache.info().bytes // 3
    done = cache.evict(limit=2 * entry + entry // 2)
    assert done.entries == 1 and not done.over
    assert not cache.has(b) and cache.has(a) and cache.has(c)  # b was the least recently used
    assert cache.info().bytes <= 2 * entry + entry // 2 and cache.info().blobs == 2


def test_a_cache_under_its_limit_reads_no_entry(tmp_path, monkeypatch):
    """Every run ends with a look at the limit: under it (the usual case, known from file sizes) no entry is
    read, so a cached re-run's cost does not grow with the cache."""
    from nodegraph import cache as cache_module

    cache = Cache(tmp_path / "c")
    for i, name in enumerate("abc"):
        _store(cache, name, float(i), 1000.0 + i)

    def read(*args, **kwargs):
        raise AssertionError("an entry was read")

    monkeypatch.setattr(cache_module.json, "loads", read)
    done = cache.evict(limit=10 * cache.info().bytes)
    assert (done.entries, done.freed, done.over) == (0, 0, False)


def test_a_shared_blob_stays_while_an_entry_names_it(tmp_path):
    cache = Cache(tmp_path / "c")
    old = _store(cache, "a", 1.0, 1000.0)
    new = _store(cache, "b", 1.0, 2000.0)  # the same value: one blob for both
    assert cache.info().blobs == 1
    cache.evict(limit=cache.info().bytes - 1)
    assert not cache.has(old) and cache.has(new)
    assert cache.load(new, {"t": Table})["t"].columns["x"][0] == 1.0


def test_what_the_run_used_is_spared_even_above_the_limit(tmp_path):
    cache = Cache(tmp_path / "c")
    old = _store(cache, "a", 1.0, 1000.0)
    recent = _store(cache, "b", 2.0, 5000.0)
    done = cache.evict(limit=1, spare_since=4000.0)
    assert not cache.has(old) and cache.has(recent) and done.over


def test_limit_from_file_environment_and_default(tmp_path, monkeypatch):
    monkeypatch.delenv("NODEGRAPH_CACHE_LIMIT", raising=False)
    cache = Cache(tmp_path / "c")
    assert cache.limit() == DEFAULT_LIMIT
    cache.set_limit(parse_size("300 MiB"))
    assert Cache(tmp_path / "c").limit() == 300 * 2**20
    monkeypatch.setenv("NODEGRAPH_CACHE_LIMIT", "1.5GiB")
    assert cache.limit() == int(1.5 * 2**30)
    assert parse_size("800k") == 800 * 1024 and parse_size("12") == 12
    with pytest.raises(NodegraphError, match="KiB, MiB or GiB"):
        parse_size("2 TB")


def test_cli_shows_sets_and_applies_the_limit(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("NODEGRAPH_CACHE_LIMIT", raising=False)
    monkeypatch.setenv("NODEGRAPH_CACHE", str(tmp_path / "cache"))
    recipe = tmp_path / "r.yaml"
    recipe.write_text("outputs: [pts]\nnodes:\n  pts: {type: toy_points, params: {count: 50}}\n")
    assert main(["run", str(recipe), "--no-rrd", "-q", "--plugin", str(TOY)]) == 0
    cache = Cache(tmp_path / "cache")
    first = cache.info()
    assert first.entries >= 1
    for k in range(3):  # older results of other settings
        _store(cache, "abc"[k], float(k), 1000.0 + k)
    assert main(["cache", "limit", f"{first.bytes + 100}"]) == 0
    out = capsys.readouterr().out
    assert "removed 3 least recently used entries" in out and "set with nodegraph cache limit" in out
    assert cache.info().entries == first.entries  # the run's own results stayed
    assert main(["cache", "info"]) == 0
    assert f"of {format_size(first.bytes + 100)}" in capsys.readouterr().out
    _store(cache, "d", 9.0, 1000.0)
    assert main(["run", str(recipe), "--no-rrd", "-q", "--plugin", str(TOY)]) == 0  # a run ends above the limit
    assert cache.info().entries == first.entries
    assert main(["cache", "clear", "--yes"]) == 0 and not (tmp_path / "cache").exists()


MAIN = """\
seed: {seed}
outputs: [shifted]
nodes:
  pts: {{type: toy_points, params: {{count: 20000}}}}
  shifted: {{type: toy_shift, inputs: {{spheres: pts.spheres}}, params: {{dx: 1.0}}}}
"""


def test_the_run_used_last_stays_whole_when_other_work_fills_the_cache(tmp_path):
    """Issue 47: the main job, other work, the main job again (its output cached: its upstream is not loaded),
    then more work past the limit. The main job was used after the first other work, so that work goes and the
    main job stays whole (it went in part: its upstream, stored first and never read again, looked oldest)."""
    import time

    from nodegraph.executor import run_recipe
    from nodegraph.recipe import parse_recipe
    from nodegraph.registry import Registry

    registry = Registry()
    registry.add_plugin_file(TOY)
    cache = Cache(tmp_path / "c")

    def run(seed):
        return run_recipe(parse_recipe(MAIN.format(seed=seed), registry, file=f"r{seed}.yaml"), cache=cache)

    main = run(1)
    entry = cache.info().bytes // 2
    run(2)  # other work
    assert all(r.status == "cached" for r in run(1).records)  # back to the main job, from the cache
    since = time.time()
    run(3)  # more work: past the limit
    done = cache.evict(limit=4 * entry + entry // 2, spare_since=since)
    assert done.entries >= 1 and not done.over
    assert all(cache.has(key) for key in main.keys.values())  # the main job, whole


def test_the_cache_keeps_outputs_deflated(tmp_path):
    """Issue 47: a rice-bowl run wrote 313 MB of outputs into the cache, stored as they are; deflated (a mesh's
    faces, an exported file's bytes shrink most) the same value takes far less, and loads back equal."""
    from nodegraph import codec
    from nodegraph.values import Mesh

    grid = np.stack(np.meshgrid(np.arange(60.0), np.arange(60.0), [0.0]), axis=-1).reshape(-1, 3)
    faces = np.array([[i, i + 1, i + 60] for i in range(len(grid) - 61)], np.int64)
    mesh = Mesh(grid, faces, name="sheet")
    cache = Cache(tmp_path / "c")
    cache.store("m" * 64, {"mesh": mesh}, "m", "toy")
    assert cache.info().bytes < 0.5 * len(codec.encode(mesh))
    again = cache.load("m" * 64, {"mesh": Mesh})["mesh"]
    assert np.array_equal(again.faces, faces) and np.array_equal(again.vertices, grid)


class _Said:
    """A reporter that keeps what a step says, info and warnings alike."""

    def __init__(self, said: list):
        self.info = self.warn = said.append


def test_the_eviction_line_says_what_the_cache_holds_not_what_is_left(tmp_path):
    """Issue 47: '2.0 GiB of 2.0 GiB left' read as free space; the line says what the cache holds of its limit."""
    from nodegraph.cli import _trim

    cache = Cache(tmp_path / "c")
    for i, name in enumerate("abc"):
        _store(cache, name, float(i), 1000.0 + i)
    cache.set_limit(cache.info().bytes // 2)
    said = []
    _trim(cache, None, _Said(said))
    held = format_size(cache.info().bytes)
    assert len(said) == 1 and " left" not in said[0]
    assert f"the cache now holds {held} of its {format_size(cache.limit())} limit" in said[0]


STOPPED = """\
name: stopped
outputs: [moved]
nodes:
  pts: {type: toy_points, params: {count: 5}}
  moved: {type: toy_shift, inputs: {spheres: pts.spheres}}
  broken: {type: toy_fail, inputs: {spheres: moved.spheres}}
"""


def test_a_run_that_stops_keeps_the_cached_steps_it_used(tmp_path, monkeypatch):
    """Issue 47: a re-run after Ctrl-C computed again steps that had finished and were cached. A run that did not
    complete (stopped, or a node failed) marked the cached steps it used only as it ended, so the trim above the
    limit that follows it removed those it had not loaded (``pts`` here: ``moved`` was loaded, not its input)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "stopped.yaml").write_text(STOPPED)
    run = ["run", "stopped.yaml", "--plugin", str(TOY), "--cache-dir", str(tmp_path / "c"), "--no-rrd", "-q"]
    assert main(run) == 0
    cache = Cache(tmp_path / "c")
    for entry in (tmp_path / "c" / "entries").glob("*/*.json"):
        os.utime(entry, (1000.0, 1000.0))  # stored by an earlier run
    monkeypatch.setenv("NODEGRAPH_CACHE_LIMIT", "1")  # above the limit: all but what the run used goes
    assert main([*run, "--output", "broken"]) == 1
    kept = {entry.stem for entry in (tmp_path / "c" / "entries").glob("*/*.json")}
    nodes = {json.loads(cache._entry_path(key).read_text())["node"] for key in kept}
    assert nodes == {"pts", "moved"}, nodes


def test_the_latest_run_of_each_recipe_goes_last(tmp_path):
    """Issue 47: a full shared cache evicted the main job within 20 minutes of other work, and going back to it
    took 86 s instead of 1 s. The entries a recipe's latest run used go only after every other entry."""
    cache = Cache(tmp_path / "c")
    main_job = _store(cache, "a", 1.0, 1000.0)  # the main job's run, the oldest
    others = [_store(cache, name, float(i), 2000.0 + i) for i, name in enumerate("bcd", 2)]
    cache.keep_run("graphs/ikura_don.yaml", [main_job])
    cache.keep_run("graphs/rice_bowl.yaml --draft", others[-1:])
    entry = cache.info().bytes // 4
    done = cache.evict(limit=2 * entry + entry // 2)
    assert done.entries == 2 and cache.has(main_job) and cache.has(others[-1])  # b and c went, though newer
    cache.keep_run("graphs/ikura_don.yaml", others[-1:])  # the main job ran again, without a
    cache.evict(limit=entry + entry // 2)
    assert not cache.has(main_job) and cache.has(others[-1])


def test_a_run_records_the_entries_it_used(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "toyrun.yaml").write_text(
        "name: toyrun\noutputs: [pts.spheres]\nnodes:\n  pts: {type: toy_points, params: {count: 8}}\n"
    )
    cache = Cache(tmp_path / "c")
    assert (
        main(["run", "toyrun.yaml", "-q", "--no-rrd", "--cache-dir", str(cache.directory), "--plugin", str(TOY)]) == 0
    )
    (entry,) = (cache.directory / "entries").glob("*/*.json")
    assert cache.latest_runs() == {entry.stem}


def test_an_eviction_says_once_what_went_the_limit_and_how_to_raise_it(tmp_path, monkeypatch, capsys):
    """Issue 47: a full cache evicted 74 entries, the main job's among them, in one line that scrolled away above the
    run's table and named neither what went nor how to keep more. One line, below the table, names the steps whose
    results went, the run that will compute its own again, the limit, where the cache is and how to raise it."""
    from nodegraph.cli import _trim

    monkeypatch.delenv("NODEGRAPH_CACHE_LIMIT", raising=False)
    cache = Cache(tmp_path / "c")
    old = [_store(cache, name, float(i), 1000.0 + i) for i, name in enumerate("abc")]
    cache.keep_run("/r/ikura_don.yaml --draft", old[:1])
    cache.set_limit(cache.info().bytes // 4)
    said = []
    _trim(cache, None, _Said(said))
    (line,) = said
    assert line.startswith("cache: removed 3 least recently used entries (") and ": b, c, a)" in line, line
    assert "the next nodegraph run /r/ikura_don.yaml --draft computes its own again" in line, line
    assert f"of its {format_size(cache.limit())} limit, in {cache.directory}; to keep more, raise it: " in line
    assert line.endswith("nodegraph cache limit 1MiB (or $NODEGRAPH_CACHE_LIMIT)"), line
    # in a run: below the table, and the run's last line says where its outputs are
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("NODEGRAPH_CACHE_LIMIT", "1")
    (tmp_path / "r.yaml").write_text("outputs: [pts]\nnodes:\n  pts: {type: toy_points, params: {count: 50}}\n")
    run = ["run", "r.yaml", "--no-rrd", "--plugin", str(TOY), "--cache-dir", str(cache.directory)]
    for seed in ("1", "2"):
        assert main([*run, "--set", f"seed={seed}"]) == 0
        for entry in (cache.directory / "entries").glob("*/*.json"):
            os.utime(entry, (1000.0, 1000.0))  # used by an earlier run, not the one that ends next
    captured = capsys.readouterr()
    err = captured.err
    second = err[err.rindex("outputs go to") :]  # the second run's: one line below its table
    assert second.index("under 1 s") < second.index("cache: removed 1 least recently used entries ("), err
    assert "KiB: pts); the cache now holds" in second, err
    assert second.count("cache:") == 1 and "raise it: $NODEGRAPH_CACHE_LIMIT (now 1)" in second, err
    last = captured.out.splitlines()[-1]
    assert last.startswith(f"the outputs are in {tmp_path / 'outputs' / 'r' / 'set_seed=2'}{os.sep}"), last
