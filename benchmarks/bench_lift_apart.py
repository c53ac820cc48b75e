"""The ikura don's eggs at a large size spread (``egg_base.diameter_sd``), dropped with ``egg_apart`` (``lift_apart``)
at several ``overlap`` shares: how many eggs end outside the bowl, the recipe's draft at three seeds. ``overlap`` 1
lifts only an egg that starts more than a whole radius deep (nearly the recipe before ``lift_apart``); the recipe's
own value must leave none outside.

    python benchmarks/bench_lift_apart.py              # sd 1.2, overlap 1 / 0.5 / 0.25, seeds 3-5, the draft
    python benchmarks/bench_lift_apart.py --record     # and write benchmarks/measured/lift_apart.jsonl
    python benchmarks/bench_lift_apart.py --quick      # the harness on one seed and share, 1 frame each: prints only

An egg is outside when its centre lies past the bowl wall's outer surface (``Vessel.outside``, as ``measure`` counts
them).
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from machine import stamp, write_rows

REPO = Path(__file__).resolve().parents[1]
RECORD = REPO / "benchmarks" / "measured" / "lift_apart.jsonl"
COMMAND = "python benchmarks/bench_lift_apart.py --record"


QUICK = ["rice_sim.frames=1", "egg_sim.frames=1"]  # a smoke run of the harness: nothing settles


def point(sd: float, overlap: float, seed: int, cache, quick: bool = False) -> dict:
    """One draft run to the dropped eggs: eggs, eggs lifted, eggs ending outside the bowl."""
    from nodegraph.api import default_registry, load_recipe, run_recipe

    overrides = [f"egg_base.diameter_sd={sd}", f"egg_apart.overlap={overlap}", f"seed={seed}"] + (QUICK * quick)
    recipe = load_recipe(REPO / "graphs" / "ikura_don.yaml", default_registry(), overrides, draft=True)
    result = run_recipe(recipe, cache=cache, outputs=["egg_sim.aggregate", "egg_apart.stats", "bowl.vessel"])
    vessel = result.output("bowl.vessel")
    eggs = result.output("egg_sim.aggregate").placement
    stats = result.output("egg_apart.stats").columns
    outside = int(vessel.outside(eggs.positions, margin=vessel.wall).sum())
    return {"eggs": len(eggs), "lifted": int(stats["lifted"][0]), "outside": outside}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sd", type=float, default=1.2)
    parser.add_argument("--overlaps", type=float, nargs="+", default=[1.0, 0.5, 0.25])
    parser.add_argument("--seeds", type=int, nargs="+", default=[3, 4, 5])
    parser.add_argument("--record", action="store_true", help=f"write {RECORD.relative_to(REPO)}")
    parser.add_argument(
        "--quick", action="store_true", help="one seed and share, 1 frame each; prints, records nothing"
    )
    args = parser.parse_args()
    if args.quick:
        args.overlaps, args.seeds, args.record = [0.25], [3], False
    import tempfile

    from nodegraph.api import Cache

    rows = []
    with tempfile.TemporaryDirectory(prefix="lift-apart-") as tmp:
        cache = Cache(Path(tmp) / "cache")  # the rice settles once per seed, shared by the overlaps
        for overlap in args.overlaps:
            load = os.getloadavg()[0]
            found = [point(args.sd, overlap, seed, cache, args.quick) for seed in args.seeds]
            stamped = stamp(load)
            print(f"overlap {overlap:g}: {json.dumps(found)} load {stamped['load']}", flush=True)
            rows.append(
                {
                    "what": f"the draft at diameter_sd {args.sd:g}: eggs ending outside the bowl, seeds "
                    + ", ".join(map(str, args.seeds)),
                    "overlap": overlap,
                    "command": COMMAND,
                    "values": {
                        "outside": [f["outside"] for f in found],
                        "eggs": [f["eggs"] for f in found],
                        "lifted": [f["lifted"] for f in found],
                    },
                    "unit": "eggs",
                    **stamped,
                }
            )
    if args.record:
        write_rows(RECORD, rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
