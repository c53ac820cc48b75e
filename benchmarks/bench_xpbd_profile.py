"""Where a substep's time goes (issue 6 performance): per-kernel timings on the settled box pile
of ``bench_xpbd_newton`` (N spheres r = 1 cm, 10 substeps per 1/60 s frame, 1 iteration, gravity,
contact, friction, box walls), warm JIT.

Every kernel call goes through the solver's ``KernelDispatch``; this benchmark swaps in a timing
dispatch, so the table shows ms per substep and calls per substep per kernel, and "python" is the
rest of the substep (solver code between kernels). Also reports how often the neighbour lists were
rebuilt. ``--clock cpu`` times by the process's CPU seconds instead of the wall clock: with
``--threads 1`` that is the work itself, which a shared, loaded machine does not inflate.
``--recipe R --output NODE.PORT`` profiles a recipe's own simulations instead: every xpbd node that output
needs, run without the node cache, per solve (one ``predict`` a solve); "rebuilds per solve" reads off the
``neighbour_lists`` row.
Run: python benchmarks/bench_xpbd_profile.py [--quick] [--sizes 10000 50000] [--threads N] [--clock cpu]
     python benchmarks/bench_xpbd_profile.py --recipe graphs/onigiri_cylinder.yaml --output rest.aggregate --clock cpu
"""

from __future__ import annotations

import argparse
import os
import time
from collections import Counter
from pathlib import Path

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from bench_xpbd_newton import SUBSTEPS, box_solver
from machine import conditions

from nodes.simulation.solver import KernelDispatch

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")


class TimedDispatch(KernelDispatch):
    """Counts calls and sums wall time per kernel (by function name)."""

    def __init__(self, clock=time.perf_counter):
        super().__init__()
        self.clock = clock
        self.seconds: Counter[str] = Counter()
        self.kernel_calls: Counter[str] = Counter()

    def __call__(self, family, kernel, *args):
        t = self.clock()
        out = super().__call__(family, kernel, *args)
        name = getattr(kernel, "__name__", family)
        self.seconds[name] += self.clock() - t
        self.kernel_calls[name] += 1
        return out


def profile(n, settle, timed, threads=None, clock=time.perf_counter):
    d = TimedDispatch(clock)
    s = box_solver(n, d, threads=threads)
    for _ in range(settle):
        s.frame()
    d.seconds.clear()
    d.kernel_calls.clear()
    t = clock()
    for _ in range(timed * SUBSTEPS):
        s.step()
    wall = clock() - t
    steps = timed * SUBSTEPS
    rows = [(name, 1e3 * sec / steps, d.kernel_calls[name] / steps) for name, sec in d.seconds.most_common()]
    rows.append(("python (rest of the substep)", 1e3 * (wall - sum(d.seconds.values())) / steps, float("nan")))
    return steps / wall, rows


def profile_recipe(recipe: str, output: str, clock) -> tuple[int, list]:
    """(solves, rows) of ``profile`` for the xpbd nodes a recipe's ``output`` needs: the solver's dispatch swapped
    for a timing one while the recipe runs without the node cache."""
    from nodegraph.api import default_registry, load_recipe, run_recipe
    from nodes.simulation import solver

    d = TimedDispatch(clock)
    given, solver.KernelDispatch = solver.KernelDispatch, lambda: d
    try:
        run_recipe(load_recipe(recipe, default_registry()), outputs=[output], cache=None)
    finally:
        solver.KernelDispatch = given
    solves = d.kernel_calls["predict"]
    return solves, [(name, 1e3 * sec / solves, d.kernel_calls[name] / solves) for name, sec in d.seconds.most_common()]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 50000])
    ap.add_argument("--threads", type=int, default=None, help="a fixed thread count (default: the free cores)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall", help="cpu: the process's CPU seconds")
    ap.add_argument("--recipe", help="profile this recipe's simulations (with --output) instead of the box pile")
    ap.add_argument("--output", help="NODE.PORT of --recipe: the xpbd nodes it needs are profiled")
    args = ap.parse_args()
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    if args.recipe:
        solves, rows = profile_recipe(args.recipe, args.output, clock)
        print(f"{args.recipe} {args.output}: {solves} solves, {args.clock} clock", flush=True)
        print(f"| kernel | {args.clock} ms / solve | calls / solve |\n|---|---|---|")
        print("\n".join(f"| {name} | {ms:.3f} | {calls:.2f} |" for name, ms, calls in rows))
        print(conditions())
        return
    settle, timed = (3, 2) if args.quick else (60, 10)
    sizes = [2000] if args.quick else args.sizes
    out = []
    for n in sizes:
        rate, rows = profile(n, settle, timed, args.threads, clock)
        out += [
            "",
            f"N = {n}: {rate:.1f} substeps/s ({1e3 / rate:.2f} ms per substep, {args.clock} clock)",
            "",
            f"| kernel | {args.clock} ms / substep | calls / substep |",
            "|---|---|---|",
        ]
        out += [f"| {name} | {ms:.3f} | {calls:.2f} |" for name, ms, calls in rows]
        print("\n".join(out[-len(rows) - 4 :]), flush=True)
    out += ["", conditions()]
    print(out[-1])
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"bench_xpbd_profile{'_quick' if args.quick else ''}.md").write_text("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
