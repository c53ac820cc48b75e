"""A shade-only change on the main job — issue 17 (≤ 5 s): per node, the cold run's seconds beside a re-run after
changing one shade parameter (``shade.baked_ambient``), everything upstream served by the node cache. (The water content
is the cooked material's: changing it re-runs the simulation too, as it should.)

    python benchmarks/bench_shade_rerun.py            # graphs/ikura_don.yaml at full size (minutes on 2 cores)
    python benchmarks/bench_shade_rerun.py --quick    # the reduced rice bowl: a smoke run of this harness (seconds)

The re-run recomputes shade, export and preview (and only those: ``tests/shading/test_recipes.py``); the table
also shows the run's total (cache loads, output files, the Rerun recording) and that total without the preview,
which is path tracing at 1280 × 720, 12 spp, by design several seconds on 2 cores (benchmarks/bench_preview.py).
Kernels are compiled by a first run (not in --quick, a smoke run of the harness: its cold time includes them); the
load average is printed beside (times on a shared machine compare only under the same line). Writes
benchmarks/results/bench_shade_rerun{_quick}.md.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

RERUN_NODES = ("shade", "export", "preview")


def timed_run(name: str, overrides: list[str], cache_dir: Path, out_dir: Path) -> tuple[float, dict[str, float]]:
    """One run of recipe ``name``: its wall seconds and each node's."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    recipe = load_recipe(ROOT / "graphs" / f"{name}.yaml", default_registry(), overrides)
    start = time.perf_counter()
    result = run_recipe(recipe, cache=Cache(cache_dir), out_dir=out_dir)
    total = time.perf_counter() - start
    nodes: dict[str, float] = {}
    for record in result.records:
        if record.status == "ran":
            nodes[record.node] = nodes.get(record.node, 0.0) + record.seconds
    return total, nodes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the reduced rice bowl (seconds)")
    parser.add_argument(
        "--ambient", type=float, default=0.5, help="the changed shade.baked_ambient (share of the base colour)"
    )
    args = parser.parse_args(argv)
    from bench_scenes import QUICK as SIZES
    from machine import conditions

    # --quick: the reduced rice bowl, a smoke run of the harness (the reduced main job's shade-only re-run is
    # tests/shading/test_recipes.py's)
    name = "rice_bowl" if args.quick else "ikura_don"
    quick = [o for o in SIZES[name] if not o.startswith("measure.")]
    base = quick if args.quick else []
    with tempfile.TemporaryDirectory(prefix="bench-shade-rerun-") as tmp:
        if not args.quick:  # numba kernels compiled (same graph), not timed
            timed_run(name, quick, Path(tmp) / "compile", Path(tmp) / "out")
        cold_total, cold = timed_run(name, base, Path(tmp) / "cache", Path(tmp) / "out")
        load_cold = os.getloadavg()[0]
        rerun_total, rerun = timed_run(
            name, base + [f"shade.baked_ambient={args.ambient:g}"], Path(tmp) / "cache", Path(tmp) / "out"
        )
    load_rerun = os.getloadavg()[0]
    if set(rerun) != set(RERUN_NODES):
        raise SystemExit(f"the shade-only re-run ran {sorted(rerun)}, expected {list(RERUN_NODES)}")

    lines = [
        f"{name} ({'reduced' if args.quick else 'full size'}): cold run vs re-run after shade.baked_ambient → "
        f"{args.ambient:g} (s; load average {load_cold:.1f} after the cold run, {load_rerun:.1f} after the re-run)",
        "",
        "| node | cold (s) | shade-only re-run (s) |",
        "|---|---|---|",
    ]
    lines += [f"| {name} | {cold.get(name, 0.0):.2f} | {rerun[name]:.2f} |" for name in RERUN_NODES]
    others = sum(s for n, s in cold.items() if n not in RERUN_NODES)
    lines.append(f"| every other node | {others:.2f} | cached |")
    lines.append(f"| **run total** | {cold_total:.2f} | {rerun_total:.2f} |")
    lines.append(
        f"| run total without the preview | {cold_total - cold['preview']:.2f} | {rerun_total - rerun['preview']:.2f} |"
    )
    text = "\n".join(lines) + f"\n\n{conditions()}"
    print(text)
    out = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or Path(__file__).parent / "results")
    out.mkdir(parents=True, exist_ok=True)
    (out / f"bench_shade_rerun{'_quick' if args.quick else ''}.md").write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
