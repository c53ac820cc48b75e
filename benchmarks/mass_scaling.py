"""Does the contacts' mass scaling (shock propagation) add momentum? Two set-ups, each at 10 and 40 substeps (the
reduced bowl's run is ``slender``: its own 80):

- two 12 × 3 mm grains crossed at right angles, the upper 0.3 mm into the lower, falling freely for 10 frames: the
  pair's centre of mass (weighted by the particles' masses) must fall ½·g·t², whatever its contacts do;
- the reduced indica rice bowl of ``tests/simulation/test_slender.py`` (39 clumped long grains, 15 frames): the
  pile's mean grain height must not rise, and no grain may leave the bowl; and at 10 substeps, what each kernel
  family adds to the mean particle height per frame (frames 2–15), pre-stabilisation's contact sweep apart.

    python benchmarks/mass_scaling.py            # print the table
    python benchmarks/mass_scaling.py --record   # and write benchmarks/measured/mass_scaling.jsonl
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
from pathlib import Path

import numpy as np
from machine import stamp, write_rows

REPO = Path(__file__).resolve().parents[1]
RECORD = REPO / "benchmarks" / "measured" / "mass_scaling.jsonl"
COMMAND = "python benchmarks/mass_scaling.py --record"
GRAVITY = 9810.0  # mm/s²
INDICA = [  # as tests/simulation/test_slender.py
    "bowl.size=14.0",
    "bowl.depth=12.0",
    "bowl.mound=2.0",
    "variety.variety=indica",
    "grain_spheres.variants=4",
    "grain_volume.resolution=24",
    "grain_mesh.target_faces=400",
]


def crossed_pair_fall(substeps: int, frames: int = 10, overlap: float = 0.3) -> dict:
    """The mass-weighted fall of two crossed grains in free fall against ½·g·t², mm."""
    from scene_builders import long_grain
    from scipy.spatial.transform import Rotation

    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.setup import build_simulation
    from nodes.simulation.xpbd import xpbd
    from nodes.values import Aggregate, ElementLibrary, Placement

    turns = np.stack([np.eye(3), Rotation.from_euler("z", 90, degrees=True).as_matrix()])
    positions, up = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 3.0 - overlap]]), np.array([[0.0, 0.0, 1.0]] * 2)
    placed = Placement(positions, up, rotations=turns, kind_names=("long",))
    aggregate = Aggregate(placed, (ElementLibrary("long", [long_grain(12.0, 3.0)]),))
    given = {"frames": frames, "particles_per_element": 8, "log_every": 0, "substeps": substeps}
    params = XpbdParams(**xpbd.resolve_params(given))
    sim = build_simulation(aggregate, [], frozenset({"gravity", "contact", "friction"}), params)
    mass = 1.0 / sim.model.w[: sim.model.n_moving]
    height = lambda: float((sim.state.x[:, 2] * mass).sum() / mass.sum())  # noqa: E731
    start = height()
    for _ in range(frames):
        sim.frame()
    t = frames / 60.0
    return {"fall": round(start - height(), 2), "free_fall": round(0.5 * GRAVITY * t * t, 2)}


def indica_bowl(substeps: int) -> dict:
    """The reduced indica bowl's mean grain rise (mm) over its run and the grains that end outside the bowl."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    overrides = INDICA + [f"rice_sim.substeps={substeps}"]
    recipe = load_recipe(REPO / "graphs" / "rice_bowl.yaml", default_registry(), overrides)
    with tempfile.TemporaryDirectory(prefix="mass-scaling-") as tmp:
        result = run_recipe(
            recipe, outputs=["rice_sim.aggregate", "pile.aggregate", "bowl.vessel"], cache=Cache(Path(tmp) / "cache")
        )
    end, start = result.output("rice_sim.aggregate").placement, result.output("pile.aggregate").placement
    vessel = result.output("bowl.vessel")
    return {
        "rise": round(float(end.positions[:, 2].mean() - start.positions[:, 2].mean()), 2),
        "outside": int(vessel.outside(end.positions, margin=vessel.wall).sum()),
        "grains": len(end),
    }


def by_family(substeps: int) -> dict:
    """The reduced indica bowl's mean particle height (mm) added per frame by each kernel family, over frames 2–15:
    each kernel call's dispatch measured before and after (adhesion writes a copy: its output is read)."""
    from collections import defaultdict

    from nodes.simulation import setup

    added, frames, build = defaultdict(float), [], setup.build_simulation

    def recording(*args, **kwargs):
        sim = build(*args, **kwargs)
        n, dispatch, prestabilise, frame = sim.model.n_moving, sim.solver.dispatch, sim.solver._prestabilise, sim.frame
        inside = []

        def call(family, kernel, *kernel_args):
            name = family if isinstance(family, str) else "+".join(family)
            before = sim.state.x[:n, 2].mean()
            result = dispatch(family, kernel, *kernel_args)
            after = (kernel_args[-1] if family == "adhesion" else sim.state.x)[:n, 2].mean()
            added[name + (" (pre-stabilisation)" if inside else "")] += after - before
            return result

        def prestabilised(*a):
            inside.append(True)
            prestabilise(*a)
            inside.pop()

        def framed():
            frame()
            frames.append(dict(added))
            added.clear()

        sim.solver.dispatch, sim.solver._prestabilise, sim.frame = call, prestabilised, framed
        return sim

    setup.build_simulation = recording
    try:
        indica_bowl(substeps)
    finally:
        setup.build_simulation = build
    kept = frames[1:]
    names = sorted({k for f in kept for k in f})
    return {k: round(sum(f.get(k, 0.0) for f in kept) / len(kept), 3) for k in names}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", action="store_true", help=f"write {RECORD.relative_to(REPO)}")
    args = parser.parse_args()
    cases = (
        ("two crossed grains in free fall, 10 frames: mass-weighted fall against ½·g·t²", crossed_pair_fall),
        ("the reduced indica bowl (slender: 8 × its substeps), 15 frames: mean grain rise", indica_bowl),
    )
    rows = []
    for what, measure in cases:
        for substeps in (10, 40):
            load = os.getloadavg()[0]
            found = measure(substeps)
            row = {"what": what, "substeps": substeps, "command": COMMAND, "values": found, "unit": "mm"}
            rows.append({**row, **stamp(load)})
            print(json.dumps(found), substeps, flush=True)
    load = os.getloadavg()[0]
    found = by_family(10)
    what = "the reduced indica bowl, 10 substeps (slender: 80): mean particle height added per frame, by kernel family"
    rows.append({"what": what, "substeps": 10, "command": COMMAND, "values": found, "unit": "mm", **stamp(load)})
    print(json.dumps(found), flush=True)
    if args.record:
        write_rows(RECORD, rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
