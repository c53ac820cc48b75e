"""G's two methods on the rice bowl, side by side (G fig. 4.3.2 / 4.5, G table 2: full 3,867 s against short
2,041 s, ratio 1.89): ``graphs/rice_bowl.yaml`` as it is (short: aperiodic fill, refine, cull, a short XPBD
run) and with ``rice_sim.mode=full`` (G §3.2.1: as many identical grains, packed on a regular grid in one
orientation above the bowl, dropped and settled for ``--full-frames`` frames). Each run cold (empty node
cache, kernels compiled); the table gives grains, fill height, packing fraction, contacts per grain, the
mesh overlap, the simulation's time, the method's time (short: placement to the end of the run; full: the
run, whose grid packing needs no placement) and the whole recipe's; both previews go side by side into one
labelled PNG.

    python benchmarks/bench_full_vs_short.py              # full size (minutes on 2 cores)
    python benchmarks/bench_full_vs_short.py --quick      # a 28 mm bowl, 3 / 30 frames: seconds

Results (PNGs) go to ``$NODEGRAPH_BENCH_RESULTS`` or ``benchmarks/results/``. The load average is printed:
on a shared machine times are comparable only within one run. ``--quick`` checks that both paths run, not
their result or time: the kernels are not compiled first, and the 30-frame drop does not settle (the grid
stack is tall over a small bowl).

Full size, 2026-11-23, load ≈ 13 on 2 shared cores (previews 640 × 360):

| method | grains | frames | fill mm | packing | contacts | overlap p95 / max | simulation s | method s | recipe s |
|---|---|---|---|---|---|---|---|---|---|
| short | 2087 | 15 | 33.4 | 0.80 | 11.4 | 0.172 / 0.258 | 46.1 | 122.4 | 399.9 |
| full | 2087 | 90 | 32.4 | 1.20 | 14.0 | 0.170 / 0.181 | 172.4 | 172.4 | 479.2 |

full / short: method time 1.41, simulation 3.74 (G: 1.89). The full pile's packing above 1 is the measure
node's estimate (element volumes over the hull of their vertices), not a physical fraction: identical grains
settle interleaved deeper (14 contacts per grain) than the hull accounts for.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

HERE = Path(__file__).resolve().parent
# the nodes of each method's own work (the grain library before them and the shading after are shared)
METHOD_NODES = {
    "short": ("rice_place", "rice_turn", "rice_mix", "implicit", "refine", "pile", "rice_sim"),
    "full": ("rice_sim",),
}
G_RATIO = 3867 / 2041  # G table 2: rice in a bowl, full / short


def results_dir() -> Path:
    return Path(os.environ.get("NODEGRAPH_BENCH_RESULTS", HERE / "results"))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a small bowl and few frames: seconds")
    parser.add_argument("--full-frames", type=int, default=90, help="frames of the full method's drop (≥ 30)")
    parser.add_argument("--width", type=int, default=640, help="preview width (height 9/16 of it)")
    args = parser.parse_args(argv)
    from bench_scenes import QUICK, run_cold
    from machine import conditions

    frames = 30 if args.quick else args.full_frames
    size = (
        QUICK["rice_bowl"] if args.quick else [f"preview.width={args.width}", f"preview.height={args.width * 9 // 16}"]
    )
    out = results_dir()
    if not args.quick:  # compile both paths first, so the timed runs are cold, not compiling (quick: not timed)
        run_cold("rice_bowl", QUICK["rice_bowl"] + ["rice_sim.mode=full", "rice_sim.frames=30"])
    rows = {}
    for method, extra in (("short", []), ("full", ["rice_sim.mode=full", f"rice_sim.frames={frames}"])):
        row = run_cold("rice_bowl", size + extra, preview_to=out / f"rice_bowl_{method}.png")
        row["method"] = sum(row["nodes"].get(n, 0.0) for n in METHOD_NODES[method])
        rows[method] = row
        print(f"{method}: {row['total']:.1f} s", flush=True)
    print()
    print(table(rows, frames))
    ratio = rows["full"]["method"] / max(rows["short"]["method"], 1e-9)
    sim_ratio = rows["full"]["nodes"]["rice_sim"] / max(rows["short"]["nodes"]["rice_sim"], 1e-9)
    print(f"\nfull / short: method time {ratio:.2f}, simulation {sim_ratio:.2f} (G table 2: {G_RATIO:.2f})")
    side = out / "rice_bowl_full_vs_short.png"
    side_by_side(rows, out, side)
    print(f"previews: {side}")
    print(f"{'quick sizes' if args.quick else 'full size'}; {conditions()}")
    return 0


def table(rows: dict[str, dict], frames: int) -> str:
    lines = [
        "| method | grains | frames | fill height mm | packing | contacts / grain | overlap p95 / max "
        "| simulation s | method s | recipe s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for method, row in rows.items():
        lines.append(
            f"| {method} | {row['elements']:.0f} | {frames if method == 'full' else 'recipe'} | "
            f"{row['fill_height']:.1f} | {row['packing_fraction']:.2f} | {row['contacts_per_element']:.1f} | "
            f"{row['overlap_p95']:.3f} / {row['overlap_max']:.3f} | {row['nodes']['rice_sim']:.1f} | "
            f"{row['method']:.1f} | {row['total']:.1f} |"
        )
    return "\n".join(lines)


def side_by_side(rows: dict[str, dict], folder: Path, out: Path) -> None:
    """Both previews in one image, each with its method, grains, fill height, packing, contacts and time."""
    import numpy as np
    from PIL import Image, ImageDraw

    panels = []
    for method, row in rows.items():
        image = Image.open(folder / f"rice_bowl_{method}.png").convert("RGB")
        draw = ImageDraw.Draw(image)
        label = (
            f"{method}: {row['elements']:.0f} grains, fill {row['fill_height']:.1f} mm, packing "
            f"{row['packing_fraction']:.2f}, {row['contacts_per_element']:.1f} contacts/grain, {row['method']:.0f} s"
        )
        draw.rectangle([0, 0, image.width, 14], fill=(0, 0, 0))
        draw.text((4, 2), label, fill=(255, 255, 255))
        panels.append(np.asarray(image))
    Image.fromarray(np.concatenate(panels, axis=1)).save(out)


if __name__ == "__main__":
    raise SystemExit(main())
