"""The cost estimate `nodegraph check` prints (``nodegraph.cost``) against real runs: elements, simulated particles,
the simulations' CPU seconds and the run's peak resident memory, estimated from the recipe alone and measured by
running it (each run a process of its own, an empty node cache, numba kernels already compiled).

    python benchmarks/bench_cost.py                          # ikura_don, rice_bowl, onigiri: draft and full size
    python benchmarks/bench_cost.py rice_bowl --draft-only   # some recipes, their --draft runs only
    python benchmarks/bench_cost.py --draft-only --threads 1 # the kernels on one thread: the work, not the waits
    python benchmarks/bench_cost.py --record                 # and write benchmarks/measured/cost.jsonl
    python benchmarks/bench_cost.py --check-time --record    # `nodegraph check graphs/ikura_don.yaml`'s time alone
    python benchmarks/bench_cost.py --placements --record    # each placement alone: placed against its estimate
    python benchmarks/bench_cost.py --quick                  # the recorded rows' estimates, printed (seconds)
    python benchmarks/bench_cost.py --re-estimate            # only the estimates of cost.jsonl's rows, from the
                                                             # code as it is now (seconds; the measured side stays)

A full run's time is also in benchmarks/measured/scenes.jsonl (bench_scenes.py); this one measures the same runs
with the estimate beside.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from machine import stamp

REPO = Path(__file__).resolve().parents[1]
RECIPES = ("ikura_don", "rice_bowl", "onigiri")
RECORD = REPO / "benchmarks" / "measured" / "cost.jsonl"


def estimated(name: str, draft: bool, registry=None):
    """(recipe, its estimate's figures) of ``graphs/<name>.yaml``, nothing run."""
    from nodegraph.recipe import load_recipe
    from nodegraph.registry import default_registry

    path = REPO / "graphs" / f"{name}.yaml"
    recipe = load_recipe(path, registry or default_registry(), draft=draft, work=True, yes=True)
    cost = recipe.cost
    return recipe, {
        "elements": cost.elements,
        "particles": cost.particles,
        "sim_cpu_s": round(sum(c.seconds for c in cost.costs.values() if c.particles), 1),
        "cpu_s": round(cost.cpu_seconds, 1),
        "peak_rss_mib": round(cost.peak[0] / 2**20),
    }


def re_estimate(write: bool = True) -> None:
    """Replace the estimates of every run row of ``RECORD`` by the code's as it is now; print each beside what
    was measured (``write`` False: print only, the ``--quick`` mode)."""
    from nodegraph.registry import default_registry

    registry = default_registry()
    rows = [json.loads(line) for line in RECORD.read_text().splitlines() if line.strip()]
    for row in rows:
        if "recipe" not in row:  # the placements' and check's own rows
            continue
        _, figures = estimated(row["recipe"], row["size"] == "--draft", registry)
        row["values"].update({f"{k}_estimate": v for k, v in figures.items()})
        print(row["recipe"], row["size"], json.dumps(row["values"]))
    if write:
        RECORD.write_text("".join(json.dumps(row, ensure_ascii=False) + "\n" for row in rows))


def _process_cpu() -> float:
    """CPU seconds (user + system) this process has spent."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def measure(name: str, draft: bool) -> dict:
    """Estimate, then run, ``graphs/<name>.yaml`` in this process; the figures of both."""
    from nodegraph.cache import Cache
    from nodegraph.executor import run_recipe
    from nodegraph.report import Reporter

    recipe, estimate = estimated(name, draft)
    cost = recipe.cost
    sims = [n for n, c in cost.costs.items() if c.particles]
    with tempfile.TemporaryDirectory() as tmp:
        reporter = Reporter(quiet=True)
        result = run_recipe(recipe, cache=Cache(Path(tmp) / "cache"), out_dir=Path(tmp) / "out", reporter=reporter)
        records = {r.node: r for r in reporter.records}
        # the elements of the scene: the aggregates the shade node shades, as the recipe's outputs carry them
        shade = next(e for e in recipe.nodes.values() if e.spec.type_name == "shade")
        elements = sum(len(result.output(f"{w.node}.{w.port}").placement) for w in shade.inputs["aggregates"])
        particles = sum(len(result.output(f"{n}.particles")) for n in sims)
        measured = {
            "elements": elements,
            "particles": particles,
            "sim_cpu_s": round(sum(records[n].cpu_seconds or 0.0 for n in sims), 1),
            "cpu_s": round(_process_cpu(), 1),  # the whole process's: its start, the estimate and the run
            "peak_rss_mib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024),
        }
    heavy = {
        n: {"estimate_mib": round(cost.costs[n].memory / 2**20), "measured_mib": round((r.peak_bytes or 0) / 2**20)}
        for n, r in records.items()
        if n in cost.costs and cost.costs[n].memory
    }
    return {"estimate": estimate, "measured": measured, "heavy": heavy}


def check_time(tries: int = 5) -> dict:
    """``nodegraph check graphs/ikura_don.yaml`` (its estimate included), ``tries`` times: the median wall and CPU
    (user + system) seconds."""
    import statistics

    walls, cpus = [], []
    for _ in range(tries):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        started = time.perf_counter()
        command = [sys.executable, "-m", "nodegraph.cli", "check", "graphs/ikura_don.yaml"]
        subprocess.run(command, cwd=REPO, check=True, capture_output=True)
        walls.append(time.perf_counter() - started)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return {"wall_s": round(statistics.median(walls), 2), "cpu_s": round(statistics.median(cpus), 2)}


PLACEMENTS = (
    ("rice_bowl", "rice_place"),
    ("ikura_don", "rice_place"),
    ("ikura_don", "egg_place"),
    ("onigiri", "place"),
)


def placements() -> list[dict]:
    """Each placement of ``PLACEMENTS`` run alone (its recipe's draft and full size): its shape's volume and area,
    r, inset, the points placed and the estimate (``poisson_place.estimate_placed``: what its density is fitted to)."""
    from nodegraph.executor import run_recipe
    from nodegraph.registry import default_registry
    from nodes.placement.poisson_place import _target

    registry = default_registry()
    rows = []
    for name, node in PLACEMENTS:
        for draft in (True, False):
            recipe, _ = estimated(name, draft, registry)
            _, _, solid = _target(node, recipe.nodes)
            stats = run_recipe(recipe, outputs=[f"{node}.stats"]).output(f"{node}.stats").columns
            rows.append(
                {
                    "recipe": name,
                    "node": node,
                    "size": "--draft" if draft else "full size",
                    "volume_mm3": round(float(solid.volume)),
                    "area_mm2": round(float(solid.area)),
                    "inset_mm": recipe.nodes[node].params["inset"],
                    "r_mm": round(float(stats["r"][0]), 3),
                    "placed": int(stats["placed"][0]),
                    "estimate": recipe.cost.costs[node].made,
                }
            )
    return rows


def _replace_row(flag: str, what: str, values, unit: str, load: float, write: bool) -> None:
    """The record of the run with ``flag`` (one per flag in ``RECORD``), replaced when ``write``."""
    row = {
        "what": what,
        "command": f"python benchmarks/bench_cost.py {flag} --record",
        "values": values,
        "unit": unit,
        **stamp(load),
    }
    if write:
        kept = [line for line in RECORD.read_text().splitlines() if line.strip() and flag not in line]
        RECORD.write_text("".join(line + "\n" for line in kept) + json.dumps(row, ensure_ascii=False) + "\n")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recipes", nargs="*", default=list(RECIPES))
    parser.add_argument("--draft-only", action="store_true")
    parser.add_argument("--threads", type=int, help="the kernels' threads in the runs measured (NUMBA_NUM_THREADS)")
    parser.add_argument("--record", action="store_true", help=f"write {RECORD.relative_to(REPO)}")
    parser.add_argument("--check-time", action="store_true", help="time `nodegraph check` on the ikura don alone")
    parser.add_argument("--placements", action="store_true", help="each placement alone against its estimate")
    parser.add_argument("--re-estimate", action="store_true", help="only the estimates of the recorded rows")
    parser.add_argument("--quick", action="store_true", help="the recorded rows' estimates, printed; nothing written")
    parser.add_argument("--one", nargs=2, metavar=("RECIPE", "DRAFT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.re_estimate or args.quick:
        re_estimate(write=not args.quick)
        return 0
    if args.placements:
        load = os.getloadavg()[0]
        found = placements()
        for row in found:
            print(json.dumps(row))
        what = "placements alone: points placed against the estimate (its volume density's fit)"
        _replace_row("--placements", what, {"placements": found}, "mm, mm², mm³, points", load, args.record)
        return 0
    if args.check_time:
        load = os.getloadavg()[0]
        figures = check_time()
        print(json.dumps(figures), f"load {load:.1f}–{os.getloadavg()[0]:.1f}")
        what = "nodegraph check graphs/ikura_don.yaml, its estimate included: median of 5"
        _replace_row("--check-time", what, figures, "s", load, args.record)
        return 0
    if args.one:
        print(json.dumps(measure(args.one[0], args.one[1] == "draft")))
        return 0
    rows = []
    env = {**os.environ, "PYTHONPATH": f"{REPO}{os.pathsep}{REPO / 'benchmarks'}"}
    if args.threads:  # the kernels' threads: one measures the work alone, where two wait for a busy machine's cores
        env["NUMBA_NUM_THREADS"] = str(args.threads)
    for name in args.recipes:
        for mode in ("draft",) if args.draft_only else ("draft", "full"):
            # a first run compiles what numba's cache lacks; the second is the one measured
            load = os.getloadavg()[0]
            check = [sys.executable, "-m", "nodegraph.cli", "check", f"graphs/{name}.yaml"] + ["--draft"] * (
                mode == "draft"
            )
            started = time.perf_counter()  # `nodegraph check`'s wall time, its estimate included
            subprocess.run(check, env=env, capture_output=True, check=True, cwd=REPO)
            check_s = round(time.perf_counter() - started, 2)
            command = [sys.executable, __file__, "--one", name, mode]
            done = subprocess.run(command, env=env, capture_output=True, text=True, cwd=REPO)
            if done.returncode:
                print(done.stderr, file=sys.stderr)
                return 1
            figures = json.loads(done.stdout.strip().splitlines()[-1]) | {"check_s": check_s}
            stamped = stamp(load)
            print(name, mode, json.dumps(figures), f"load {stamped['load']}", flush=True)
            rows.append(
                {
                    "what": "cost estimate / a run: elements, particles, sim CPU s, the run's CPU s, peak RSS MiB",
                    "recipe": name,
                    "size": "--draft" if mode == "draft" else "full size",
                    **({"threads": args.threads} if args.threads else {}),
                    "command": "python benchmarks/bench_cost.py --record"
                    + (f" --threads {args.threads}" if args.threads else ""),
                    "values": {f"{k}_estimate": v for k, v in figures["estimate"].items()}
                    | {f"{k}_measured": v for k, v in figures["measured"].items()}
                    | {"check_s": figures["check_s"]},
                    "heavy_nodes_mib": figures["heavy"],
                    "unit": "elements, particles, CPU s, MiB",
                    **stamped,
                }
            )
    if args.record:  # the rows of the runs measured now replace theirs; every other row stays
        ran = {(row["recipe"], row["size"], row.get("threads")) for row in rows}
        kept = [json.loads(line) for line in RECORD.read_text().splitlines() if line.strip()]
        kept = [row for row in kept if (row.get("recipe"), row.get("size"), row.get("threads")) not in ran]
        RECORD.write_text("".join(json.dumps(row, ensure_ascii=False) + "\n" for row in kept + rows))
        print(f"wrote {RECORD}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
