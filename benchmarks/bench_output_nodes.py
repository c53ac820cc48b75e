"""The single-threaded output nodes of a scene — ``measure``, ``shade``, ``export`` (issue 27: every recipe ≤ 60 s
cold on 2 cores) — timed on their cached inputs, with a digest of what each returns to compare two checkouts.

    python benchmarks/bench_output_nodes.py onigiri CACHE_DIR [--nodes measure,shade,export]
    python benchmarks/bench_output_nodes.py --quick     # the reduced rice bowl in a temporary cache (CI smoke run)

CACHE_DIR holds the recipe's node cache (a copy of a full cold run's, e.g. /work/main/exp/gal_cache/onigiri: the
inputs are read from it, nothing is written). Each node function runs once in this process, in the order given,
with the seed the engine derives for it; its wall and CPU seconds are printed (the first node also pays the imports
its code needs; the CPU seconds of the processes a node forks are printed beside its own). The last line is JSON:
the measure table's values, a sha256 of the shaded scenes' arrays and of each exported file, so two checkouts
compare with ``diff`` (run each with its own ``PYTHONPATH``, back to back: times on a shared machine compare only
under the same load, printed beside).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
# --quick computes the reduced rice bowl's inputs first, the cheapest food recipe with all three nodes (the reduced
# main job is tests/scenes' work; the numba cache may be cold in CI: its compiling counts)
QUICK_CPU_S = 300


def scene_digest(scene) -> str:
    """sha256 (16 hex digits) of a shaded scene's mesh arrays, materials and material indices."""
    digest = hashlib.sha256()
    for mesh in scene.meshes:
        for name in ("vertices", "faces", "normals", "colors", "parts"):
            value = getattr(mesh, name)
            if value is not None:
                digest.update(np.ascontiguousarray(value).tobytes())
    for sigma in scene.cdrf_sigma:
        digest.update(np.ascontiguousarray(sigma).tobytes())
    digest.update(repr(scene.materials).encode())
    digest.update(np.asarray(scene.material_of).tobytes())
    return digest.hexdigest()[:16]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("recipe", nargs="?", help="a recipe name in graphs/")
    parser.add_argument("cache", nargs="?", type=Path, help="the recipe's node cache (read only)")
    parser.add_argument("--nodes", default="measure,shade,export", help="node types to time, in order")
    parser.add_argument("--quick", action="store_true", help="the reduced rice bowl, its inputs computed here")
    args = parser.parse_args()
    if args.quick:
        import bench_scenes

        with tempfile.TemporaryDirectory(prefix="bench-output-nodes-") as tmp:
            time_nodes("rice_bowl", Path(tmp), args.nodes.split(","), bench_scenes.QUICK["rice_bowl"])
        return
    if args.recipe is None or args.cache is None:
        parser.error("give a recipe and its node cache, or --quick")
    time_nodes(args.recipe, args.cache, args.nodes.split(","), [])


def time_nodes(name: str, cache: Path, types: list[str], overrides: list[str]) -> None:
    """Run each chosen node once on its inputs from ``cache`` (computed there if missing); print times, then JSON."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
    from nodegraph.context import Context
    from nodegraph.plan import derive_seed

    recipe = load_recipe(ROOT / "graphs" / f"{name}.yaml", default_registry(), overrides)
    chosen = [n for t in types for n, entry in recipe.nodes.items() if entry.spec.type_name == t]
    sources = sorted({str(s) for n in chosen for refs in recipe.nodes[n].inputs.values() for s in refs})
    result = run_recipe(recipe, outputs=sources, cache=Cache(cache))
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}", flush=True)
    out = {}
    for node in chosen:
        entry = recipe.nodes[node]
        inputs = {}
        for port, refs in entry.inputs.items():
            values = [result.output(str(s)) for s in refs]
            inputs[port] = values if entry.spec.inputs[port].many else values[0]
        seed = derive_seed(recipe.seed if entry.seed is None else entry.seed, node, None) if entry.spec.random else None
        ctx = Context.standalone(node_type=entry.spec.type_name, seed=seed)
        wall, cpu, before = time.perf_counter(), time.process_time(), os.times()
        value = entry.spec.run(ctx, **inputs, **entry.params)
        wall, cpu, after = time.perf_counter() - wall, time.process_time() - cpu, os.times()
        children = after.children_user + after.children_system - before.children_user - before.children_system
        # the children: processes a node started and joined before it returned (none now: nodegraph/runtime.py)
        print(f"{node}: wall {wall:.2f} s CPU {cpu:.2f} s + {children:.2f} s in child processes", flush=True)
        if entry.spec.type_name == "measure":
            out[node] = {k: np.asarray(v).tolist() for k, v in value.columns.items()}
        elif entry.spec.type_name == "shade":
            out[node] = scene_digest(value)
        elif entry.spec.type_name == "export":
            out[node] = {k: hashlib.sha256(v).hexdigest()[:16] for k, v in value.files.items()}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
