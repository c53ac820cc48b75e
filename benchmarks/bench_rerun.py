"""Rerun logging per node: cold (outputs logged from their values) against cached (the fragment kept
with the cache entry appended to the recording), beside the time to load the node's values.

Each repeat builds a scratch cache from the source cache — entries without their Rerun fragments, blobs
linked — then runs the recipe twice with a recording: run A finds no fragment, so it loads every value
and logs it (the cold logging path, which keeps a fragment), run B appends the kept fragments (values
not loaded unless an output needs them). Entries missing from the source cache are computed first (no
recording). Both recordings are compared with ``rerun rrd compare``.

Run: python benchmarks/bench_rerun.py [graphs/ikura_don.yaml] [--cache-dir .nodegraph/cache] [--repeat 1]
     python benchmarks/bench_rerun.py --quick   # a toy recipe, seconds
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

from nodegraph.cache import Cache, default_cache_dir
from nodegraph.executor import run_recipe
from nodegraph.recipe import load_recipe
from nodegraph.registry import default_registry
from nodegraph.rerun_log import RunRecording

ROOT = Path(__file__).resolve().parent.parent
TOY = ROOT / "tests" / "engine" / "toy_nodes.py"
QUICK = """\
name: rerun_quick
seed: 1
outputs: [surf]
nodes:
  pts: {type: toy_points, variants: 4, params: {count: 2000}}
  merge: {type: toy_merge, inputs: {parts: pts.spheres}}
  slow: {type: toy_slow, inputs: {spheres: merge.spheres}}
  surf: {type: toy_sphere_mesh, inputs: {spheres: slow.spheres}}
"""


def scratch_cache(source: Path, target: Path) -> Cache:
    """A copy of ``source``'s entries without their Rerun fragments; blobs hard-linked (copied across disks)."""
    for entry in (source / "entries").glob("*/*.json"):
        manifest = json.loads(entry.read_bytes())
        manifest.pop("rerun", None)
        out = target / "entries" / entry.parent.name / entry.name
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(manifest))
    for blob in (source / "blobs").glob("*/*.npz"):
        out = target / "blobs" / blob.parent.name / blob.name
        out.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.link(blob, out)
        except OSError:
            shutil.copyfile(blob, out)
    return Cache(target)


def node_times(result) -> dict[str, tuple[float, float]]:
    """Per node (variants summed): wall time as recorded (for a cached node: loading its values) and log time."""
    out: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0])
    for record in result.records:
        name = record.node.split("[")[0]
        out[name][0] += record.seconds or 0.0
        out[name][1] += record.log_seconds or 0.0
    return {k: (v[0], v[1]) for k, v in out.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recipe", nargs="?", type=Path, default=ROOT / "graphs" / "ikura_don.yaml")
    parser.add_argument("--cache-dir", type=Path, default=None, help="source cache (default: the usual one)")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--quick", action="store_true", help="a toy recipe in a fresh cache, 3 repeats (seconds)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        if args.quick:
            args.recipe, args.repeat, args.cache_dir = tmp / "rerun_quick.yaml", 3, tmp / "source"
            args.recipe.write_text(QUICK)
        registry = default_registry(plugins=[str(TOY)] if args.quick else [])
        recipe = load_recipe(args.recipe, registry)
        source = Cache(args.cache_dir or default_cache_dir())
        start = time.perf_counter()
        run_recipe(recipe, cache=source)  # fills what the source cache lacks
        print(f"source cache {source.directory}: ready in {time.perf_counter() - start:.1f} s")
        cold, cached, whole = defaultdict(list), defaultdict(list), defaultdict(list)
        sizes: dict[str, int] = {}
        same = []
        for i in range(args.repeat):
            cache = scratch_cache(source.directory, tmp / f"scratch{i}")
            for label, rrd, store in (("A", tmp / f"a{i}.rrd", cold), ("B", tmp / f"b{i}.rrd", cached)):
                start = time.perf_counter()
                result = run_recipe(recipe, cache=cache, rrd=rrd)
                whole[label].append(time.perf_counter() - start)
                for node, times in node_times(result).items():
                    store[node].append(times)
            for entry in (cache.directory / "entries").glob("*/*.json"):
                manifest = json.loads(entry.read_bytes())
                sizes[manifest["node"]] = sizes.get(manifest["node"], 0) + manifest["rerun"]["size"]
            compare = [sys.executable, "-m", "rerun", "rrd", "compare", "--unordered"]
            done = subprocess.run([*compare, str(tmp / f"a{i}.rrd"), str(tmp / f"b{i}.rrd")], capture_output=True)
            same.append(done.returncode == 0)
            if i == args.repeat - 1:
                probe = interleaved(recipe, cache, result.keys, tmp / "probe.rrd", max(2, args.repeat))
            shutil.rmtree(cache.directory)
    sizes = {k: v // args.repeat for k, v in sizes.items()}
    print(
        f"\n{recipe.name}: Rerun logging per node, median of {args.repeat}; load average "
        f"{os.getloadavg()[0]:.2f} on {os.cpu_count()} cores\n"
        "load: reading and decoding the node's stored values; cold log: logging them into a fragment and "
        "appending it; cached replay: appending the kept fragment (values not loaded)\n"
    )
    header = ["node", "load ms", "cold log ms", "cached replay ms", "replay / cold log", "replay / load", "fragment MB"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    totals = [0.0, 0.0, 0.0]
    order = sorted(cold, key=lambda n: -statistics.median(t[1] for t in cold[n]))
    for node in order:
        load = statistics.median(t[0] for t in cold[node])
        log = statistics.median(t[1] for t in cold[node])
        replay = statistics.median(t[1] for t in cached[node])
        totals = [totals[0] + load, totals[1] + log, totals[2] + replay]
        print(
            f"| {node} | {load * 1e3:.1f} | {log * 1e3:.1f} | {replay * 1e3:.1f} | {_ratio(replay, log)} | "
            f"{_ratio(replay, load)} | {sizes.get(node, 0) / 2**20:.2f} |"
        )
    print(
        f"| **all** | {totals[0] * 1e3:.1f} | {totals[1] * 1e3:.1f} | {totals[2] * 1e3:.1f} | "
        f"{_ratio(totals[2], totals[1])} | {_ratio(totals[2], totals[0])} | {sum(sizes.values()) / 2**20:.2f} |"
    )
    print(
        f"\nthe same, one node at a time, load and replay alternated {max(2, args.repeat)} times (the least time "
        "each); replay flushed to the file, so it includes writing the chunks\n"
    )
    print("| node | load ms | replay + flush ms | replay / load |\n|---|---|---|---|")
    for node in sorted(probe, key=lambda n: -probe[n][1]):
        load, replay = probe[node]
        print(f"| {node} | {load * 1e3:.1f} | {replay * 1e3:.1f} | {_ratio(replay, load)} |")
    load, replay = (sum(v[j] for v in probe.values()) for j in (0, 1))
    print(f"| **all** | {load * 1e3:.1f} | {replay * 1e3:.1f} | {_ratio(replay, load)} |")
    print(
        f"\nwhole run with a recording, median: A (cold logging) {statistics.median(whole['A']):.2f} s, "
        f"B (fragments appended) {statistics.median(whole['B']):.2f} s; "
        f"recordings A and B identical in content (rerun rrd compare): {all(same)}"
    )
    if not all(same):
        raise SystemExit("the cached run's recording differs from the cold run's")


def interleaved(recipe, cache: Cache, keys, rrd: Path, repeat: int) -> dict[str, tuple[float, float]]:
    """Per node: the least time over ``repeat`` alternations of loading its instances' values and of
    appending their kept fragments to a recording (flushed)."""
    recording = RunRecording(rrd, "probe")
    by_node = defaultdict(list)
    for inst, key in keys.items():
        by_node[inst.node].append((inst, key))
    out = {}
    for node, instances in by_node.items():
        expected = {port: o.type for port, o in recipe.nodes[node].spec.outputs.items()}
        loads, replays = [], []
        for _ in range(repeat):
            start = time.perf_counter()
            for _inst, key in instances:
                cache.load(key, expected)
            loads.append(time.perf_counter() - start)
            start = time.perf_counter()
            for inst, key in instances:
                fragment = cache.fragment(key, recording.loggers)
                recording.append(fragment.path, inst.entity, fragment.logged, fragment.entity, live=False)
            recording.stream.flush()
            replays.append(time.perf_counter() - start)
        out[node] = (min(loads), min(replays))
    recording.close()
    return out


def _ratio(a: float, b: float) -> str:
    return f"{a / b:.2f}" if b > 0 else ""


if __name__ == "__main__":
    main()
