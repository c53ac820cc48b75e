"""Engine overhead: load + validate a 50-node recipe, and the cost per cached node on a re-run.

Targets (issue 2): < 50 ms to load and validate a 50-node recipe; < 5 ms per cached node.
Run: python benchmarks/bench_engine.py [--nodes 50] [--repeat 20]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

from nodegraph.cache import Cache
from nodegraph.executor import run_recipe
from nodegraph.recipe import load_recipe
from nodegraph.registry import Registry

TOY = Path(__file__).resolve().parent.parent / "tests" / "engine" / "toy_nodes.py"


def chain_recipe(nodes: int) -> str:
    """A source node, then shifts in a chain with a merge every 10 nodes: nodes in all."""
    lines = [
        "name: bench",
        "seed: 1",
        f"outputs: [n{nodes - 1}]",
        "nodes:",
        "  n0: {type: toy_points, params: {count: 100, scale: 1.0}}",
    ]
    for i in range(1, nodes):
        if i % 10 == 0:
            lines.append(f"  n{i}: {{type: toy_merge, inputs: {{parts: [n{i - 1}.spheres, n{i - 5}.spheres]}}}}")
        else:
            lines.append(
                f"  n{i}: {{type: toy_shift, inputs: {{spheres: n{i - 1}.spheres}}, params: {{dx: {i % 7 * 0.1:.1f}}}}}"
            )
    return "\n".join(lines) + "\n"


def timed(fn, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--nodes", type=int, default=50)
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--quick", action="store_true", help="a 10-node recipe, 3 repeats (a smoke run)")
    args = parser.parse_args()
    if args.quick:
        args.nodes, args.repeat = 10, 3
    registry = Registry()
    registry.add_plugin_file(TOY)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "bench.yaml"
        path.write_text(chain_recipe(args.nodes))
        load_median, load_min = timed(lambda: load_recipe(path, registry), args.repeat)
        recipe = load_recipe(path, registry)
        cache = Cache(Path(tmp) / "cache")
        cold_median, _ = timed(lambda: run_recipe(recipe, cache=None), max(3, args.repeat // 4))
        run_recipe(recipe, cache=cache)
        warm_median, warm_min = timed(lambda: run_recipe(recipe, cache=cache), args.repeat)
        every = [f"n{i}" for i in range(args.nodes)]
        loaded_warm, _ = timed(lambda: run_recipe(recipe, cache=cache, outputs=every), args.repeat)
        rrd_warm, _ = timed(lambda: run_recipe(recipe, cache=cache, rrd=Path(tmp) / "b.rrd"), max(3, args.repeat // 4))
    n = args.nodes
    rows = [
        ("load + validate recipe", f"{load_median * 1e3:.2f} ms", f"{load_min * 1e3:.2f} ms", "< 50 ms"),
        ("cold run, no cache (per node)", f"{cold_median / n * 1e3:.3f} ms", "", ""),
        ("re-run, all cached (per node)", f"{warm_median / n * 1e3:.3f} ms", f"{warm_min / n * 1e3:.3f} ms", "< 5 ms"),
        ("re-run, all cached, every value loaded (per node)", f"{loaded_warm / n * 1e3:.3f} ms", "", "< 5 ms"),
        ("re-run, all cached + .rrd logging (per node)", f"{rrd_warm / n * 1e3:.3f} ms", "", ""),
    ]
    print(f"engine overhead, {n}-node recipe, median of {args.repeat} (min beside)\n")
    print(f"| {'measure':<50} | {'median':>10} | {'min':>10} | {'target':>8} |")
    print(f"|{'-' * 52}|{'-' * 12}|{'-' * 12}|{'-' * 10}|")
    for row in rows:
        print(f"| {row[0]:<50} | {row[1]:>10} | {row[2]:>10} | {row[3]:>8} |")


if __name__ == "__main__":
    main()
