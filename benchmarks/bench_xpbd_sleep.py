"""xpbd sleeping benchmark (issue 6): the rice bowl with sleeping on (sleep_speed 2 mm/s, the node's
default) and off (0), same scene and effects (RICE of bench_xpbd): wall time, the last frames' cost,
the share of particles solved per substep, the sleeping share at the end, and the pile (fill height,
contacts per grain) — what sleeping saves and whether it changes the result. The 2,000-grain bowl
for the issue's 60 frames, then a 300-grain bowl run on for 240 frames, to rest.
Run: python benchmarks/bench_xpbd_sleep.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from bench_xpbd import RICE, pile_measures
from machine import conditions
from scene_builders import rice_bowl

from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation, finish_simulation
from nodes.simulation.xpbd import xpbd

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")


TAIL = 10  # frames at the end whose cost is reported apart


def run(aggregate, colliders, sleep_speed, frames):
    """(wall s, per-frame seconds, diagnostics, node-like outputs) of one run."""
    params = XpbdParams(**xpbd.resolve_params({"frames": frames, "sleep_speed": sleep_speed}))
    sim = build_simulation(aggregate, colliders, frozenset(RICE), params)
    per_frame = []
    for _ in range(frames):
        t = time.perf_counter()
        sim.frame()
        per_frame.append(time.perf_counter() - t)
    return sum(per_frame), np.array(per_frame), sim.solver.diagnostics, finish_simulation(sim)


def compare(n, frames):
    """Markdown table: the n-grain bowl for ``frames`` frames with sleep_speed 2 and 0."""
    aggregate, colliders = rice_bowl(n)
    for speed in (2.0, 0.0):  # warm every kernel (same particle count: same serial/parallel variants)
        run(aggregate, colliders, speed, 1)
    rows = []
    for speed in (2.0, 0.0):
        wall, per_frame, dg, out = run(aggregate, colliders, speed, frames)
        height, contacts = pile_measures(out)
        rows.append(
            (
                speed,
                wall,
                per_frame[-TAIL:].mean() * 1e3,
                float(np.mean(dg.solved)),
                dg.solved[-1],
                dg.sleeping[-1],
                height,
                contacts,
            )
        )
        print(rows[-1], flush=True)
    base = rows[1][1]
    lines = [
        f"rice bowl, {n} grains, {frames} frames (1/60 s, 10 substeps × 2 iterations), effects "
        f"{', '.join(RICE)}; warm JIT",
        "",
        f"| sleep_speed (mm/s) | wall, {frames} frames (s) | speedup | ms / frame, last {TAIL} "
        "| solved share, mean | solved share, last frame | sleeping share, end | fill height (mm) | contacts / grain |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {s:g} | {w:.2f} | {base / w:.2f} | {t:.1f} | {m:.2f} | {ls:.2f} | {sl:.2f} | {h:.2f} | {c:.2f} |"
        for s, w, t, m, ls, sl, h, c in rows
    ]
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    # the bowl (60 frames: still settling), then a smaller bowl run on to rest
    sizes = ((300, 20), (60, 90)) if args.quick else ((2000, 60), (300, 240))
    table = "\n\n".join(compare(n, frames) for n, frames in sizes) + f"\n\n{conditions()}"
    print(table, flush=True)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"bench_xpbd_sleep{'_quick' if args.quick else ''}.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
