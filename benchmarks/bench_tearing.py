"""Shape matching with tearing (issue 15, SPEC §5): U table 4.1, the mesh split, accuracy against time.

table — U table 4.1: cube surfaces with k = 10, 15, 20, 25 segments per edge (602 … 3,752 vertices),
  steps per second of ``ElasticBody.step`` (goals + U eq. 3.16–3.17 + the break test), one cluster,
  without splits and with 50 cluster splits during the timed run (a vertex's fan torn out every
  steps/50 steps: split, relabel, re-cluster, caps); ratio to U's 140/65/40/20 and 92/42/23/12
  (Core2Duo E8400). Target ≥ 50× U on every row.
split — the cut along edges (one vertex's fan; every edge): ``SurfaceMesh.cut`` in all, and its corner
  unions alone by numba's union-find (used) and by scipy's connected components (numpy + scipy).
accuracy — the tear_block scene on a k = 6 cube: substeps per frame × rotation iterations against a
  400-substep, 8-iteration reference: max over frames of the RMS vertex distance (/ size) of an
  elastic pull-and-release run, the first-tear time error of a run whose corner pull grows linearly
  until the fan tears out, and wall time; table and Pareto PNG in benchmarks/results/.
Run: python benchmarks/bench_tearing.py [--quick] [--only table|split|accuracy]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from nodes.tearing.body import BodySettings, ElasticBody
from nodes.tearing.elastic_body import pull_field
from nodes.tearing.surface_mesh import SurfaceMesh, cube_surface, union_labels

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")


U_TABLE = {10: (140.0, 92.0), 15: (65.0, 42.0), 20: (40.0, 23.0), 25: (20.0, 12.0)}  # steps/s: none, 50 splits


def _fan_rim(mesh: SurfaceMesh, vertex: int) -> np.ndarray:
    """Both halves of the rim edges of ``vertex``'s fan (U's tear of a pulled vertex)."""
    corner = np.flatnonzero(mesh.origin == vertex)
    broken = np.zeros(len(mesh.twin), bool)
    broken[3 * (corner // 3) + (corner % 3 + 1) % 3] = True
    return (mesh.twin >= 0) & (broken | broken[np.maximum(mesh.twin, 0)])


def steps_per_second(k: int, steps: int, splits: int, during: bool) -> tuple[float, int]:
    """Steps/s of a k-segment cube surface after ``splits`` fans were torn out (U's measure: the body in
    splits + 1 clusters), or with them torn out evenly during the timed run (``during``: the tears'
    cost included); and the number of tears."""
    vertices, faces = cube_surface(k, 20.0)
    settings = BodySettings(h=1 / 60, stiffness=2e2, beta=0.3, tearing=True)
    body = ElasticBody(vertices, faces, 10.0, settings)
    body.x += np.random.default_rng(0).normal(0.0, 0.05, body.x.shape)  # something to match
    rng = np.random.default_rng(1)

    def tear_one():
        biggest = int(np.argmax(np.diff(body.start)))
        body.tear(_fan_rim(body.mesh, int(rng.integers(body.start[biggest], body.start[biggest + 1]))))

    if not during:
        for _ in range(splits):
            tear_one()
    for _ in range(3):
        body.step()  # compiled, warm
    every = steps // splits if splits and during else steps + 1
    start = time.perf_counter()
    for i in range(steps):
        if i % every == 0 and body.calls["tear"] < splits:
            tear_one()
        body.step()
    return steps / (time.perf_counter() - start), body.calls["tear"]


def table(quick: bool) -> None:
    steps = 200 if quick else 3000
    print(f"\nU table 4.1: steps per second (cube surfaces, {steps} steps; U: Core2Duo E8400)")
    print("  after 50: the body already in 51 clusters (U's measure); during: 50 tears inside the timed steps")
    print(
        f"{'k':>3} {'vertices':>8} | {'no split':>8} {'U':>4} {'ratio':>6} | {'after 50':>8} {'U':>4} {'ratio':>6} | "
        f"{'during':>7} {'ratio':>6}"
    )
    for k, (u_none, u_split) in U_TABLE.items():
        if quick and k > 10:
            break
        none, _ = steps_per_second(k, steps, 0, False)
        after, done = steps_per_second(k, steps, 50, False)
        during, done_during = steps_per_second(k, steps, 50, True)
        assert done == done_during == 50, f"{done}, {done_during} tears, not 50"
        print(
            f"{k:>3} {6 * k * k + 2:>8} | {none:>8.0f} {u_none:>4.0f} {none / u_none:>5.0f}× | "
            f"{after:>8.0f} {u_split:>4.0f} {after / u_split:>5.0f}× | {during:>7.0f} {during / u_split:>5.0f}×"
        )


def _scipy_corner_vertices(mesh: SurfaceMesh, broken: np.ndarray):
    """The cut's corner unions by scipy's connected components (the numpy + scipy alternative)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    twin = mesh.twin
    glued = (twin >= 0) & ~(mesh.cracked | broken)
    h = np.flatnonzero(glued)
    h = h[h < twin[h]]
    t = twin[h]
    nxt = lambda e: 3 * (e // 3) + (e + 1) % 3  # noqa: E731
    rows, cols = np.concatenate([h, nxt(h)]), np.concatenate([nxt(t), t])
    n = 3 * len(mesh.faces)
    graph = coo_matrix((np.ones(len(rows), np.int8), (rows, cols)), shape=(n, n))
    count, labels = connected_components(graph, directed=False)
    return labels, count


def split(quick: bool) -> None:
    k = 10 if quick else 25
    vertices, faces = cube_surface(k, 1.0)
    mesh = SurfaceMesh.from_faces(faces, len(vertices))
    repeats = 5 if quick else 50
    print(f"\nsplit along edges, k = {k} cube ({len(vertices):,} vertices), ms per cut (best of {repeats})")
    print(f"{'cut':>14} | {'SurfaceMesh.cut (numba)':>23} | {'unions alone: numba':>19} {'scipy':>7} | same")
    mesh.cut(np.zeros(len(mesh.twin), bool))  # compiled
    for name, broken in (
        ("one fan", _fan_rim(mesh, len(vertices) // 2)),
        ("every edge", np.ones(len(faces) * 3, bool)),
    ):
        cut, numba_ms, scipy_ms, same = _time_cut(mesh, broken, repeats)
        print(f"{name:>14} | {cut:>23.2f} | {numba_ms:>19.3f} {scipy_ms:>7.3f} | {same}")


def _time_cut(mesh: SurfaceMesh, broken: np.ndarray, repeats: int):
    """Best ms of the whole cut, of its corner unions by numba and by scipy; whether both unions agree."""
    h = np.flatnonzero((mesh.twin >= 0) & ~broken)
    h = h[h < mesh.twin[h]]
    t = mesh.twin[h]
    rows = np.concatenate([h, 3 * (h // 3) + (h + 1) % 3])
    cols = np.concatenate([3 * (t // 3) + (t + 1) % 3, t])
    n = 3 * len(mesh.faces)
    runs = (
        lambda: mesh.cut(broken),
        lambda: union_labels(n, rows, cols),
        lambda: _scipy_corner_vertices(mesh, broken),
    )
    best = []
    for fn in runs:
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            fn()
            times.append(time.perf_counter() - start)
        best.append(min(times) * 1e3)
    same = union_labels(n, rows, cols)[1] == _scipy_corner_vertices(mesh, broken)[1]
    return (*best, same)


TEAR_RAMP = 1.5e5  # mm/s² per second: the corner's pull grows until the fan tears out (≈ 0.9 s at k = 6)


def _scene(substeps: int, iterations: int, tear: bool, frames: int):
    """tear_block on a k = 6 cube, its corner pulled harder each frame until it tears (first tear time),
    or its elastic pull-and-release (positions per frame)."""
    vertices, faces = cube_surface(6, 20.0)
    accel, moving = pull_field(vertices, [1.0, 1.0, 1.0], 1.0 if tear else 3e4, 0.0 if tear else 3.5, True)
    settings = BodySettings(
        h=(1 / 60) / substeps,
        stiffness=2e4,
        beta=0.3,
        rotation_iterations=iterations,
        damping=5.0,
        tearing=tear,
    )
    body = ElasticBody(vertices, faces, 10.0, settings, accel=accel, moving=moving)
    unit = body.accel.copy()
    order = np.lexsort(body.x0.T[::-1])  # rest positions name the vertices (the body sorts them by cluster)
    out, first_tear = [], np.nan
    for frame in range(frames):
        if tear and np.isnan(first_tear):
            body.accel[:] = unit * TEAR_RAMP * frame / 60
        if frame == frames // 4 and not tear:
            body.accel[:] = 0.0
        for s in range(substeps):
            if body.step() and np.isnan(first_tear):
                first_tear = (frame + (s + 1) / substeps) / 60
                body.accel[:] = 0.0
        if not tear:
            out.append(body.x[order].copy())
    return np.array(out), first_tear


def accuracy(quick: bool) -> None:
    frames = 90 if quick else 120  # the ramped pull tears the corner at ≈ 1.3 s (80 frames)
    ref_sub = 20 if quick else 400
    grid_sub = (1, 5) if quick else (1, 2, 5, 10, 20, 50)
    grid_it = (1, 4) if quick else (1, 2, 4, 8)
    ref_x, _ = _scene(ref_sub, 8, False, frames)
    _, ref_tear = _scene(ref_sub, 8, True, frames)
    print(
        f"\naccuracy vs a {ref_sub}-substep, 8-iteration reference (k = 6 cube, {frames} frames; "
        f"reference tear at {ref_tear:.4f} s)"
    )
    print(f"{'substeps':>8} {'iters':>5} | {'shape err (rms/size)':>20} | {'tear-time err (s)':>17} | {'wall s':>6}")
    rows = []
    for sub in grid_sub:
        for it in grid_it:
            t = time.perf_counter()
            x, _ = _scene(sub, it, False, frames)
            _, tear = _scene(sub, it, True, frames)
            wall = time.perf_counter() - t
            shape = float(np.sqrt(((x - ref_x) ** 2).sum(2).mean(1)).max() / 20.0)
            tear_err = abs(tear - ref_tear)
            rows.append((sub, it, shape, tear_err, wall))
            print(f"{sub:>8} {it:>5} | {shape:>20.2e} | {tear_err:>17.4f} | {wall:>6.2f}")
    _pareto(rows)


def _pareto(rows) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, col, label in ((axes[0], 2, "shape error (max rms / size)"), (axes[1], 3, "tear-time error (s)")):
        shown = [r for r in rows if np.isfinite(r[col])]  # a run that never tore has no tear-time error
        for sub, it, shape, tear, wall in shown:
            y = max((shape, tear)[col - 2], 1e-6)
            ax.scatter(wall, y, c=f"C{(1, 2, 4, 8).index(it) if it in (1, 2, 4, 8) else 0}")
            ax.annotate(f"{sub}×{it}", (wall, y), fontsize=7)
        best, xs, ys = np.inf, [], []
        for r in sorted(shown, key=lambda r: r[4]):
            if r[col] < best:
                best = r[col]
                xs.append(r[4])
                ys.append(max(r[col], 1e-6))
        ax.step(xs, ys, where="post", color="k", lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time of both runs (s)")
        ax.set_ylabel(label)
    for it in (1, 2, 4, 8):
        axes[0].scatter([], [], c=f"C{(1, 2, 4, 8).index(it)}", label=f"{it} rotation iteration{'s' * (it > 1)}")
    axes[0].legend(fontsize=7, loc="upper right")
    fig.suptitle("tearing: substeps × rotation iterations (labels), Pareto front in black")
    fig.tight_layout()
    RESULTS.mkdir(parents=True, exist_ok=True)
    fig.savefig(RESULTS / "tearing_accuracy.png", dpi=110)
    print(f"saved {RESULTS / 'tearing_accuracy.png'}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small sizes, seconds")
    ap.add_argument("--only", choices=("table", "split", "accuracy"))
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} (1 min) on {os.cpu_count()} cores")
    for name, fn in (("table", table), ("split", split), ("accuracy", accuracy)):
        if args.only in (None, name):
            fn(args.quick)


if __name__ == "__main__":
    main()
