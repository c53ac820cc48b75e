"""The food scenes at their real scale — issue 17: each recipe run cold (empty node cache, numba kernels
already compiled), its elements, vertices, wall time per node and in total, and the mesh-level quality
of the ``measure`` node (overlap p50 / p95 / max of touching pairs in element lengths, contacts per
element, packing fraction), with G table 2's times and counts beside (SPEC §6).

    python benchmarks/bench_scenes.py                 # every recipe at full size (minutes on 2 cores)
    python benchmarks/bench_scenes.py --quick         # the rice bowl at its reduced size: a smoke run of this harness
    python benchmarks/bench_scenes.py --quick rice_bowl sushi  # other recipes at their reduced sizes
    python benchmarks/bench_scenes.py rice_bowl ikura_don     # some recipes only
    python benchmarks/bench_scenes.py --gallery && python tools/gallery.py   # the README pictures from these runs

G's full method against the short one on the rice bowl is ``benchmarks/bench_full_vs_short.py``.

Kernels are compiled by a first quick run of the same recipe (numba's cache then serves later runs), so
the timed run's cold time is the recipe's, not the compiler's. The load average is printed beside: on a
shared machine the times are only comparable under the same line; each row also gives the load average
when its run started and the run's peak resident memory (each run is a process of its own, so the peak is
that recipe's).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import resource
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

# G table 2 (i9-9900X, CPU): (full s, short s, elements, vertices); S table 2 for the mixed rice.
REFERENCE = {
    "rice_bowl": ("G", 3867, 2041, 2000, 1_840_000),
    "ikura_don": ("G", None, 65, 310, 746_062),
    "onigiri": ("G", 2567, 1307, 3064, 2_818_880),
    "rice_bunny": ("G", 8561, 4376, 5111, 4_702_120),
    "onigiri_cylinder": ("G", 2567, 1307, 3064, 2_818_880),
    "sushi": ("G", 17_622, None, None, None),  # G ch.4: sushi rice, full simulation 4 h 53 m 42 s
    "rice_chestnut": ("S", None, 6.27 + 194.30, 5365, None),  # S: initial placement + adjustment
}

# Reduced sizes (seconds each): each recipe's own draft: block (what `nodegraph run --draft` applies: a smaller
# shape, fewer variants and frames), with a still smaller preview on top.
PREVIEW = ["preview.width=64", "preview.height=48", "preview.samples=1", "measure.sample=60"]
# --quick runs the rice bowl small (its cheapest food recipe), in a process of its own: the harness's smoke run (every
# recipe at its reduced size is tests/scenes' work; all of them here took 199 CPU s with compiled kernels, load 2.5)
QUICK_CPU_S = 120
SCENES = ("rice_bowl", "ikura_don", "onigiri", "onigiri_cylinder", "sushi", "kakigori", "rice_chestnut")


def recipe_path(name: str) -> Path:
    return REPO / "graphs" / f"{name}.yaml"


def draft_overrides(name: str) -> list[str]:
    """A recipe's draft: block as --set texts (as ``Recipe.draft``), read without loading the node registry."""
    import yaml

    block = yaml.safe_load(recipe_path(name).read_text()).get("draft") or {}
    return [f"{key}={json.dumps(value)}" for key, value in block.items()]


def _quick(name: str) -> list[str]:
    """The draft's counts with PREVIEW on top; the walls' distance field at its default resolution (the scene
    tests' quality targets were set with it; the draft coarsens it for speed)."""
    keep = [t for t in draft_overrides(name) if t.split("=")[0] not in {p.split("=")[0] for p in PREVIEW}]
    return [t for t in keep if not t.split("=")[0].endswith(".wall_cells")] + PREVIEW


# the scene tests' own sizes where a recipe's draft is larger than a test needs: the drafts are sized for an artist
# to judge a look (the chawan and the donburi at full size, ≈ 480 grains and ≈ 1,230 elements; the onigiri 28 mm,
# ≈ 360 grains); the tests run a 39 mm chawan (≈ 120 grains), the 14.4 mm onigiri (≈ 50 grains) and the 64 mm donburi
# (≈ 340 elements)
SMALLER = {
    "rice_bowl": ["bowl.size=18.0", "bowl.depth=18.0", "bowl.mound=5.0", "bowl.wall=1.5", "rice_core.lower=8.0"],
    "onigiri": ["onigiri.size=14.4", "plate.gap=0.15", "nori.gap=0.1"],
    "ikura_don": ["bowl.size=32.0", "bowl.depth=38.0", "bowl.mound=4.0", "bowl.wall=2.7", "rice_core.lower=5.0"],
}
QUICK = {name: _quick(name) + SMALLER.get(name, []) for name in SCENES}


def run_cold(name: str, overrides: list[str], preview_to: Path | None = None, out: Path | None = None) -> dict:
    """One run in a fresh cache; per-node wall, total, elements, vertices and the measure row. ``out``: where its
    files go (a temporary folder if None)."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    recipe = load_recipe(recipe_path(name), default_registry(), overrides)
    with tempfile.TemporaryDirectory(prefix="bench-scenes-") as tmp:
        start = time.perf_counter()
        result = run_recipe(recipe, cache=Cache(Path(tmp) / "cache"), out_dir=out or Path(tmp) / "out")
        total = time.perf_counter() - start
        if preview_to is not None:
            preview_to.parent.mkdir(parents=True, exist_ok=True)
            preview_to.write_bytes(((out or Path(tmp) / "out") / "preview.png").read_bytes())
    table = result.output("measure.table").columns
    nodes, cpu = {}, {}
    for record in result.records:
        nodes[record.node] = nodes.get(record.node, 0.0) + record.seconds
        cpu[record.node] = cpu.get(record.node, 0.0) + (record.cpu_seconds or 0.0)
    vertices = 0
    for ref in _final_aggregates(recipe):
        aggregate = result.output(ref)
        vertices += sum(len(aggregate.element_mesh(i).vertices) for i in range(len(aggregate.placement)))
    return {
        "total": total,
        "nodes": nodes,
        "cpu": cpu,
        "vertices": vertices,
        **{k: float(v[0]) for k, v in table.items()},
    }


def _measured(name: str, overrides: list[str], preview_to: Path | None, out: Path | None) -> dict:
    row = run_cold(name, overrides, preview_to, out)
    row["peak_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # KiB on Linux
    return row


def run_isolated(name: str, overrides: list[str], preview_to: Path | None = None, out: Path | None = None) -> dict:
    """``run_cold`` in a fresh process (its peak memory is this run's alone), with the load average at its
    start."""
    load = os.getloadavg()[0]
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        row = pool.submit(_measured, name, overrides, preview_to, out).result()
    return {**row, "load": load}


def _final_aggregates(recipe) -> list[str]:
    """The aggregates the ``measure`` node reads (``node.port``)."""
    wires = recipe.nodes["measure"].inputs["aggregates"]
    return [str(w) for w in (wires if isinstance(wires, (list, tuple)) else [wires])]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recipes", nargs="*", help="recipe names (default: every one with a row below)")
    parser.add_argument("--quick", action="store_true", help="reduced sizes: seconds per recipe")
    parser.add_argument("--top", type=int, default=4, help="slowest nodes shown per recipe")
    parser.add_argument(
        "--gallery",
        action="store_true",
        help="keep each timed run's files in outputs/<recipe>/ with its time (gallery.json): then "
        "`python tools/gallery.py` (without --run) makes the README's pictures from these very runs",
    )
    args = parser.parse_args(argv)
    from machine import conditions

    names = args.recipes or (["rice_bowl"] if args.quick else [n for n in QUICK if recipe_path(n).exists()])
    rows = []
    for name in names:
        quick = QUICK.get(name, PREVIEW)
        if not args.quick:  # compiles the kernels (numba cache) so the timed run is cold, not compiling
            run_isolated(name, quick)  # (a --quick run is a smoke test: its times include the compile)
        preview = None if args.quick else REPO / "benchmarks" / "results" / f"{name}.png"  # for a look
        out = REPO / "outputs" / name if args.gallery and not args.quick else None
        rows.append((name, run_isolated(name, quick if args.quick else [], preview_to=preview, out=out)))
        if out is not None:  # what tools/gallery.py --run writes for one recipe
            row = rows[-1][1]
            info = {"cold_s": round(row["total"], 1), "load": round(row["load"], 1), "count": int(row["elements"])}
            (out / "gallery.json").write_text(json.dumps(info, indent=1) + "\n")
        _print_row(name, rows[-1][1], args.top)
    print()
    print(_table(rows))
    print(f"\n{'quick sizes' if args.quick else 'full sizes'}; {conditions()}; pid {os.getpid()}")
    return 0


def _print_row(name: str, row: dict, top: int) -> None:
    slow = sorted(row["nodes"].items(), key=lambda kv: -kv[1])[:top]
    print(
        f"{name}: {row['total']:.1f} s, {sum(row['cpu'].values()):.1f} CPU s — "
        + ", ".join(f"{n} {s:.1f} s ({row['cpu'][n]:.1f} CPU s)" for n, s in slow),
        flush=True,
    )


def _table(rows) -> str:
    head = (
        "| recipe | elements | vertices | total s | load | peak MiB | p50 | p95 | max | >1 % | contacts | packing "
        "| fill mm | ref | ref short s | ref full s | ref elements | ref vertices |"
    )
    lines = [head, "|" + "---|" * 18]
    for name, row in rows:
        src, full, short, count, verts = REFERENCE.get(name, ("", None, None, None, None))
        lines.append(
            f"| {name} | {row['elements']:.0f} | {row['vertices']:,} | {row['total']:.1f} | {row['load']:.1f} | "
            f"{row['peak_mib']:,.0f} | "
            f"{row['overlap_p50']:.3f} | {row['overlap_p95']:.3f} | {row['overlap_max']:.3f} | "
            f"{row['deeper_than_1pct']:.2f} | {row['contacts_per_element']:.1f} | {row['packing_fraction']:.2f} | "
            f"{row['fill_height']:.1f} | {src} | {_num(short)} | {_num(full)} | {_num(count)} | {_num(verts)} |"
        )
    return "\n".join(lines)


def _num(x) -> str:
    return "—" if x is None else (f"{x:,.0f}" if x >= 100 else f"{x:g}")


if __name__ == "__main__":
    raise SystemExit(main())
