"""xpbd benchmarks (issue 6): scene speed, the cost of each effect, and accuracy against time.

- speed: rice bowl (2,000 grains, short), ikura don (310 eggs) through the node, warm JIT;
- effects: seconds per frame as effects are added one by one (500 grains), with kernel calls;
- accuracy: substeps × iterations on a 150-grain bowl and on a stack of 8 cubes resting on the
  ground (exact rest known); wall time, max penetration / radius, residual, energy drift, mean
  element position error against a reference run with many more substeps (and, for the stack, the
  analytic rest); Pareto front (time vs error) marked. Tables + a two-panel PNG.
Run: python benchmarks/bench_xpbd.py [--quick] [--only speed effects accuracy]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from machine import conditions
from scene_builders import energy_drift, ikura_don, mechanical_energy, rice_bowl, stack_column

from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.xpbd import xpbd

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")


RICE = ("gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping")
IKURA = ("gravity", "contact", "friction", "collider", "buoyancy", "damping")


def timed_node(aggregate, colliders, effects, moulds=None, **given):
    t = time.perf_counter()  # parameter validation is inside, but takes microseconds
    out = xpbd.call(effects=effects, aggregate=aggregate, colliders=colliders, moulds=moulds, **given)
    return time.perf_counter() - t, out


def pile_measures(out):
    """Fill height (95th percentile of element z above the lowest particle), contacts per grain."""
    from nodes.simulation.spatial_hash import neighbour_lists

    p = out["particles"]
    start, nbr, _, _, order, _ = neighbour_lists(
        p.positions, p.radii, p.element.astype(np.int64), 0.05, 2 * p.radii.max() + 0.05, len(p.positions), False
    )
    pairs = {  # row k lists the partners of particle order[k]
        (int(p.element[i]), int(p.element[j]))
        for k, i in enumerate(order)
        for j in nbr[start[k] : start[k + 1]]
        if np.linalg.norm(p.positions[i] - p.positions[j]) - p.radii[i] - p.radii[j] <= 0.05
    }
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
    rows.append(
        ("rice bowl short", n_rice, len(out["particles"].positions), frames, wall, 30.0, 2041.0, height, contacts)
    )
    print(rows[-1], flush=True)
    if not quick:
        wall, out = timed_node(aggregate, colliders, RICE, mode="full", frames=240)
        height, contacts = pile_measures(out)
        rows.append(
            (
                "rice bowl full",
                n_rice,
                len(out["particles"].positions),
                240,
                wall,
                float("nan"),
                3867.0,
                height,
                contacts,
            )
        )
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
    lines = [
        "| scene | elements | particles | frames (1/60 s, 10 substeps × 2 it.) | wall (s) | target (s) | G table 2 (s) "
        "| fill height (mm) | contacts / element |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {a} | {b} | {c} | {d} | {e:.2f} | {f:g} | {g:g} | {h:.1f} | {i:.2f} |" for a, b, c, d, e, f, g, h, i in rows
    ]
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
    return (
        "rice bunny short (mould)",
        len(aggregate.placement),
        len(out["particles"].positions),
        given["frames"],
        wall,
        90.0,
        4376.0,
        height,
        contacts,
    )


def bench_effects(quick):
    n, frames = (150, 5) if quick else (500, 20)
    aggregate, colliders = rice_bowl(n)
    ladder = [("gravity", "collider"), ("contact",), ("friction",), ("adhesion",), ("damping",), ("moisture",)]
    effects, rows, base = (), [], None
    params = XpbdParams(**xpbd.resolve_params({"frames": frames}))
    for step in ladder:
        effects = effects + step
        sim = build_simulation(aggregate, colliders, frozenset(effects), params)
        sim.frame()  # warm
        t = time.perf_counter()
        for _ in range(frames):
            sim.frame()
        per_frame = (time.perf_counter() - t) / frames
        base = per_frame if base is None else base
        calls = sim.solver.dispatch.calls
        rows.append(
            (
                "+ " + " + ".join(step),
                per_frame * 1e3,
                per_frame / base,
                ", ".join(f"{k} {v}" for k, v in sorted(calls.items())),
            )
        )
        print(rows[-1], flush=True)
    lines = [
        f"| effects ({n} grains, {frames} frames) | ms / frame | × gravity+collider | kernel calls |",
        "|---|---|---|---|",
    ]
    lines += [f"| {a} | {b:.1f} | {c:.2f} | {d} |" for a, b, c, d in rows]
    return "\n".join(lines)


def run_to_rest(run, frames, repeats=1, make=None):
    """Run ``frames`` frames of a ``setup.Simulation`` or ``scene_builders.SolverRun``; returns (wall of the
    frames alone, element centres, max penetration / r over the run, last residual, energy drift and
    rise of ``energy_drift``). With ``repeats`` > 1 the (deterministic) run is repeated on fresh runs
    from ``make`` and the fastest wall kept."""
    walls = []
    for k in range(repeats):
        s = run if k == 0 else make()
        energies, wall = [], 0.0
        for _ in range(frames):
            t = time.perf_counter()
            s.frame()
            wall += time.perf_counter() - t
            energies.append(mechanical_energy(s))
        walls.append(wall)
    m = s.model
    mass = float(np.sum(1.0 / m.w[: m.n_moving]))
    drift, rise = energy_drift(energies, mass, s.solver.settings.gravity, float(np.median(m.r[: m.n_moving])))
    dg = s.solver.diagnostics
    return min(walls), m.centres(s.state.x), max(dg.penetration), dg.residual[-1], drift, rise


def bowl_maker(aggregate, colliders, frames):
    def make(substeps, iterations):
        params = xpbd.resolve_params(
            {"frames": frames, "substeps": substeps, "iterations": iterations, "sleep_speed": 0.0}
        )
        return build_simulation(aggregate, colliders, frozenset(RICE), XpbdParams(**params))

    return make


def sweep(make, frames, grid, reference, second, repeats=1):
    """Rows [substeps, iterations, wall, penetration, residual, drift, rise, error vs reference, second
    error] for every (substeps, iterations) in ``grid``; the error vs the reference run is the mean
    element-centre distance (mm), ``second`` = (title, f(centres, reference centres)) another one."""
    make(*reference).frame()  # warm JIT
    ref = run_to_rest(make(*reference), frames)[1]
    print(f"reference {reference[0]}×{reference[1]}: {second[0]} {second[1](ref, ref):.3g}", flush=True)
    rows = []
    for s, it in grid:
        try:
            make(s, it)
        except ValueError as refused:  # gravity beyond the speed clamp (issue 11): no row
            print(f"{s}×{it}: refused ({str(refused).split(':')[0]})", flush=True)
            continue
        wall, centres, pen, res, drift, rise = run_to_rest(make(s, it), frames, repeats, lambda s=s, it=it: make(s, it))
        rows.append(
            [s, it, wall, pen, res, drift, rise, np.linalg.norm(centres - ref, axis=1).mean(), second[1](centres, ref)]
        )
        print(" ".join(f"{v:.4g}" for v in rows[-1]), flush=True)
    return np.array(rows)


def height_profile_error(centres, ref):
    """Mean |sorted z − sorted z of the reference| (mm): the 1-D Wasserstein distance between the
    element heights, blind to which grain went where (the pile's chaotic part) but not to its shape."""
    return float(np.abs(np.sort(centres[:, 2]) - np.sort(ref[:, 2])).mean())


def pareto_front(rows, col=7):
    """Rows no other row beats on both wall time (col 2) and error (``col``; 7 = vs the reference)."""
    t, e = rows[:, 2], rows[:, col]
    return np.array([not np.any((t <= a) & (e <= b) & ((t < a) | (e < b))) for a, b in zip(t, e)])


def accuracy_table(rows, reference, second):
    """Markdown rows of ``sweep``; ★ marks the Pareto front on the position error vs the reference,
    ☆ the front on the ``second`` error."""
    ref = f"{reference[0]}×{reference[1]}"
    head = [
        "substeps",
        "iterations",
        "wall (s)",
        "max penetration / r",
        "residual (mm)",
        "energy drift (M·g·r)",
        "max energy rise (M·g·r)",
        f"mean position error vs {ref} (mm)",
        second,
        "Pareto ★ position, ☆ 2nd",
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r, p, q in zip(rows, pareto_front(rows), pareto_front(rows, 8)):
        cells = [
            f"{int(r[0])}",
            f"{int(r[1])}",
            f"{r[2]:.3g}",
            f"{r[3]:.3g}",
            f"{r[4]:.3g}",
            f"{r[5]:+.2g}",
            f"{r[6]:.2g}",
            f"{r[7]:.3g}",
            f"{r[8]:.3g}",
            ("★" if p else "") + ("☆" if q else ""),
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def bench_accuracy(quick):
    """Substeps × iterations on the rice bowl and on the stack test (``scene_builders.stack_column``),
    plus the xpbd node's defaults (10 × 2); Pareto front on wall time vs error against a reference run.

    Both scenes are below ``solver.PARALLEL_PARTICLES``: the solver runs them on one thread (on the
    shared 2-core machine, two OpenMP threads under load spread identical runs over 10× in wall time)."""
    if quick:
        n, bowl_frames, bowl_ref, stack_frames, stack_ref = 60, 12, (16, 4), 30, (64, 8)
        grid_s, grid_i, stack_s, stack_i = (2,), (1, 2), (1, 4, 16), (1, 2, 4)
    else:
        n, bowl_frames, bowl_ref, stack_frames, stack_ref = 150, 45, (128, 8), 90, (256, 16)
        grid_s, grid_i = (1, 2, 4, 8, 16, 32), (1, 2, 4, 8)
        stack_s, stack_i = (1, 2, 4, 8, 16, 32, 64), (1, 2, 4, 8, 16, 32)
    layers = 8
    aggregate, colliders = rice_bowl(n)
    scenes = []
    heights = ("height-profile error vs reference (mm)", height_profile_error)
    bowl = sweep(
        bowl_maker(aggregate, colliders, bowl_frames),
        bowl_frames,
        sorted({*((s, i) for s in grid_s for i in grid_i), (10, 2)}),
        bowl_ref,
        heights,
        repeats=1 if quick else 2,
    )
    scenes.append((f"{n} grains in a bowl, {bowl_frames} frames", bowl, bowl_ref, heights[0], True))
    rest = stack_column(layers)[1]
    analytic = (
        "mean position error vs analytic rest (mm)",
        lambda centres, _: float(np.linalg.norm(centres - rest, axis=1).mean()),
    )
    stack = sweep(
        lambda s, it: stack_column(layers, substeps=s, iterations=it)[0],
        stack_frames,
        sorted({*((s, i) for s in stack_s for i in stack_i), (10, 2)}),
        stack_ref,
        analytic,
        repeats=1 if quick else 5,  # --quick: a smoke run of the sweep, its times not compared
    )
    scenes.append(
        (
            f"stack of {layers} cubes (2×2×2 particles, r = 1 mm), {stack_frames} frames",
            stack,
            stack_ref,
            analytic[0],
            False,
        )
    )
    plot_accuracy(scenes, quick)
    out = [ENERGY_NOTE]
    for title, rows, ref, second, _ in scenes:
        out += [
            f"**{title}** (reference {ref[0]} substeps × {ref[1]} iterations)",
            "",
            accuracy_table(rows, ref, second),
            "",
        ]
    return "\n".join(out).rstrip()


ENERGY_NOTE = (
    "Energy drift: E = KE + Σ m·g·z after each frame; drift = E_T − E_k0 and max rise = max over "
    "k ≥ k0 of E_k − E_k0, over the last third of the frames (k0 = T − ⌊T/3⌋), "
    "in units of M·g·r "
    "(the whole mass lifted by one particle radius). At rest both should be ≈ 0; drift < 0 is settling "
    "or sinking, a rise > 0 is energy gained. Max penetration / r is over the whole run; the position "
    "error is the mean element-centre distance at the last frame; the bowl's height-profile error "
    "(``height_profile_error``) compares sorted element heights, so it sees the pile's shape, not "
    "which grain went where. Wall: the frames alone on one numba "
    "thread, the fastest of 5 identical runs for the stack and of 2 for the full-size bowl.\n"
)


def plot_accuracy(scenes, quick):
    """One panel per scene: wall time vs position error against the reference, Pareto front in red;
    scenes flagged ``plot_second`` (the bowl, whose position error is mostly the pile's chaos) add
    their second error (triangles, front in orange)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(scenes), figsize=(7 * len(scenes), 5.5))
    for ax, (title, rows, ref, second, plot_second) in zip(axes, scenes):
        columns = [(7, "o", "r", f"position error vs {ref[0]}×{ref[1]}")]
        if plot_second:
            columns.append((8, "^", "orange", second.replace(" (mm)", "")))
        for col, marker, colour, label in columns:
            sc = ax.scatter(
                rows[:, 2],
                rows[:, col],
                c=np.log2(rows[:, 0]),
                marker=marker,
                s=20 + 15 * np.log2(rows[:, 1]) ** 2,
                cmap="viridis",
            )
            front = rows[pareto_front(rows, col)]
            front = front[np.argsort(front[:, 2])]
            ax.plot(
                front[:, 2], front[:, col], "-", color=colour, marker=marker, mfc="none", label=f"Pareto front: {label}"
            )
            for r in rows:
                default = r[0] == 10 and r[1] == 2
                ax.annotate(
                    f"{int(r[0])}×{int(r[1])}" + (" (default)" if default else ""),
                    (r[2], r[col]),
                    fontsize=8 if default else 6,
                    color="red" if default else "black",
                    xytext=(3, 3),
                    textcoords="offset points",
                )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("error (mm)")
        ax.set_title(title, fontsize=10)
        fig.colorbar(sc, ax=ax, label="log2 substeps (marker size: iterations)")
        ax.legend()
    fig.suptitle("xpbd accuracy vs time (substeps × iterations)")
    fig.tight_layout()
    fig.savefig(RESULTS / f"bench_xpbd_accuracy{'_quick' if quick else ''}.png", dpi=120)


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
