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
