"""``nodegraph watch``: a real process, a real file edited under it: each save re-runs only what the edit
changed, from the inputs it holds in memory, says when each node that ran is in the recording, and a bad
edit shows its error at its line and leaves the last good outputs as they were."""

import queue
import shutil
import subprocess
import sys
import threading
import time

from .conftest import TOY
from .test_validation import VALID


def _lines(proc) -> queue.Queue:
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in proc.stdout], daemon=True).start()
    return lines


def _until(lines: queue.Queue, text: str, seen: list, timeout: float = 120.0) -> float:
    """Read lines until one contains ``text``; when it came."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        try:
            line = lines.get(timeout=1.0)
        except queue.Empty:
            continue
        seen.append(line)
        if text in line:
            return time.perf_counter()
    raise AssertionError(f"no line with {text!r} in:\n{''.join(seen)}")


def test_watch_reruns_what_an_edit_changed_and_keeps_the_last_good_result(tmp_path):
    recipe = tmp_path / "r.yaml"
    recipe.write_text(VALID.replace("outputs: [merge.spheres]", "outputs: [shifted.spheres]"))
    out = tmp_path / "out"
    command = [sys.executable, "-m", "nodegraph.cli", "watch", str(recipe), "--plugin", str(TOY), "--runs", "4"]
    command += ["--cache-dir", str(tmp_path / "cache"), "--out-dir", str(out), "--no-rrd"]
    proc = subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines, seen = _lines(proc), []
    try:
        _until(lines, "watching", seen)
        first = (out / "shifted.npz").read_bytes()

        seen.clear()
        saved = time.perf_counter()
        recipe.write_text(recipe.read_text().replace("dx: 1.5", "dx: 2.5"))  # an edit of one node's parameter
        done = _until(lines, "run 2 done", seen)
        rows = {line.split("│")[1].strip(): line for line in seen if line.count("│") > 3}
        assert "cached" in rows["pts"] and "ran" in rows["shifted"]  # only the edited node ran again
        assert any(line.startswith("run 2: shifted updated") for line in seen), "".join(seen)
        second = (out / "shifted.npz").read_bytes()
        assert second != first
        assert done - saved < 10.0, f"{done - saved:.1f} s from the save to the new outputs"

        seen.clear()
        shutil.rmtree(tmp_path / "cache")  # the session holds the last run's values: pts is not run again
        recipe.write_text(recipe.read_text().replace("dx: 2.5", "dx: 3.5"))
        _until(lines, "run 3 done", seen)
        rows = {line.split("│")[1].strip(): line for line in seen if line.count("│") > 3}
        assert "cached" in rows["pts"] and "ran" in rows["shifted"], "".join(seen)
        third = (out / "shifted.npz").read_bytes()

        seen.clear()
        recipe.write_text(recipe.read_text().replace("dx: 3.5", "dx: oops"))  # a bad edit
        _until(lines, "run 4: not run; the last good outputs stay", seen)
        assert any("r.yaml:13" in line and "dx" in line for line in seen), "".join(seen)  # file, line, parameter
        assert (out / "shifted.npz").read_bytes() == third
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()


def test_what_an_edit_ran_reaches_the_recording_before_what_was_cached(tmp_path):
    """The nodes an edit re-ran are sent first (a viewer shows the change without waiting for the cached rest)."""
    from rerun.chunk import RrdReader

    from nodegraph.cache import Cache
    from nodegraph.executor import run_recipe
    from nodegraph.recipe import parse_recipe
    from nodegraph.registry import Registry

    registry = Registry()
    registry.add_plugin_file(TOY)
    cache = Cache(tmp_path / "cache")
    text = VALID
    run_recipe(parse_recipe(text, registry, file="r.yaml"), cache=cache, rrd=tmp_path / "a.rrd")
    edited = parse_recipe(text.replace("dx: 1.5", "dx: 2.5"), registry, file="r.yaml")
    run_recipe(edited, cache=cache, rrd=tmp_path / "b.rrd")
    nodes = [c.entity_path.split("/")[1] for c in RrdReader(str(tmp_path / "b.rrd")).stream().to_chunks()]
    ran = [i for i, n in enumerate(nodes) if n in ("shifted", "phys", "merge")]
    cached = [i for i, n in enumerate(nodes) if n == "pts"]
    assert ran and cached and max(ran) < min(cached), nodes


SLOW = """\
name: toy
seed: 3
outputs: [{output}]
nodes:
  pts:
    type: toy_points
    params: {{count: 20, scale: 2.0}}
{middle}"""


def _watch(tmp_path, text: str, runs: int):
    recipe = tmp_path / "r.yaml"
    recipe.write_text(text)
    command = [sys.executable, "-m", "nodegraph.cli", "watch", str(recipe), "--plugin", str(TOY), "--runs", str(runs)]
    command += ["--cache-dir", str(tmp_path / "cache"), "--out-dir", str(tmp_path / "out")]
    proc = subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    return recipe, proc


def _wait_for_start(folder, proc, lines, seen, timeout: float = 120.0) -> None:
    deadline = time.time() + timeout
    while not (folder.is_dir() and any(folder.iterdir())):
        assert time.time() < deadline and proc.poll() is None, "".join(seen) + "".join(list(lines.queue))
        time.sleep(0.05)


def test_a_save_during_a_long_step_it_no_longer_needs_stops_that_step(tmp_path):
    """The artist saves while a slow step computes what the edit changes: the watch stops that step at once
    and runs the new version, instead of finishing the old one first (30 s here)."""
    started = tmp_path / "started"
    middle = f"""\
  shifted:
    type: toy_shift
    inputs: {{spheres: pts.spheres}}
    params: {{dx: 1.5}}
  slow:
    type: toy_slow
    inputs: {{spheres: shifted.spheres}}
    params: {{seconds: 30.0, started: {started}}}
"""
    recipe, proc = _watch(tmp_path, SLOW.format(output="slow.spheres", middle=middle), runs=2)
    lines, seen = _lines(proc), []
    try:
        _wait_for_start(started, proc, lines, seen)
        saved = time.perf_counter()
        recipe.write_text(recipe.read_text().replace("dx: 1.5", "dx: 2.5").replace("seconds: 30.0", "seconds: 0.5"))
        done = _until(lines, "run 2 done", seen, timeout=60)
        assert any(line.startswith("first run: stopped at slow") for line in seen), "".join(seen)
        assert done - saved < 10.0, f"{done - saved:.1f} s from the save to the new outputs"
        rows = {line.split("│")[1].strip(): line for line in seen if line.count("│") > 3}
        assert "cached" in rows["pts"] and "ran" in rows["shifted"] and "ran" in rows["slow"], "".join(seen)
        assert (tmp_path / "out" / "slow.npz").is_file()
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()


def test_a_save_that_still_needs_the_running_step_lets_it_finish(tmp_path):
    """A long step the edit does not touch (a simulation under a shading edit) is not thrown away: it runs on,
    the old run stops before the step the edit changed, and the new run takes the slow result from memory."""
    started = tmp_path / "started"
    middle = f"""\
  slow:
    type: toy_slow
    inputs: {{spheres: pts.spheres}}
    params: {{seconds: 3.0, started: {started}}}
  shifted:
    type: toy_shift
    inputs: {{spheres: slow.spheres}}
    params: {{dx: 1.5}}
"""
    recipe, proc = _watch(tmp_path, SLOW.format(output="shifted.spheres", middle=middle), runs=2)
    lines, seen = _lines(proc), []
    try:
        _wait_for_start(started, proc, lines, seen)
        recipe.write_text(recipe.read_text().replace("dx: 1.5", "dx: 2.5"))
        _until(lines, "run 2 done", seen, timeout=60)
        assert not any(line.startswith("first run: stopped at slow") for line in seen), "".join(seen)
        second = "".join(seen).split("watching")[-1]  # the second run's lines
        rows = {line.split("│")[1].strip(): line for line in second.splitlines() if line.count("│") > 3}
        assert "cached" in rows["slow"] and "ran" in rows["shifted"], second
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()


def test_the_first_edit_pays_no_first_load_and_finds_the_inputs_in_memory(tmp_path):
    """Between saves the watch loads the inputs of the quick nodes its first run took from the cache and runs
    them once (``WatchSession.warm_up``): the first edit then pays neither a node's first load in the process
    (a kernel loaded from numba's cache, 1 s here) nor a read of its inputs (the cache is gone here)."""
    trace = tmp_path / "trace"
    middle = f"""\
  shifted:
    type: toy_shift
    inputs: {{spheres: pts.spheres}}
    params: {{dx: 1.5}}
  scaled:
    type: toy_first_load
    inputs: {{spheres: shifted.spheres}}
    params: {{scale: 2.5, load_seconds: 1.0, trace: {trace}}}
"""
    text = SLOW.format(output="scaled.spheres", middle=middle)
    recipe = tmp_path / "r.yaml"
    recipe.write_text(text)
    cached = [sys.executable, "-m", "nodegraph.cli", "run", str(recipe), "--plugin", str(TOY), "-q"]
    cached += ["--cache-dir", str(tmp_path / "cache"), "--out-dir", str(tmp_path / "first")]
    subprocess.run(cached, cwd=tmp_path, check=True, capture_output=True)  # the watch's first run: all cached
    assert trace.read_text().split() == ["load", "call"]
    recipe, proc = _watch(tmp_path, text, runs=2)
    lines, seen = _lines(proc), []
    try:
        _until(lines, "ready:", seen, timeout=60)
        shutil.rmtree(tmp_path / "cache")
        recipe.write_text(recipe.read_text().replace("scale: 2.5", "scale: 3.5"))
        _until(lines, "run 2 done", seen, timeout=60)
        second = "".join(seen).split("watching")[-1]  # the second run's lines
        rows = {line.split("│")[1].strip(): line for line in second.splitlines() if line.count("│") > 3}
        assert "ran" in rows["scaled"] and "cached" in rows["shifted"] and "cached" in rows["pts"], second
        assert trace.read_text().split()[-2:] == ["call", "call"], trace.read_text()  # the edit's call: no load
        assert proc.wait(timeout=60) == 0
    finally:
        proc.kill()


def test_a_rehearsal_whose_input_is_gone_from_the_cache_skips_its_step_instead_of_computing_it(
    tmp_path, registry, cache, monkeypatch
):
    """The warm-up only loads: an input whose cache entry went after the warm-up planned (evicted, cleared, torn)
    is not computed there, where it could take minutes, print as a run and outlast a save; its step is skipped."""
    from nodegraph.cache import Cache
    from nodegraph.executor import run_recipe
    from nodegraph.recipe import parse_recipe
    from nodegraph.watch import WatchSession

    trace = tmp_path / "trace"
    middle = f"""\
  scaled:
    type: toy_first_load
    inputs: {{spheres: pts.spheres}}
    params: {{scale: 2.5, trace: {trace}}}
  shifted:
    type: toy_shift
    inputs: {{spheres: scaled.spheres}}
    params: {{dx: 1.5}}
"""
    recipe = parse_recipe(SLOW.format(output="shifted.spheres", middle=middle), registry, file="toy.yaml")
    result = run_recipe(recipe, cache=cache)
    assert trace.read_text().split().count("call") == 1
    session = WatchSession()
    session.keep(result)
    scaled = next(inst for inst in result.keys if inst.node == "scaled")
    cache.discard(result.keys[scaled])  # gone after the warm-up found it: it still counts as cached
    monkeypatch.setattr(Cache, "has", lambda self, key: True)
    assert "shifted" in list(session.warm_up(cache))  # its turn came ('scaled', with no entry, has no turn)
    assert trace.read_text().split().count("call") == 1, trace.read_text()  # 'scaled' was not computed for it


def test_the_first_run_says_it_is_the_watchs_start_not_a_save(capsys):
    """Issue 47: the first run said "run 1: pts updated 0.05 s after the save was seen" where nothing was saved."""
    from nodegraph.plan import Instance
    from nodegraph.watch import WatchSession, run_name

    session = WatchSession()
    session.begin(1, time.perf_counter())
    session.ran(Instance("pts"))
    first = capsys.readouterr().out
    assert first.startswith("first run: pts ready ") and first.rstrip().endswith("after the watch started"), first
    session.begin(2, time.perf_counter())
    session.ran(Instance("pts"))
    assert capsys.readouterr().out.startswith("run 2: pts updated ")
    assert run_name(1) == "first run" and run_name(3) == "run 3"
