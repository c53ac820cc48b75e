"""The rice bunny's cut view (issue 26): the pieces the ``cut`` node leaves with each ``islands`` setting, how high
each floating piece hangs, which removed grains bridge them, and the node's CPU seconds.

    python benchmarks/bench_cut.py --cache-dir exp/cache [--draft] [--set bunny.size=16.0 ...]
    python benchmarks/bench_cut.py --quick      # a 16 mm bunny (the test's size) in a temporary cache, seconds

The recipe runs to ``contact.aggregate`` (the cut's input) in ``--cache-dir``: after a ``nodegraph run
graphs/rice_bunny.yaml --cache-dir DIR`` it is read from there. Pieces are counted by the node's own contact
graph (vertices within ``cut.gap`` grain lengths) and, for a second look, at 0.5 mm.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

ROOT = Path(__file__).resolve().parents[1]
QUICK = ["bunny.size=16.0", "grain_spheres.variants=2", "grain_volume.resolution=24", "press.frames=2"]


def pieces(aggregate, reach: float) -> str:
    """The aggregate's pieces at ``reach`` (mm, vertex to vertex), largest first, with their heights above the
    lowest point."""
    from scipy.sparse.csgraph import connected_components

    from nodes.placement.islands import contact_graph, element_surfaces

    points, owner, _ = element_surfaces(aggregate)
    count, label = connected_components(contact_graph(points, owner, len(aggregate.placement), reach))
    lowest = np.full(len(aggregate.placement), np.inf)
    np.minimum.at(lowest, owner, points[:, 2])
    sizes = np.bincount(label)
    rows = [f"{sizes[c]} ({lowest[label == c].min() - lowest.min():.1f} mm up)" for c in np.argsort(-sizes)]
    return f"{count} at {reach:.2f} mm: " + ", ".join(rows)


def main(argv: list[str] | None = None) -> int:
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe
    from nodes.placement import cut
    from nodes.placement.islands import element_surfaces

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache-dir", type=Path, help="the node cache of a rice_bunny run (default: a new one)")
    parser.add_argument("--draft", action="store_true", help="the recipe's draft sizes")
    parser.add_argument("--quick", action="store_true", help="a 16 mm bunny: " + " ".join(QUICK))
    parser.add_argument("--set", action="append", default=[], dest="overrides", help="NODE.PARAM=VALUE")
    args = parser.parse_args(argv)
    overrides = (QUICK if args.quick else []) + args.overrides
    recipe = load_recipe(ROOT / "graphs" / "rice_bunny.yaml", default_registry(), overrides, draft=args.draft)
    with tempfile.TemporaryDirectory(prefix="bench_cut-") as scratch:
        cache_dir = args.cache_dir or Path(scratch)
        result = run_recipe(recipe, cache=Cache(cache_dir), out_dir=Path(scratch), outputs=["contact.aggregate"])
        whole = result.output("contact.aggregate")
    params = {k: v for k, v in recipe.nodes["cut"].params.items() if k != "islands"}
    length = element_surfaces(whole)[2]
    print(f"{len(whole.placement)} grains, cut {params}")
    kept = cut.call(aggregate=whole, **params, islands="keep").placement.p_num
    for islands in ("keep", "bridge", "drop"):
        start = time.process_time()
        out = cut.call(aggregate=whole, **params, islands=islands)
        seconds = time.process_time() - start
        print(f"islands {islands}: {len(out.placement)} grains kept, {seconds:.2f} CPU s")
        for reach in (params["gap"] * length, 0.5):
            print(f"  pieces {pieces(out, reach)}")
        added = np.flatnonzero(~np.isin(out.placement.p_num, kept))
        for i in added:
            print(f"  bridging grain p_num {out.placement.p_num[i]} at {np.round(out.placement.positions[i], 1)} mm")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
