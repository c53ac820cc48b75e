"""What an artist waits for (issues 27 and 28): a cached re-run, a watched edit, a draft from an empty cache.

- ``cached``: ``nodegraph run RECIPE`` again with every node cached, outputs and recording in place (target
  ≤ 1.5 s). The first run (computing what the cache lacks) is not timed.
- ``watch``: ``nodegraph watch RECIPE`` on a copy of the recipe beside it; each edit rewrites a parameter of
  one node in the file (default ``shade.baked_ambient``); the time from the save to the watcher's "run N done" line
  (outputs and recording written), with the CPU seconds the watcher spent meanwhile (target ≤ 2 s). Each save
  comes ``--pause`` seconds after the watcher says it is watching; with ``--warm``, after it says its warm-up
  between saves is done (``nodegraph/watch.py``: a save during the warm-up stops it, and pays what it left).
- ``resave``: a save while the preview of the save before it renders (``--delay`` seconds into it): the time
  from that save to its change in the recording (target ≤ 2 s, as for any save: the watch stops the preview).
- ``draft``: ``nodegraph run RECIPE --draft`` with an empty node cache (compiled kernels kept; target ≤ 15 s).

Wall times carry the machine's load (printed); CPU seconds are the comparable figures.
Run: python benchmarks/bench_latency.py [cached|watch|resave|draft ...] [--recipe graphs/ikura_don.yaml ...]
(``--quick``: the engine's toy recipe, one of each, in seconds: a smoke run)
"""

from __future__ import annotations

import argparse
import os
import queue
import random
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CLI = [sys.executable, "-m", "nodegraph.cli"]
QUICK_RECIPE = """\
name: toy
seed: 3
effects: [gravity]
outputs: [merge.spheres]
draft: {pts.count: 8}
nodes:
  pts:
    type: toy_points
    params: {count: 20, scale: 2.0}
  shifted:
    type: toy_shift
    inputs: {spheres: pts.spheres}
    params: {dx: 1.5}
  phys:
    type: toy_physics
    inputs: {spheres: shifted.spheres}
  merge:
    type: toy_merge
    inputs: {parts: [pts.spheres, phys.spheres]}
"""


def load() -> str:
    return " ".join(f"{x:.1f}" for x in os.getloadavg())


def timed_run(args: list[str]) -> tuple[float, float, str]:
    """Wall and CPU seconds (the child's user + system) of one CLI command; its output."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(CLI + args, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(args)} failed:\n{done.stderr[-3000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), done.stderr


def bench_cached(recipe: str, repeat: int, extra: list[str]) -> list[tuple]:
    timed_run(["run", recipe, "-q", *extra])  # whatever the cache lacks is computed here, not timed
    rows = []
    for i in range(repeat):
        wall, cpu, _ = timed_run(["run", recipe, "-q", *extra])
        rows.append((f"cached re-run {i + 1}", recipe, f"{wall:.2f}", f"{cpu:.2f}", "≤ 1.5", load()))
    return rows


def bench_draft(recipe: str, extra: list[str]) -> list[tuple]:
    """One draft from an empty node cache, recording and preview included (what ``--draft`` promises)."""
    with tempfile.TemporaryDirectory(prefix="bench-draft-") as tmp:
        args = ["run", recipe, "--draft", "--cache-dir", f"{tmp}/cache", "--out-dir", f"{tmp}/out", *extra]
        wall, cpu, err = timed_run(args)
    slowest = sorted(_node_times(err).items(), key=lambda kv: -kv[1])[:5]
    note = ", ".join(f"{n} {s:.1f}" for n, s in slowest)
    return [("draft, empty node cache", recipe, f"{wall:.1f}", f"{cpu:.1f}", "≤ 15", load(), note)]


def _node_times(summary: str) -> dict[str, float]:
    """Seconds per node from a run's summary table."""
    from nodegraph.report import parse_duration

    out = {}
    wall = None
    for line in summary.splitlines():
        cells = [c.strip() for c in line.replace("┃", "│").split("│")]
        if "wall time" in cells:  # the header: the table drops its type column where it would not fit
            wall = cells.index("wall time")
        elif wall is not None and len(cells) > wall:
            try:
                out[cells[1]] = parse_duration(cells[wall])
            except ValueError:
                continue
    return out


def _cpu_seconds(pid: int) -> float:
    """User + system CPU seconds of a running process (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def set_param(text: str, node: str, param: str, value: str) -> str:
    """The recipe text with ``param: value`` in node ``node``'s params (a ``params:`` line added or replaced)."""
    block = re.search(rf"^  {re.escape(node)}:[^\n]*\n((?:    [^\n]*\n|\s*\n)*)", text, re.M)
    if block is None:
        raise SystemExit(f"no node '{node}' in the recipe")
    body = block.group(1)
    line = re.search(r"^    params: \{(.*)\}[^\n]*$", body, re.M)
    if line is None:
        new_body = body.rstrip("\n") + f"\n    params: {{{param}: {value}}}\n"
    else:
        items = [p.strip() for p in line.group(1).split(",") if p.strip() and not p.strip().startswith(f"{param}:")]
        new_body = body.replace(line.group(0), f"    params: {{{', '.join(items + [f'{param}: {value}'])}}}")
    return text[: block.start(1)] + new_body + text[block.end(1) :]


class Watcher:
    """``nodegraph watch`` on a copy of the recipe beside it (relative asset paths still resolve), its output
    lines read as they come."""

    def __init__(self, recipe: str, runs: int, draft: bool, extra: list[str], out: str):
        source = ROOT / recipe
        self.copy = source.with_name(f".bench_watch_{source.name}")
        shutil.copy(source, self.copy)
        command = CLI + ["watch", str(self.copy), "--out-dir", out, "--runs", str(runs), *extra]
        command += ["--draft"] if draft else []
        self.proc = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.lines: queue.Queue = queue.Queue()
        threading.Thread(target=lambda: [self.lines.put(x) for x in self.proc.stdout], daemon=True).start()

    def save(self, node: str, param: str, value: str) -> tuple[float, float]:
        """Rewrite one parameter in the file; when, and the watcher's CPU seconds then."""
        cpu = _cpu_seconds(self.proc.pid)
        saved = time.perf_counter()
        self.copy.write_text(set_param(self.copy.read_text(), node, param, value))
        return saved, cpu

    def until(self, text: str, seen: list, also: str | None = None) -> tuple[float, float | None, float | None]:
        """Read lines until one contains ``text``; when it came, and when (with the watcher's CPU seconds
        then) a line containing ``also`` came before it (None: none did, as with an engine that does not
        say when a node reaches the recording)."""
        deadline, found = time.time() + 900, (None, None)
        while time.time() < deadline:
            try:
                line = self.lines.get(timeout=1.0)
            except queue.Empty:
                if self.proc.poll() is not None:
                    break
                continue
            seen.append(line)
            if also is not None and also in line:
                found = (time.perf_counter(), _cpu_seconds(self.proc.pid))
            if text in line:
                return time.perf_counter(), *found
        raise SystemExit(f"no {text!r}:\n{''.join(seen)[-3000:]}")

    def close(self) -> None:
        self.proc.kill()
        self.copy.unlink(missing_ok=True)


def bench_watch(
    recipe: str, edits: int, draft: bool, target: str, values: list[str], extra: list[str], pause: float, warm: bool
) -> list[tuple]:
    """Each save ``pause`` seconds after the watcher is ready: after its "watching" line, or with ``warm``
    after its "warm:" line (the warm-up between saves done)."""
    node, param = target.split(".")
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-watch-") as tmp:
        watcher = Watcher(recipe, edits + 1, draft, extra, f"{tmp}/out")
        try:
            for i in range(edits):
                watcher.until("warm:" if warm else "watching", [])
                time.sleep(pause)
                saved, cpu0 = watcher.save(node, param, values[i % len(values)])
                seen: list = []
                done, shown, shown_cpu = watcher.until(f"run {i + 2} done", seen, also=f"run {i + 2}: {node} updated")
                cpu = _cpu_seconds(watcher.proc.pid) - cpu0
                ran = {n: s for n, s in _node_times("".join(seen)).items() if s > 0}
                note = ", ".join(f"{n} {s:.2f}" for n, s in sorted(ran.items(), key=lambda kv: -kv[1])[:5])
                case, now = f"watch edit {i + 1}: {target}", load()
                if shown is not None:
                    row = (
                        f"{case}, {node} in the recording",
                        recipe,
                        f"{shown - saved:.2f}",
                        f"{shown_cpu - cpu0:.2f}",
                    )
                    rows.append((*row, "≤ 2", now))
                row = (f"{case}, all outputs written", recipe, f"{done - saved:.2f}", f"{cpu:.2f}", "", now, note)
                rows.append(row)
            watcher.proc.wait(timeout=120)
        finally:
            watcher.close()
    return rows


def bench_resave(recipe: str, draft: bool, target: str, values: list[str], delay: float, extra: list[str]) -> list:
    """A save while the preview of the previous save renders: from that save to its change in the recording.
    An engine that finishes the preview first adds what was left of it."""
    node, param = target.split(".")
    with tempfile.TemporaryDirectory(prefix="bench-watch-") as tmp:
        watcher = Watcher(recipe, 3, draft, extra, f"{tmp}/out")
        try:
            watcher.until("watching", [])
            watcher.save(node, param, values[0])
            watcher.until(f"run 2: {node} updated", [])
            time.sleep(delay)  # the preview is rendering now
            saved, cpu0 = watcher.save(node, param, values[1 % len(values)])
            seen: list = []
            shown, _, _ = watcher.until(f"run 3: {node} updated", seen)
            cpu = _cpu_seconds(watcher.proc.pid) - cpu0
            stopped = next((line.strip() for line in seen if line.startswith("run 2: stopped")), "run 2 finished first")
        finally:
            watcher.close()
    case = f"watch: a save {delay:g} s into the preview, {node} in the recording"
    return [(case, recipe, f"{shown - saved:.2f}", f"{cpu:.2f}", "≤ 2", load(), stopped)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("what", nargs="*", help="any of cached, watch, resave, draft (default: cached, watch, draft)")
    parser.add_argument("--recipe", action="append", default=None, help="default graphs/ikura_don.yaml")
    parser.add_argument("--repeat", type=int, default=3, help="cached re-runs timed")
    parser.add_argument("--edits", type=int, default=3, help="saves timed in watch")
    parser.add_argument("--full", action="store_true", help="watch the full recipe, not its draft")
    parser.add_argument("--pause", type=float, default=1.0, help="watch: seconds from the watcher ready to a save")
    parser.add_argument("--warm", action="store_true", help="watch: ready once its warm-up is done, not at once")
    parser.add_argument("--param", default="shade.baked_ambient", help="NODE.PARAM that watch edits")
    parser.add_argument("--delay", type=float, default=2.0, help="resave: seconds into the preview of the first save")
    parser.add_argument("--values", default=None, help="values written in turn (default: new random ones in 0.2–0.7)")
    parser.add_argument("--cache-dir", default=None, help="cache for cached and watch (default: the usual one)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="NODE.PARAM=VALUE")
    parser.add_argument("--quick", action="store_true", help="a toy recipe, one of each (a smoke run for CI)")
    args = parser.parse_args()
    args.what = args.what or ["cached", "watch", "draft"]
    cases = {"cached", "watch", "resave", "draft"}
    if set(args.what) - cases:
        parser.error(f"unknown case(s) {sorted(set(args.what) - cases)}: {', '.join(sorted(cases))}")
    recipes = args.recipe or ["graphs/ikura_don.yaml"]
    common = [f"--set={o}" for o in args.overrides]  # every command
    cached = ["--cache-dir", args.cache_dir] if args.cache_dir else []  # cached re-runs and watch
    scratch = None
    if args.quick:  # the toy node plugin of the engine's tests, in a scratch folder
        scratch = tempfile.TemporaryDirectory(prefix="bench-latency-")
        recipe = Path(scratch.name) / "toy.yaml"
        recipe.write_text(QUICK_RECIPE)
        recipes, args.repeat, args.edits, args.param, args.values = [str(recipe)], 2, 1, "shifted.dx", "2.5"
        common += ["--plugin", str(ROOT / "tests" / "engine" / "toy_nodes.py")]
        cached = ["--cache-dir", f"{scratch.name}/cache", "--out-dir", f"{scratch.name}/out"]
    rows = []
    for recipe in recipes:
        if "cached" in args.what:
            rows += bench_cached(recipe, args.repeat, cached + common)
        if "watch" in args.what:
            values = (
                args.values.split(",")
                if args.values
                else [f"{random.uniform(0.2, 0.7):.6f}" for _ in range(args.edits)]
            )
            rows += bench_watch(
                recipe, args.edits, not args.full, args.param, values, cached[:2] + common, args.pause, args.warm
            )
        if "resave" in args.what:
            values = args.values.split(",") if args.values else [f"{random.uniform(0.2, 0.7):.6f}" for _ in range(2)]
            rows += bench_resave(recipe, not args.full, args.param, values, args.delay, cached[:2] + common)
        if "draft" in args.what:
            rows += bench_draft(recipe, common)
    if scratch is not None:
        scratch.cleanup()
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):  # every process compiles the project's modules (≈ 0.1 CPU s)
        print("PYTHONDONTWRITEBYTECODE is set: no bytecode is written, so each command compiles the project's modules")
    header = ("case", "recipe", "wall s", "CPU s", "target s", "load 1/5/15", "slowest nodes (s)")
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for row in rows:
        print("| " + " | ".join(row + ("",) * (len(header) - len(row))) + " |")


if __name__ == "__main__":
    main()
