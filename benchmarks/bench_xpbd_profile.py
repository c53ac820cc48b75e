"""Where a substep's time goes (issue 6 performance): per-kernel timings on the settled box pile
of ``bench_xpbd_newton`` (N spheres r = 1 cm, 10 substeps per 1/60 s frame, 1 iteration, gravity,
contact, friction, box walls), warm JIT.

Every kernel call goes through the solver's ``KernelDispatch``; this benchmark swaps in a timing
dispatch, so the table shows ms per substep and calls per substep per kernel, and "python" is the
rest of the substep (solver code between kernels). Also reports how often the neighbour lists were
rebuilt. Run: python benchmarks/bench_xpbd_profile.py [--quick] [--sizes 10000 50000]
"""

from __future__ import annotations

import argparse
import os
import time
from collections import Counter
from pathlib import Path

from bench_xpbd_newton import SUBSTEPS, box_solver
from machine import conditions

from nodes.simulation.solver import KernelDispatch

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")


class TimedDispatch(KernelDispatch):
    """Counts calls and sums wall time per kernel (by function name)."""

    def __init__(self):
        super().__init__()
        self.seconds: Counter[str] = Counter()
        self.kernel_calls: Counter[str] = Counter()

    def __call__(self, family, kernel, *args):
        t = time.perf_counter()
        out = super().__call__(family, kernel, *args)
        name = getattr(kernel, "__name__", family)
        self.seconds[name] += time.perf_counter() - t
        self.kernel_calls[name] += 1
        return out


def profile(n, settle, timed):
    d = TimedDispatch()
    s = box_solver(n, d)
    for _ in range(settle):
        s.frame()
    d.seconds.clear()
    d.kernel_calls.clear()
    t = time.perf_counter()
    for _ in range(timed * SUBSTEPS):
        s.solver.substep(s.state)
    wall = time.perf_counter() - t
    steps = timed * SUBSTEPS
    rows = [(name, 1e3 * sec / steps, d.kernel_calls[name] / steps) for name, sec in d.seconds.most_common()]
    rows.append(("python (rest of the substep)", 1e3 * (wall - sum(d.seconds.values())) / steps, float("nan")))
    return steps / wall, rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 50000])
    args = ap.parse_args()
    settle, timed = (3, 2) if args.quick else (60, 10)
    sizes = [2000] if args.quick else args.sizes
    out = []
    for n in sizes:
        rate, rows = profile(n, settle, timed)
        out += [
            "",
            f"N = {n}: {rate:.1f} substeps/s ({1e3 / rate:.2f} ms per substep)",
            "",
            "| kernel | ms / substep | calls / substep |",
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
