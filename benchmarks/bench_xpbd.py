"""xpbd benchmarks (issue 6): scene speed, the cost of each effect, and accuracy against time.

- speed: rice bowl (2,000 grains, short), ikura don (310 eggs) through the node, warm JIT;
- effects: seconds per frame as effects are added one by one (500 grains), with kernel calls;
- accuracy: substeps × iterations on a 150-grain bowl; wall time, max penetration / radius,
  residual, final kinetic energy, mean element position error against a reference run
  (64 substeps × 8 iterations); Pareto front (time vs error) marked. Table + PNG.
Run: python benchmarks/bench_xpbd.py [--quick] [--only speed effects accuracy]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "simulation"))
sys.path.insert(0, str(ROOT / "benchmarks"))
RESULTS = ROOT / "benchmarks" / "results"

from machine import conditions  # noqa: E402
from xpbd_scenes import ikura_don, rice_bowl  # noqa: E402

from nodegraph.context import Context  # noqa: E402
from nodes.simulation.setup import build_simulation, finish_simulation  # noqa: E402
from nodes.simulation.xpbd import xpbd  # noqa: E402

RICE = ("gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping")
IKURA = ("gravity", "contact", "friction", "collider", "buoyancy", "damping")


def timed_node(aggregate, colliders, effects, moulds=None, **given):
    params = xpbd.resolve_params(given)
    ctx = Context.standalone(effects=effects)
    t = time.perf_counter()
    out = xpbd(ctx, aggregate=aggregate, colliders=colliders, moulds=moulds, **params)
    return time.perf_counter() - t, out


def pile_measures(out):
    """Fill height (95th percentile of element z above the lowest particle), contacts per grain."""
    from nodes.simulation.spatial_hash import neighbour_lists

    p = out["particles"]
    start, nbr, *_ = neighbour_lists(p.positions, p.radii, p.element.astype(np.int64), 0.05,
                                     2 * p.radii.max() + 0.05, len(p.positions), False)
    pairs = {(int(p.element[i]), int(p.element[j])) for i in range(len(p.positions)) for j in nbr[start[i]:start[i + 1]]
             if np.linalg.norm(p.positions[i] - p.positions[j]) - p.radii[i] - p.radii[j] <= 0.05}
    contacts = len(pairs) / (p.element.max() + 1)  # each pair counted from both sides = contacts per grain
    z = out["aggregate"].placement.positions[:, 2]
    return float(np.percentile(z, 95) - p.positions[:, 2].min()), contacts


def bench_speed(quick):
    rows = []
    n_rice, frames = (300, 20) if quick else (2000, 60)
    aggregate, colliders = rice_bowl(n_rice)
    timed_node(aggregate, colliders, RICE, frames=1)  # warm JIT and caches
    wall, out = timed_node(aggregate, colliders, RICE, frames=frames)
    height, contacts = pile_measures(out)
    rows.append(("rice bowl short", n_rice, len(out["particles"].positions), frames, wall, 30.0, 2041.0, height, contacts))
    print(rows[-1], flush=True)
    if not quick:
        wall, out = timed_node(aggregate, colliders, RICE, mode="full", frames=240)
        height, contacts = pile_measures(out)
        rows.append(("rice bowl full", n_rice, len(out["particles"].positions), 240, wall, float("nan"), 3867.0,
                     height, contacts))
        print(rows[-1], flush=True)
    if not quick:
        rows.append(bench_bunny())
        print(rows[-1], flush=True)
    n_egg = 60 if quick else 310
    aggregate, colliders = ikura_don(n_egg)
    timed_node(aggregate, colliders, IKURA, frames=1, mass=190.0)
    wall, out = timed_node(aggregate, colliders, IKURA, frames=frames, mass=190.0)
    height, contacts = pile_measures(out)
    rows.append(("ikura don short", n_egg, len(out["particles"].positions), frames, wall, 3.0, 65.0, height, contacts))
    print(rows[-1], flush=True)
    lines = ["| scene | elements | particles | frames (1/60 s, 10 substeps × 2 it.) | wall (s) | target (s) | G table 2 (s) "
             "| fill height (mm) | contacts / element |", "|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {a} | {b} | {c} | {d} | {e:.2f} | {f:g} | {g:g} | {h:.1f} | {i:.2f} |" for a, b, c, d, e, f, g, h, i in rows]
    return "\n".join(lines)


def bench_bunny():
    """G's rice bunny: graphs/rice_bunny.yaml up to the cull (engine-cached under results/), then its
    ``press`` node (the bunny as a mould) timed alone, warm JIT."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    recipe = load_recipe(ROOT / "graphs" / "rice_bunny.yaml", default_registry())
    result = run_recipe(recipe, outputs=["pile.aggregate", "bunny.mesh"], cache=Cache(RESULTS / "cache"))
    aggregate, mould = result.output("pile.aggregate"), result.output("bunny.mesh")
    press = recipe.nodes["press"]
    effects, given = recipe.effects, dict(press.params)
    timed_node(aggregate, None, effects, **{**given, "frames": 1}, moulds=[mould])  # warm
    wall, out = timed_node(aggregate, None, effects, **given, moulds=[mould])
    height, contacts = pile_measures(out)
    return ("rice bunny short (mould)", len(aggregate.placement), len(out["particles"].positions), given["frames"],
            wall, 90.0, 4376.0, height, contacts)


def bench_effects(quick):
    n, frames = (150, 5) if quick else (500, 20)
    aggregate, colliders = rice_bowl(n)
    ladder = [("gravity", "collider"), ("contact",), ("friction",), ("adhesion",), ("damping",), ("moisture",)]
    effects, rows, base = (), [], None
    params = xpbd.resolve_params({"frames": frames})
    for step in ladder:
        effects = effects + step
        sim = build_simulation(aggregate, colliders, frozenset(effects), params)
        sim.solver.frame()  # warm
        t = time.perf_counter()
        for _ in range(frames):
            sim.solver.frame()
        per_frame = (time.perf_counter() - t) / frames
        base = per_frame if base is None else base
        calls = sim.solver.dispatch.calls
        rows.append(("+ " + " + ".join(step), per_frame * 1e3, per_frame / base,
                     ", ".join(f"{k} {v}" for k, v in sorted(calls.items()))))
        print(rows[-1], flush=True)
    lines = [f"| effects ({n} grains, {frames} frames) | ms / frame | × gravity+collider | kernel calls |",
             "|---|---|---|---|"]
    lines += [f"| {a} | {b:.1f} | {c:.2f} | {d} |" for a, b, c, d in rows]
    return "\n".join(lines)


def run_positions(aggregate, colliders, substeps, iterations, frames):
    params = xpbd.resolve_params({"frames": frames, "substeps": substeps, "iterations": iterations, "sleep_speed": 0.0})
    sim = build_simulation(aggregate, colliders, frozenset(RICE), params)
    t = time.perf_counter()
    for _ in range(frames):
        sim.solver.frame()
    wall = time.perf_counter() - t
    out = finish_simulation(sim)
    dg = sim.solver.diagnostics
    return wall, out["aggregate"].placement.positions, max(dg.penetration), dg.residual[-1], dg.kinetic_energy[-1]


def bench_accuracy(quick):
    n, frames = (60, 10) if quick else (150, 30)
    aggregate, colliders = rice_bowl(n)
    grid_s = (1, 2, 4) if quick else (1, 2, 4, 8, 16, 32)
    grid_i = (1, 2) if quick else (1, 2, 4, 8)
    ref_s, ref_i = (16, 4) if quick else (64, 8)
    run_positions(aggregate, colliders, 1, 1, 1)  # warm
    _, reference, *_ = run_positions(aggregate, colliders, ref_s, ref_i, frames)
    rows = []
    for s in grid_s:
        for it in grid_i:
            wall, pos, pen, res, ke = run_positions(aggregate, colliders, s, it, frames)
            err = float(np.linalg.norm(pos - reference, axis=1).mean())
            rows.append([s, it, wall, pen, res, ke, err])
            print(rows[-1], flush=True)
    rows = np.array(rows)
    pareto = np.array([not np.any((rows[:, 2] <= r[2]) & (rows[:, 6] <= r[6]) & ((rows[:, 2] < r[2]) | (rows[:, 6] < r[6])))
                       for r in rows])
    plot_accuracy(rows, pareto, n, frames, ref_s, ref_i)
    lines = [f"| substeps | iterations | wall (s) | max penetration / r | residual (mm) | final KE (g·mm²/s²) "
             f"| mean position error vs {ref_s}×{ref_i} (mm) | Pareto |", "|---|---|---|---|---|---|---|---|"]
    lines += [f"| {int(r[0])} | {int(r[1])} | {r[2]:.2f} | {r[3]:.3f} | {r[4]:.3g} | {r[5]:.3g} | {r[6]:.3f} | "
              f"{'★' if p else ''} |" for r, p in zip(rows, pareto)]
    return "\n".join(lines)


def plot_accuracy(rows, pareto, n, frames, ref_s, ref_i):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    sc = ax.scatter(rows[:, 2], rows[:, 6], c=np.log2(rows[:, 0]), s=20 + 15 * np.log2(rows[:, 1]) ** 2, cmap="viridis")
    front = rows[pareto][np.argsort(rows[pareto][:, 2])]
    ax.plot(front[:, 2], front[:, 6], "r-o", mfc="none", label="Pareto front")
    for r in rows:
        ax.annotate(f"{int(r[0])}×{int(r[1])}", (r[2], r[6]), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel(f"mean element position error vs {ref_s}×{ref_i} (mm)")
    ax.set_title(f"xpbd accuracy vs time: {n} grains in a bowl, {frames} frames (substeps × iterations)")
    fig.colorbar(sc, label="log2 substeps")
    ax.legend()
    fig.tight_layout()
    fig.savefig(RESULTS / "bench_xpbd_accuracy.png", dpi=120)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", nargs="+", default=["speed", "effects", "accuracy"])
    args = ap.parse_args()
    RESULTS.mkdir(parents=True, exist_ok=True)
    sections = {"speed": bench_speed, "effects": bench_effects, "accuracy": bench_accuracy}
    for name in args.only:
        table = sections[name](args.quick) + f"\n\n{conditions()}"
        print(table, flush=True)
        (RESULTS / f"bench_xpbd_{name}{'_quick' if args.quick else ''}.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
