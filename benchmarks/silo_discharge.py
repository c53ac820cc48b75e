"""Silo discharge against Beverloo's law (Beverloo, Leniger & van de Velde 1961, Chem. Eng. Sci. 15:260):
W = C ρ_b √g (D − k d)^{5/2}, C ≈ 0.55–0.65, k ≈ 1.3–2.9.

A flat-bottomed cylindrical silo (inner diameter ``--silo`` mm, a tube for the wall, a floor slab with a round
hole of diameter D, both watertight manifold3d solids) is filled with rice grains (``rice_library``: ellipsoids
≈ 5 × 3 × 2.5 mm, 8 particles, 25 mg) on a jittered grid, which settle with the hole closed (a floor without a
hole); the settled state then continues in a simulation whose floor has the hole (same particles, same solver
settings). Discharged grains land on a catch slab well below (keeps the neighbour grid bounded). The rate is
the slope of the count of grains whose centre lies below the floor, over the steady window: from the time 10 %
of the grains have left to the time 50 % have (or the end of the run), fitted by least squares; the rate over
the window's first and second half compares fill heights. Solver: the xpbd node's defaults, only frames,
substeps and logging set.

    PYTHONPATH=.:benchmarks .venv/bin/python benchmarks/silo_discharge.py  # 7,000 grains, 60 mm: D 16–25 @10, 19 @40
    PYTHONPATH=.:benchmarks .venv/bin/python benchmarks/silo_discharge.py --quick  # smaller set
"""

import argparse
import copy
import datetime
import functools
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "benchmarks" / "measured" / "silo_discharge.jsonl"
EFFECTS = frozenset({"gravity", "contact", "friction", "collider", "damping"})
G = 9810.0  # mm/s²
FLOOR = 3.0  # mm, floor thickness: its top face at z = 0
CATCH = 60.0  # mm below the floor's bottom: the catch slab's top
WINDOW = (0.10, 0.50)  # steady window, as fractions of the grains discharged


def silo(radius, height, hole, wall=3.0, segments=96):
    """(closed colliders, open colliders): tube wall, floor slab (with a round hole of diameter ``hole``), catch
    slab."""
    import manifold3d as mf
    from scene_builders import box_mesh, manifold_mesh

    tube = mf.Manifold.cylinder(height, radius + wall, radius + wall, segments) - mf.Manifold.cylinder(
        height, radius, radius, segments
    )
    half = radius + wall
    slab = mf.Manifold.cube((2 * half, 2 * half, FLOOR)).translate((-half, -half, -FLOOR))
    cut = mf.Manifold.cylinder(3 * FLOOR, hole / 2, hole / 2, segments).translate((0, 0, -2 * FLOOR))
    side = 2.0 * radius
    catch = box_mesh([-side, -side, -FLOOR - CATCH - 4.0], [side, side, -FLOOR - CATCH], "catch")
    closed = [manifold_mesh(tube, "wall"), manifold_mesh(slab, "floor"), catch]
    opened = [manifold_mesh(tube, "wall"), manifold_mesh(slab - cut, "floor_hole"), catch]
    return closed, opened


def fill(n, radius, seed, long=5.8, across=3.6, layer=3.1, jitter=0.15):
    """n grain centres on a jittered grid inside the silo (lowest first): each layer's grains lie along x (even
    layers) or y (odd), spaced ``long`` along and ``across`` across their axis, yaw ±0.1 rad, tilt ±0.05 rad."""
    from scipy.spatial.transform import Rotation

    from nodes.values import Placement

    rng = np.random.default_rng(seed)
    inner = radius - 3.2
    xs, yaw = [], []
    k = 0
    while sum(len(a) for a in xs) < n:
        a, b = (long, across) if k % 2 == 0 else (across, long)
        gx, gy = np.meshgrid(np.arange(-inner, inner + 1e-9, a), np.arange(-inner, inner + 1e-9, b), indexing="ij")
        g = np.c_[gx.ravel(), gy.ravel(), np.full(gx.size, 2.0 + k * layer)]
        # the grain's far end (half its length ≈ 2.75 mm along its axis) inside the tube
        ends = np.hypot(np.abs(g[:, 0]) + (2.75 if k % 2 == 0 else 0), np.abs(g[:, 1]) + (0 if k % 2 == 0 else 2.75))
        g = g[ends < radius - 0.6]
        xs.append(g)
        yaw.append(np.full(len(g), 0.0 if k % 2 == 0 else np.pi / 2))
        k += 1
    x, yaw = np.concatenate(xs)[:n], np.concatenate(yaw)[:n]
    x = x + rng.uniform(-jitter, jitter, x.shape)
    angles = np.c_[yaw + rng.uniform(-0.1, 0.1, n), rng.uniform(-0.05, 0.05, (n, 2))]
    return Placement(
        x,
        np.tile([0, 0, 1.0], (n, 1)),
        Rotation.from_euler("zyx", angles).as_matrix(),
        variants=rng.integers(0, 4, n).astype(np.int32),
        kind_names=("japonica",),
    )


def grain_d(seed):
    """Equivalent-sphere diameter (mm) of the library's grains, mean over its variants."""
    import trimesh
    from scene_builders import rice_library

    vols = [trimesh.Trimesh(m.vertices, m.faces).volume for m in rice_library(seed=seed).meshes]
    return float(np.mean([(6 * v / np.pi) ** (1 / 3) for v in vols]))


def bulk_density(centres, radius, mass_g, d):
    """ρ_b (g/mm³) from the grains in the settled bed's core: r < R − d, d < z < H − 2d, H the 95th percentile of z."""
    c = centres
    top = np.percentile(c[:, 2], 95)
    lo, hi, rr = d, top - 2 * d, radius - d
    inside = (np.hypot(c[:, 0], c[:, 1]) < rr) & (c[:, 2] > lo) & (c[:, 2] < hi)
    vol = np.pi * rr**2 * max(hi - lo, 1e-9)
    return inside.sum() * mass_g / vol, float(top)


def slope(t, y):
    if len(t) < 3:
        return float("nan")
    return float(np.polyfit(t, y, 1)[0])


def params_for(frames, substeps, damping=None):
    """The xpbd node's defaults with only frames, substeps and logging set (and the damping, where given)."""
    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.xpbd import xpbd

    return XpbdParams(
        **xpbd.resolve_params(
            {"frames": frames, "substeps": substeps, "log_every": 0, "log_meshes_every": 0}
            | ({} if damping is None else {"damping": damping})
        )
    )


@functools.cache
def settled(substeps, grains, radius, settle, frames, seed, d, damping=None):
    """The bed settled with the hole closed, once per solver setting and fill (every hole discharges the same bed):
    (its checkpoint, placement's aggregate, height, bulk density g/mm³, fill top, 95th-percentile speed, grains
    escaped while settling, settle seconds)."""
    from scene_builders import rice_library

    from nodes.simulation.setup import build_simulation
    from nodes.values import Aggregate

    clock = time.perf_counter()
    placement = fill(grains, radius, seed)
    height = float(placement.positions[:, 2].max()) + 8.0
    closed, _ = silo(radius, height, 1.0)
    params = params_for(frames, substeps, damping)
    aggregate = Aggregate(placement, (rice_library(seed=seed),))
    sim_closed = build_simulation(aggregate, closed, EFFECTS, params)
    for _ in range(settle):
        sim_closed.frame()
    c0 = sim_closed.model.centres(sim_closed.state.x)
    rho_b, top = bulk_density(c0, radius, params.mass * 1e-3, d)
    v_settle = float(np.percentile(np.linalg.norm(sim_closed.state.v[: sim_closed.model.n_moving], axis=1), 95))
    escaped = int((c0[:, 2] < -FLOOR).sum() + (np.hypot(c0[:, 0], c0[:, 1]) > radius + 0.5).sum())
    progress = sim_closed.progress(settle)
    return progress, aggregate, height, rho_b, top, v_settle, escaped, time.perf_counter() - clock


def run(D, substeps, grains, radius=25.0, settle=60, max_seconds=6.0, seed=0, d=3.3, damping=None):
    from nodes.simulation.setup import build_simulation

    wall_clock = time.perf_counter()
    frames = settle + int(max_seconds * 60)
    progress, aggregate, height, rho_b, top, v_settle, escaped_settle, settle_s = settled(
        substeps, grains, radius, settle, frames, seed, d, damping
    )
    _, opened = silo(radius, height, D)
    params = params_for(frames, substeps, damping)
    sim_open = build_simulation(aggregate, opened, EFFECTS, params)
    dt, mass_g = params.dt, params.mass * 1e-3
    sim_open.resume(copy.deepcopy(progress))  # the settled bed stays as it was for the next hole
    t, count, vmax, outside_wall = [0.0], [0], [], 0
    f = 0
    while f < int(max_seconds * 60):
        sim_open.frame()
        f += 1
        c = sim_open.model.centres(sim_open.state.x)
        below = c[:, 2] < -FLOOR
        above = ~below
        # grains above the floor outside the tube's inner radius have passed through the wall
        outside_wall = max(outside_wall, int((above & (np.hypot(c[:, 0], c[:, 1]) > radius + 1.0)).sum()))
        t.append(f * dt)
        count.append(int(below.sum()))
        n_moving = sim_open.model.n_moving
        vmax.append(float(np.linalg.norm(sim_open.state.v[:n_moving], axis=1).max()))
        if count[-1] >= (WINDOW[1] + 0.05) * grains:
            break
    t, count = np.array(t), np.array(count)
    lo_n, hi_n = WINDOW[0] * grains, WINDOW[1] * grains
    i0 = int(np.argmax(count >= lo_n)) if (count >= lo_n).any() else len(t)
    i1 = int(np.argmax(count >= hi_n)) if (count >= hi_n).any() else len(t) - 1
    sel = slice(i0, i1 + 1)
    rate = slope(t[sel], count[sel])
    mid = (i0 + i1) // 2
    first, second = slope(t[i0 : mid + 1], count[i0 : mid + 1]), slope(t[mid : i1 + 1], count[mid : i1 + 1])
    # settled fill height (H) of the grains still in the silo at the window's start and end
    return dict(
        what="silo_discharge",
        D_mm=D,
        substeps=substeps,
        damping=params.damping,
        grains=grains,
        silo_diameter_mm=2 * radius,
        d_mm=round(d, 3),
        rho_b_g_per_cm3=round(rho_b * 1000, 4),
        fill_height_mm=round(top, 1),
        rate_grains_per_s=round(rate, 1),
        rate_g_per_s=round(rate * mass_g, 3),
        window_s=[round(float(t[min(i0, len(t) - 1)]), 3), round(float(t[i1]), 3)],
        first_half=round(first, 1),
        second_half=round(second, 1),
        discharged=int(count[-1]),
        simulated_s=round(float(t[-1]), 3),
        jam=bool(count[-1] < hi_n),
        escaped_through_wall=outside_wall,
        escaped_at_settle=escaped_settle,
        v95_at_settle_mm_per_s=round(v_settle, 1),
        vmax_mm_per_s=round(float(np.max(vmax)), 1),
        count_every_0p1s=[int(x) for x in count[::6]],
        seconds_wall=round(time.perf_counter() - wall_clock, 1),
        settle_seconds_wall=round(settle_s, 1),
    )


def fit(rows, d):
    """n with k = 1.5 and with k = 0 (log-log least squares), C at n = 2.5, k = 1.5 (mean), and k at n = 2.5
    (W^{2/5} linear in D, Beverloo's own plot: intercept = k d)."""
    D = np.array([r["D_mm"] for r in rows], float)
    W = np.array([r["rate_g_per_s"] for r in rows], float)
    rho = np.mean([r["rho_b_g_per_cm3"] for r in rows]) / 1000.0  # g/mm³
    out = {"D_mm": [float(x) for x in D], "rho_b_g_per_cm3": round(rho * 1000, 4), "d_mm": round(d, 3)}
    ok = W > 0
    D, W = D[ok], W[ok]
    if len(D) >= 2:
        out["n_k1.5"] = round(float(np.polyfit(np.log(D - 1.5 * d), np.log(W), 1)[0]), 3)
        out["n_k0"] = round(float(np.polyfit(np.log(D), np.log(W), 1)[0]), 3)
        a, b = np.polyfit(D, W**0.4, 1)
        out["k_n2.5"] = round(float(-b / a / d), 3)
        out["C_n2.5_kfit"] = round(float(a**2.5 / (rho * np.sqrt(G))), 3)
    C = W / (rho * np.sqrt(G) * (D - 1.5 * d) ** 2.5)
    out["C_n2.5_k1.5"] = round(float(C.mean()), 3)
    out["C_each_k1.5"] = [round(float(c), 3) for c in C]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="D 16, 22 at 10 substeps, 1,500 grains")
    ap.add_argument("--grains", type=int, default=7000)
    ap.add_argument("--silo", type=float, default=60.0, help="inner diameter, mm")
    ap.add_argument("--D", type=float, nargs="*", help="hole diameters (mm) at 10 substeps")
    ap.add_argument("--fine", type=float, nargs="*", help="(D, substeps) pairs run besides, e.g. 18 20")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument(
        "--damping", type=float, help="velocity fraction removed per 1/60 s (the node's default if not given)"
    )
    ap.add_argument("--no-write", action="store_true")
    ap.add_argument(
        "--out", type=Path, default=OUT, help="the data file: rows of the same set-up and setting are replaced"
    )
    args = ap.parse_args()
    if args.quick:
        plan, grains = [(16.0, 10), (22.0, 10)], min(args.grains, 1500)
    else:
        plan, grains = [(D, 10) for D in (args.D if args.D is not None else [16.0, 19.0, 22.0, 25.0])], args.grains
        fine = args.fine if args.fine is not None else [19.0, 40]
        plan += [(float(fine[i]), int(fine[i + 1])) for i in range(0, len(fine) - 1, 2)]
    d = grain_d(args.seed)
    command = " ".join(["python", "benchmarks/silo_discharge.py", *sys.argv[1:]])
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    stamp = {"load": f"{os.getloadavg()[0]:.1f}", "machine": f"{os.cpu_count()} cores"}
    rows = []
    hdr = (
        f"{'D mm':>5} {'sub':>4} {'grains':>6} {'grains/s':>9} {'g/s':>7} {'window s':>13} {'1st/2nd half':>15} "
        f"{'ρb':>6} {'H mm':>5} {'vmax':>6} {'esc':>4} {'wall s':>6}"
    )
    print(f"grain d (equivalent sphere) = {d:.3f} mm; silo {args.silo:.0f} mm; window {WINDOW} of grains out")
    print(hdr, flush=True)
    for D, sub in plan:
        r = run(D, sub, grains, radius=args.silo / 2, seed=args.seed, d=d, damping=args.damping)
        r.update(values={"rate": r["rate_grains_per_s"]}, unit="grains/s", command=command, date=date, **stamp)
        rows.append(r)
        print(
            f"{D:5.1f} {sub:4d} {grains:6d} {r['rate_grains_per_s']:9.1f} {r['rate_g_per_s']:7.2f} "
            f"{r['window_s'][0]:6.2f}-{r['window_s'][1]:<6.2f} {r['first_half']:7.1f}/{r['second_half']:<7.1f} "
            f"{r['rho_b_g_per_cm3']:6.3f} {r['fill_height_mm']:5.1f} {r['vmax_mm_per_s']:6.0f} "
            f"{r['escaped_through_wall']:4d} {r['seconds_wall']:6.1f}" + ("  JAM/unfinished" if r["jam"] else ""),
            flush=True,
        )
    base = [r for r in rows if r["substeps"] == 10 and not r["jam"]]
    if len(base) >= 2:
        fitted = fit(base, d)
        values = {"n_k1.5": fitted["n_k1.5"], "C_n2.5_k1.5": fitted["C_n2.5_k1.5"]}
        rows.append(
            {"what": "silo_discharge_fit", **fitted, "values": values, "unit": "1", "command": command, "date": date}
            | stamp
        )
        print("fit (10 substeps):", json.dumps(fitted))
        print("Beverloo et al. 1961: n = 2.5, C ≈ 0.55–0.65, k ≈ 1.3–2.9")
    if not args.no_write:
        write(args.out, rows)


def key(row: dict) -> tuple:
    """What a row measured: the set-up and setting (a fit row: which holes)."""
    if row["what"] == "silo_discharge_fit":
        return ("fit",)
    return tuple(row.get(k) for k in ("silo_diameter_mm", "grains", "D_mm", "substeps", "damping"))


def write(path: Path, rows: list[dict]) -> None:
    """Rows into the data file, replacing those that measured the same set-up and setting, keeping the rest."""
    new = {key(r) for r in rows}
    old = [json.loads(line) for line in path.read_text().splitlines()] if path.exists() else []
    kept = [r for r in old if key(r) not in new]
    path.write_text("".join(json.dumps(r) + "\n" for r in kept + rows))


if __name__ == "__main__":
    main()
