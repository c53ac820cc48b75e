"""xpbd stability map (issue 11): where the solver holds.

Map 1 — Δt/substeps × mass ratio × compliance: a two-cube stack (``scene_builders.stack_column``, the
upper cube ``ratio``× heavier) dropped 0.1 r onto the ground; max inter-element penetration / r over
the run, energy growth (max of E − E₀ over the run, in M·g·r; gravity does the only work, so > 0 is
a gain) and the settled error of the element centres against the analytic rest (r). A refused
setting (``step_limits.check_gravity_step``: g·h² beyond what the iterations hold or the speed clamp)
is marked "refused".
Map 2 — speed clamp × wall thickness: 200 particles fired at 20 m/s at a bowl wall; how many cross it.
Run: python benchmarks/bench_xpbd_stability.py [--quick]   (tables; benchmarks/results/xpbd_stability[_quick].png)
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported


from scene_builders import bowl_mesh, mechanical_energy, solver_run, stack_column

from nodes.simulation.collider import signed_distance_grid
from nodes.simulation.settings import solver_settings_for

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")


ITERATIONS = 2  # the node's default
# compliance (s²/g) → the node's stiffness (N/m); 0 (rigid) is no node setting: its stiffest, 1e5 N/m
STIFFNESS = {0.0: 100000.0, 1e-6: 1000.0, 1e-3: 1.0}


def stack_cell(dt, substeps, ratio, compliance, frames):
    try:
        stiffness = STIFFNESS[compliance]
        s, rest, mass = stack_column(2, dt=dt, substeps=substeps, iterations=ITERATIONS, stiffness=stiffness)
    except ValueError:
        return None
    s.model.w[8:] /= ratio
    total = mass * (1 + ratio)
    e0, pen, gain = mechanical_energy(s), 0.0, 0.0
    for _ in range(frames):
        s.frame()
        pen = max(pen, s.solver.diagnostics.penetration[-1])
        gain = max(gain, (mechanical_energy(s) - e0) / (total * 9810.0 * 1.0))
    if not np.isfinite(s.state.x).all():
        return np.inf, np.inf, np.inf
    return pen, gain, float(np.linalg.norm(s.centres() - rest, axis=1).max())


def wall_cell(clamp, wall, frames=20):
    bowl = bowl_mesh(radius=20.0, wall=wall, rim=0.3, segments=64)
    sdf = signed_distance_grid([bowl], np.array([-24.0, -24, -24]), np.array([24.0, 24, 10]), min(0.25, wall / 2))
    settings = solver_settings_for(
        frozenset({"contact", "collider"}), 0.5, substeps=4, iterations=1, speed_clamp=clamp, sleep_speed=0.0
    )
    rng = np.random.default_rng(1)
    n = 200
    x = rng.uniform(-4, 4, (n, 3))
    s = solver_run(
        x, np.full(n, 0.5), np.full(n, 40.0), np.arange(n + 1), np.zeros((n, 3)), np.tile([1.0, 0, 0, 0], (n, 1)),
        settings, sdf=sdf,
    )  # fmt: skip
    d = x / np.linalg.norm(x, axis=1, keepdims=True)
    d[:, 2] = -np.abs(d[:, 2])
    s.state.v[:] = 20000.0 * d
    through = np.zeros(n, bool)
    for _ in range(frames):
        s.frame()
        through |= (np.linalg.norm(s.state.x, axis=1) > 20.0 - wall) & (s.state.x[:, 2] < 6.0)
    return int(through.sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a few cells, seconds")
    args = ap.parse_args()
    if args.quick:
        steps, ratios, compliances, frames = [(1 / 60, 10), (1 / 60, 2)], [1, 1000], [1e-6], 15
        clamps, walls = [1.0, 2.0], [0.4]
    else:
        steps = [(1 / 60, 40), (1 / 60, 10), (1 / 60, 4), (1 / 60, 3), (1 / 60, 2), (1 / 30, 10), (0.5, 256), (0.5, 1)]
        ratios, compliances, frames = [1, 10, 100, 1000], [0.0, 1e-6, 1e-3], 45
        clamps, walls = [0.5, 1.0, 2.0], [0.2, 0.4, 0.8, 2.0]
    rows = []
    print(
        "| dt (s) | substeps | mass ratio | compliance (s²/g) | max penetration (r) | energy gain (M·g·r) "
        "| rest error (r) |"
    )
    print("|---|---|---|---|---|---|---|")
    for dt, sub in steps:
        for ratio in ratios:
            for c in compliances:
                cell = stack_cell(dt, sub, ratio, c, frames)
                rows.append((dt, sub, ratio, c, cell))
                vals = "refused | – | –" if cell is None else " | ".join(f"{v:.3g}" for v in cell)
                print(f"| {dt:.4g} | {sub} | {ratio} | {c:g} | {vals} |", flush=True)
    print("\n| speed clamp (r/substep) | wall (mm) | particles through (of 200) |\n|---|---|---|")
    walls_rows = []
    for clamp in clamps:
        for wall in walls:
            k = wall_cell(clamp, wall)
            walls_rows.append((clamp, wall, k))
            print(f"| {clamp} | {wall} | {k} |", flush=True)
    try:
        import matplotlib

        matplotlib.use("Agg")
    except ImportError:
        return
    plot(rows, walls_rows, RESULTS / f"xpbd_stability{'_quick' if args.quick else ''}.png")


def plot(rows, walls_rows, path):
    """Left: max penetration against g·h²/r per iteration (the refusal's measure: refused at
    g·h² > iterations/4·r, dashed), marker size = mass ratio, colour = compliance, refused cells as
    crosses at the top; right: particles through the wall, speed clamp × wall thickness."""
    import matplotlib.pyplot as plt

    from nodes.simulation.step_limits import HOLD, SINK

    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5))
    colours = {c: f"C{k}" for k, c in enumerate(sorted({row[3] for row in rows}))}
    for dt, sub, ratio, c, cell in rows:
        load = 9810 * (dt / sub) ** 2 / ITERATIONS
        size = 20 + 12 * np.log10(ratio) ** 2
        if cell is None:
            ax.scatter(load, 3.0, s=size, marker="x", c=colours[c])
        else:
            ax.scatter(load, min(max(cell[0], 1e-3), 3.0), s=size, c=colours[c], alpha=0.7)
    ax.axvline(HOLD / SINK, ls="--", c="k", lw=1)
    ax.axhline(1.0, ls=":", c="grey", lw=1)
    for c, colour in colours.items():
        ax.scatter([], [], c=colour, label=f"compliance {c:g} s²/g")
    ax.legend(loc="lower right", fontsize=8)
    ax.set(
        xscale="log",
        yscale="log",
        xlabel="g·h² / iterations (mm, r = 1 mm)",
        ylabel="max penetration over the run (r)",
        title="two-cube stack: size = mass ratio 1…1000, × = refused",
    )
    clamps = sorted({row[0] for row in walls_rows})
    walls = sorted({row[1] for row in walls_rows})
    grid = np.array([[next(k for cl, w, k in walls_rows if cl == c and w == wall) for wall in walls] for c in clamps])
    bx.imshow(grid, cmap="Reds", vmin=0, vmax=200, origin="lower", aspect="auto")
    for i in range(len(clamps)):
        for j in range(len(walls)):
            bx.text(j, i, str(grid[i, j]), ha="center", va="center")
    bx.set(
        xticks=range(len(walls)),
        xticklabels=[f"{w:g}" for w in walls],
        yticks=range(len(clamps)),
        yticklabels=[f"{c:g}" for c in clamps],
        xlabel="wall thickness (mm; particles r = 0.5)",
        ylabel="speed clamp (r per substep)",
        title="particles through the bowl wall (of 200 at 20 m/s)",
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"\nsaved {path}")


if __name__ == "__main__":
    main()
