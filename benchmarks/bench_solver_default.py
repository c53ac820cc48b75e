"""The xpbd default (substeps × iterations) against the settings of about its cost — SPEC §3.

``bench_xpbd --only accuracy`` sweeps the whole grid on wall time; on a shared 2-core machine a
setting's wall time moves by more than the differences near the default, so this benchmark times
the few settings of 10–40 constraint passes per frame in CPU seconds of the process (the solver
runs these scenes on one thread, so CPU time is its work, whatever else the machine runs), the
fastest of several runs, and reads the errors ``bench_xpbd`` defines on the same two scenes:
a 150-grain bowl (max penetration / r, height-profile error against a 64 × 4 reference) and the
8-cube stack (mean distance from its analytic rest).

    python benchmarks/bench_solver_default.py [--quick]

Writes benchmarks/results/bench_solver_default.md (or under $NODEGRAPH_BENCH_RESULTS).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")

SETTINGS = ((10, 2), (20, 1), (16, 1), (8, 2), (5, 4), (10, 1), (20, 2))


def cpu_frames(run, frames: int) -> float:
    """CPU seconds of this process for ``frames`` frames of a solver run."""
    start = time.process_time()
    for _ in range(frames):
        run.frame()
    return time.process_time() - start


def measure(settings, grains, bowl_frames, stack_frames, repeats):
    """Per setting: CPU seconds (fastest of ``repeats``) and the errors of both scenes."""
    import bench_xpbd as bx

    aggregate, colliders = bx.rice_bowl(grains)
    make = bx.bowl_maker(aggregate, colliders, bowl_frames)
    make(10, 2).frame()  # compile before timing
    reference = bx.run_to_rest(make(64, 4), bowl_frames)[1]
    rest = bx.stack_column(8)[1]
    rows = []
    for substeps, iterations in settings:
        bowl_cpu = min(cpu_frames(make(substeps, iterations), bowl_frames) for _ in range(repeats))
        stack = lambda s=substeps, i=iterations: bx.stack_column(8, substeps=s, iterations=i)[0]  # noqa: E731
        stack_cpu = min(cpu_frames(stack(), stack_frames) for _ in range(repeats))
        _, centres, penetration, _, _, rise = bx.run_to_rest(make(substeps, iterations), bowl_frames)
        _, stack_centres, stack_penetration, _, _, stack_rise = bx.run_to_rest(stack(), stack_frames)
        rows.append(
            {
                "substeps": substeps,
                "iterations": iterations,
                "bowl_cpu": bowl_cpu,
                "bowl_penetration": penetration,
                "bowl_height_error": bx.height_profile_error(centres, reference),
                "bowl_rise": rise,
                "stack_cpu": stack_cpu,
                "stack_error": float(np.linalg.norm(stack_centres - rest, axis=1).mean()),
                "stack_penetration": stack_penetration,
                "stack_rise": stack_rise,
            }
        )
        print(rows[-1], flush=True)
    return rows


def table(rows, grains, bowl_frames, stack_frames, repeats) -> str:
    base = rows[0]
    lines = [
        f"Bowl: {grains} grains, {bowl_frames} frames (height error against 64 × 4); stack: 8 cubes, {stack_frames} "
        f"frames; CPU seconds of the frames, fastest of {repeats}; × = against {base['substeps']} × "
        f"{base['iterations']}; energy rise in M·g·r over the last third (bench_xpbd's definition).",
        "",
        "| substeps | iterations | passes | bowl CPU (s) | bowl × | bowl max penetration / r | bowl height error (mm) "
        "| bowl energy rise | stack CPU (s) | stack × | stack error vs rest (mm) | stack max penetration / r "
        "| stack energy rise |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['substeps']} | {r['iterations']} | {r['substeps'] * r['iterations']} | {r['bowl_cpu']:.3f} | "
            f"{r['bowl_cpu'] / base['bowl_cpu']:.2f} | {r['bowl_penetration']:.3g} | {r['bowl_height_error']:.3g} | "
            f"{r['bowl_rise']:.2g} | {r['stack_cpu']:.4f} | {r['stack_cpu'] / base['stack_cpu']:.2f} | "
            f"{r['stack_error']:.3g} | {r['stack_penetration']:.3g} | {r['stack_rise']:.2g} |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a 40-grain bowl, few frames, one run each (seconds)")
    args = parser.parse_args()
    from machine import conditions

    grains, bowl_frames, stack_frames, repeats = (40, 8, 20, 1) if args.quick else (150, 45, 90, 3)
    settings = SETTINGS[:3] if args.quick else SETTINGS
    rows = measure(settings, grains, bowl_frames, stack_frames, repeats)
    text = table(rows, grains, bowl_frames, stack_frames, repeats) + f"\n\n{conditions()}"
    print(text)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"bench_solver_default{'_quick' if args.quick else ''}.md").write_text(text + "\n")


if __name__ == "__main__":
    main()
