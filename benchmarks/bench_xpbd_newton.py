"""Side by side: our XPBD particle contacts vs Newton's SolverXPBD on CPU (issue 6).

N spheres of radius 1 cm in an open box, 10 substeps per 1/60 s frame, 1 iteration, gravity, contact + friction, box
walls. Both start from the same jittered grid (1 mm gaps), run ``settle`` frames so the pile forms (60 frames: the
50k lattice, 2 m tall, stands on the floor and closes its 1 mm gaps; a free fall of 95 mm takes 0.14 s), then take
turns, three rounds of 10 frames each, ours then Newton's (noise on this shared machine falls on both): substeps per
second, median and range. Also reported per side: the pile top, the packing fraction below 80 % of the
95th-percentile height (random packing ≈ 0.60–0.64) and, for ours, the max penetration / r.
Newton's CPU path runs on one thread; ``--threads 1`` compares at equal thread count. ``--clock cpu``
rates each side by the process's CPU seconds instead of the wall clock: at one thread each that is
the work itself, which other processes on a shared, loaded machine do not inflate (wall time then
mostly measures their share of the cores).
``--equal-piles`` (issue 49) compares piles, not substeps: each side at the cheapest substeps × iterations at which
its 10k pile converges (packing at 1.5 s within ``CONVERGED`` of the pile at 4× the substeps) and rests (mean speed
below ``REST_SPEED``; where none rests, the cheapest that converges below ``CALM``), ``EQUAL_PILES`` or, with
``--search``, searched over ``CANDIDATES``; per side the packing, the rest speed and CPU s per simulated second. At
10 × 1 Newton's pile boils (Jacobi contact sums overshoot), ours stands in the lattice's columns (no particle rotates,
static friction holds a 2° tilt): docs/performance.md. ``--pile SIDE SUBSTEPS ITERATIONS`` traces one side's packing,
speed and drift every 20 frames.
Run: python benchmarks/bench_xpbd_newton.py [--quick] [--sizes 10000 50000] [--threads N] [--clock cpu]
     [--equal-piles [--search] [--newton SUBSTEPS ITERATIONS] [--frames F]] [--pile SIDE SUBSTEPS ITERATIONS [--mu μ]]
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import sys
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

from machine import conditions

ROOT = Path(__file__).resolve().parents[1]
# packages this benchmark needs beyond the project's own (tests/benchmarks skips it without them)
REQUIRES = ("newton", "warp")
RESULTS = Path(os.environ.get("NODEGRAPH_BENCH_RESULTS") or ROOT / "benchmarks" / "results")


SUBSTEPS, RADIUS, SIDE = 10, 0.01, 0.5  # m
MU = {"friction": 0.5}  # both sides' friction coefficient (Newton's example); --mu changes it


def initial_grid(n, seed=0):
    """Jittered grid in a square column of side ``side`` = SIDE (m), spacing 2.1 r."""
    side = SIDE
    spacing = 2.1 * RADIUS
    per_row = int(side / spacing)
    k = np.arange(n)
    grid = np.stack([k % per_row, (k // per_row) % per_row, k // per_row**2], 1) * spacing + RADIUS * 1.05
    rng = np.random.default_rng(seed)
    return grid + rng.uniform(-0.0004, 0.0004, grid.shape), side


def box_solver(n, dispatch=None, threads=None, substeps=SUBSTEPS, iterations=1):
    """Our solver on the jittered grid in the open box (mm, g, s), ready to run: a ``SolverRun`` (``scenes``)."""
    from scene_builders import open_box, solver_run

    from nodes.simulation.collider import signed_distance_grid
    from nodes.simulation.settings import solver_settings_for

    x, side = initial_grid(n)
    x_mm, r_mm, side_mm = x * 1000, RADIUS * 1000, side * 1000
    height = x_mm[:, 2].max() + 2 * r_mm
    sdf = signed_distance_grid(
        open_box(side_mm, wall=20.0, height=height),
        np.array([-20.0, -20, -20]),
        np.array([side_mm + 20, side_mm + 20, height]),
        r_mm / 2,
    )
    # Newton's example: μ 0.5 for both; as measured: no sleeping, β = 0
    settings = solver_settings_for(
        frozenset({"gravity", "contact", "friction", "collider"}),
        r_mm,
        substeps=substeps,
        iterations=iterations,
        static_threshold=MU["friction"],
        dynamic_scale=1.0,
        sleep_speed=0.0,
        linear_deformation=0.0,
    )
    return solver_run(
        x_mm,
        np.full(n, r_mm),
        np.full(n, 1.0),
        np.arange(n + 1),
        np.zeros((n, 3)),
        np.tile([1.0, 0, 0, 0], (n, 1)),
        settings,
        dispatch=dispatch,
        threads=threads,
        sdf=sdf,
    )


def ours_scene(n, threads=None, substeps=SUBSTEPS, iterations=1):
    """(frame, positions in m, notes) of our solver on the box scene at ``substeps`` × ``iterations``."""
    s = box_solver(n, threads=threads, substeps=substeps, iterations=iterations)
    return (
        s.frame,
        lambda: s.state.x / 1000,
        lambda: {"penetration": s.solver.diagnostics.penetration[-1], "threads": s.solver.threads},
    )


def packing(x, side):
    """Volume fraction of spheres below 80 % of the 95th-percentile height, in a box of side ``side``."""
    cut = 0.8 * np.percentile(x[:, 2], 95)
    return float((x[:, 2] < cut).sum() * 4 / 3 * np.pi * RADIUS**3 / (side**2 * cut))


def newton_scene(n, threads=None, substeps=SUBSTEPS, iterations=1):
    """(frame, positions in m, notes) of Newton's SolverXPBD on the same scene (CPU, one thread: ``threads``
    is ours only) at ``substeps`` × ``iterations``."""
    import newton
    import warp as wp

    wp.config.quiet = True
    x, side = initial_grid(n)
    builder = newton.ModelBuilder()
    builder.add_ground_plane()
    h = float(x[:, 2].max() + 2 * RADIUS)
    wall = 0.02
    for cx, cy, hx, hy in (
        (-wall, side / 2, wall, side / 2 + wall),
        (side + wall, side / 2, wall, side / 2 + wall),
        (side / 2, -wall, side / 2, wall),
        (side / 2, side + wall, side / 2, wall),
    ):
        builder.add_shape_box(
            body=-1, xform=wp.transform(wp.vec3(cx, cy, h / 2), wp.quat_identity()), hx=hx, hy=hy, hz=h / 2
        )
    for p in x:
        builder.add_particle(wp.vec3(*p), wp.vec3(0.0, 0.0, 0.0), mass=0.004, radius=RADIUS)
    model = builder.finalize(device="cpu")
    model.particle_mu = MU["friction"]
    model.soft_contact_mu = MU["friction"]
    solver = newton.solvers.SolverXPBD(model, iterations=iterations)
    state_0, state_1 = model.state(), model.state()
    control = model.control()
    pipeline = newton.CollisionPipeline(model)
    contacts = pipeline.contacts()
    dt = 1.0 / 60 / substeps

    def frame():
        nonlocal state_0, state_1
        for _ in range(substeps):
            state_0.clear_forces()
            pipeline.collide(state_0, contacts)
            solver.step(state_0, state_1, control, contacts, dt)
            state_0, state_1 = state_1, state_0

    return frame, lambda: state_0.particle_q.numpy(), lambda: {}


def side_by_side(n, settle, timed, rounds, threads=None, clock=time.perf_counter):
    """Both scenes settle ``settle`` frames, then take turns: ``rounds`` blocks of ``timed`` frames
    each, ours then Newton's, so machine noise falls on both; substeps per second of ``clock`` per block."""
    import warp as wp

    scenes = {"ours": ours_scene(n, threads), "newton": newton_scene(n)}
    for frame, _, _ in scenes.values():
        for _ in range(settle):
            frame()
    rates = {name: [] for name in scenes}
    for _ in range(rounds):
        for name, (frame, _, _) in scenes.items():
            t = clock()
            for _ in range(timed):
                frame()
            wp.synchronize()
            rates[name].append(timed * SUBSTEPS / (clock() - t))
    return {name: (rates[name], positions(), notes()) for name, (_, positions, notes) in scenes.items()}


# -- equal piles (issue 49): each side at the cheapest settings at which its pile converges and rests ----------
PILE_FRAMES = 90  # 1.5 s (ours rests by 0.67 s at 50k); packing and rest are read at the last frame
REST_SPEED = 1e-3  # m/s: a pile rests when its particles' mean speed over the last frame is below this (0.1 r/s)
CONVERGED = 0.01  # a pile's packing within this of the same side's pile at 4× the substeps
CALM = 1e-2  # m/s (1 r/s): where no setting rests, the cheapest that converges below this speed (not boiling)
# the substeps × iterations each side runs with in --equal-piles (its tries: benchmarks/measured/xpbd_newton.jsonl):
# ours, the cheapest of CANDIDATES, rests from the 10th frame at 0.443 at 10 × 1, 40 × 1 and 10 × 4; Newton's pile
# rests at none up to 160 × 4 (its columns creep over), and 80 × 4 is the cheapest whose packing at 1.5 s converges,
# 0.444 against 0.443 at 160 × 4 (its 4× reference, 320 × 4, not run: ≈ 500 CPU s) and ours'
EQUAL_PILES = {"ours": (10, 1), "newton": (80, 4)}
CANDIDATES = ((10, 1), (10, 2), (20, 1), (10, 4), (20, 2), (40, 1), (20, 4), (40, 2), (40, 4), (80, 4), (160, 4))
BLOCK = 10  # frames per turn: the sides take turns, so the machine's noise falls on both


def scene(side, n, settings, threads=None):
    """(frame, positions, notes) of ``side`` ("ours" or "newton") at ``settings`` = (substeps, iterations)."""
    make = ours_scene if side == "ours" else newton_scene
    return make(n, threads, *settings)


def piles(n, settings, frames=PILE_FRAMES, threads=None, clock=time.process_time):
    """Each side of ``settings`` (side: (substeps, iterations)) runs ``frames`` frames from the start, the sides
    taking turns ``BLOCK`` frames at a time; per side (packing, mean speed over the last frame in m/s, ``clock``
    seconds per simulated second after the first block: it loads the kernels and builds the first lists, a
    once-per-process cost that at 50k made ours' first 10 frames cost 2.8× its rate)."""
    import warp as wp

    scenes = {side: scene(side, n, s, threads) for side, s in settings.items()}
    spent = dict.fromkeys(scenes, 0.0)
    last = {}
    warm = BLOCK if frames > BLOCK else 0  # frames left out of the cost
    for done in range(0, frames, BLOCK):
        for side, (frame, positions, _) in scenes.items():
            t = clock()
            for f in range(done, min(done + BLOCK, frames)):
                if f == frames - 1:
                    last[side] = positions().copy()
                frame()
            wp.synchronize()
            if done >= warm:
                spent[side] += clock() - t
    out = {}
    for side, (_, positions, _) in scenes.items():
        x = positions()
        speed = float(np.linalg.norm(x - last[side], axis=1).mean() * 60)
        out[side] = (packing(x, SIDE), speed, spent[side] / ((frames - warm) / 60))
    return out


def search(side, n, threads=None, clock=time.process_time):
    """The cheapest ``CANDIDATES`` (by substeps × iterations) at which ``side``'s pile converges (its packing within
    ``CONVERGED`` of the pile at 4× the substeps) and rests, or, where none rests, the cheapest that converges and
    moves slower than ``CALM`` (a boiling pile's packing can match its finer run's by chance); with whether it
    rests. Prints every try."""
    tried = {}

    def run(settings):
        if settings not in tried:
            tried[settings] = piles(n, {side: settings}, threads=threads, clock=clock)[side]
            fit, speed, cost = tried[settings]
            print(f"{side} {n} {settings[0]}×{settings[1]}: packing {fit:.3f}, {speed:.4f} m/s, {cost:.1f} s per s")
        return tried[settings]

    fallback = None
    for substeps, iterations in sorted(CANDIDATES, key=lambda c: c[0] * c[1]):
        fit, speed, _ = run((substeps, iterations))
        finer, finer_speed, _ = run((4 * substeps, iterations))
        if abs(fit - finer) > CONVERGED:
            continue
        if speed < REST_SPEED and finer_speed < REST_SPEED:
            return (substeps, iterations), True
        if speed < CALM:
            fallback = fallback or (substeps, iterations)
    return fallback, False


def trace(side, n, settings, frames, threads=None, every=20):
    """--pile: one side's pile every ``every`` frames: packing, mean speed over the frame (m/s), the median
    horizontal drift from the start (mm: the lattice's columns hold while it stays ≪ the 1 mm gaps), CPU s."""
    frame, positions, _ = scene(side, n, settings, threads)
    x0 = positions().copy()
    start = time.process_time()
    for f in range(1, frames + 1):
        before = positions().copy() if f % every == 0 else None
        frame()
        if before is not None:
            x = positions()
            speed = np.linalg.norm(x - before, axis=1).mean() * 60
            drift = np.median(np.linalg.norm(x[:, :2] - x0[:, :2], axis=1)) * 1000
            print(
                f"{side} {n} {settings[0]}×{settings[1]} frame {f}: packing {packing(x, SIDE):.3f}, "
                f"{speed * 1000:.2f} mm/s, drift {drift:.2f} mm, {time.process_time() - start:.1f} CPU s",
                flush=True,
            )


def equal_piles_table(rows, clock_unit):
    """The --equal-piles table: per size, each side's settings, packing, rest speed and cost, and the ratio."""
    lines = [
        "| particles | substeps × iterations, ours / Newton | packing ours / Newton "
        f"| mean speed at the end, ours / Newton (mm/s) | {clock_unit} per simulated s, ours / Newton | ratio |",
        "|---|---|---|---|---|---|",
    ]
    for n, settings, result in rows:
        (pa, va, ca), (pb, vb, cb) = result["ours"], result["newton"]
        a, b = ("×".join(map(str, settings[side])) for side in ("ours", "newton"))
        lines.append(
            f"| {n} | {a} / {b} | {pa:.3f} / {pb:.3f} | {va * 1000:.2f} / {vb * 1000:.2f} "
            f"| {ca:.2f} / {cb:.2f} | **{cb / ca:.1f}×** |"
        )
    return "\n".join(lines)


def equal_piles(args, clock):
    """--equal-piles: both sides at ``EQUAL_PILES`` (or, with --search, at the settings found at the first size)."""
    sizes = [2000] if args.quick else args.sizes
    frames = 6 if args.quick else args.frames or PILE_FRAMES
    settings = dict(EQUAL_PILES)
    if args.newton:
        settings["newton"] = tuple(args.newton)
    if args.search:
        for side in settings:
            found, rests = search(side, sizes[0], args.threads, clock)
            if found is None:
                print(f"{side}: no candidate converges at {sizes[0]} particles")
                return
            if not rests:
                print(f"{side}: no candidate rests at {sizes[0]} particles; the cheapest that converges: {found}")
            settings[side] = found
    start = conditions()
    rows = []
    for n in sizes:
        rows.append((n, settings, piles(n, settings, frames, args.threads, clock)))
        print(rows[-1], flush=True)
    unit = "CPU s" if args.clock == "cpu" else "s"
    table = equal_piles_table(rows, unit) + f"\n\nat the start: {start}\nat the end: {conditions()}"
    print(table)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"bench_xpbd_newton_equal_piles{'_quick' if args.quick else ''}.md").write_text(table + "\n")


def require_peer() -> None:
    """Stop with what to install, not a traceback, where the optional peer simulator is missing."""
    missing = [name for name in REQUIRES if importlib.util.find_spec(name) is None]
    if missing:
        print(
            f"bench_xpbd_newton: the peer simulator is not installed (missing: {', '.join(missing)}).\n"
            'Install the optional extra from the repository root: pip install -e ".[peer]"',
            file=sys.stderr,
        )
        sys.exit(2)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10000, 50000])
    ap.add_argument("--threads", type=int, help="our kernels' threads (default: the cores other processes leave free)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall", help="cpu: substeps per CPU second")
    ap.add_argument("--equal-piles", action="store_true", help="each side at the settings where its pile converges")
    ap.add_argument("--search", action="store_true", help="with --equal-piles: search those settings first")
    ap.add_argument("--newton", type=int, nargs=2, metavar=("SUBSTEPS", "ITERATIONS"), help="Newton's, --equal-piles")
    ap.add_argument("--pile", nargs=3, metavar=("SIDE", "SUBSTEPS", "ITERATIONS"), help="trace one side's pile")
    ap.add_argument("--frames", type=int, help=f"frames to run: --pile 120, --equal-piles {PILE_FRAMES}")
    ap.add_argument("--mu", type=float, default=MU["friction"], help="with --pile: friction coefficient, both sides")
    args = ap.parse_args()
    require_peer()
    MU["friction"] = args.mu
    clock = time.process_time if args.clock == "cpu" else time.perf_counter
    if args.pile:
        side, substeps, iterations = args.pile
        trace(side, args.sizes[0], (int(substeps), int(iterations)), args.frames or 120, args.threads)
        return
    if args.equal_piles:
        equal_piles(args, clock)
        return
    settle, timed, rounds = (3, 3, 2) if args.quick else (60, 10, 3)
    sizes = [2000] if args.quick else args.sizes
    rows = []
    start = conditions()
    for n in sizes:
        result = side_by_side(n, settle, timed, rounds, args.threads, clock)
        (ours, x_ours, notes), (peer, x_peer, _) = result["ours"], result["newton"]
        a, b = float(np.median(ours)), float(np.median(peer))
        rows.append(
            (
                n,
                a,
                min(ours),
                max(ours),
                b,
                min(peer),
                max(peer),
                a / b,
                float(x_ours[:, 2].max()),
                float(x_peer[:, 2].max()),
                packing(x_ours, SIDE),
                packing(x_peer, SIDE),
                notes["penetration"],
                notes["threads"],
            )
        )
        print(rows[-1], flush=True)
    unit = "CPU s" if args.clock == "cpu" else "s"
    lines = [
        f"| N | ours substeps/{unit} (median of {rounds}; min–max) | Newton SolverXPBD CPU substeps/{unit} "
        "| ratio of medians "
        "| pile top ours / Newton (m) | packing ours / Newton | our max penetration / r | our threads |",
        "|---|---|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {n} | {a:.1f} ({a0:.1f}–{a1:.1f}) | {b:.1f} ({b0:.1f}–{b1:.1f}) | **{c:.2f}** | {d:.3f} / {e:.3f} "
        f"| {f:.3f} / {g:.3f} | {h:.3f} | {k} |"
        for n, a, a0, a1, b, b0, b1, c, d, e, f, g, h, k in rows
    ]
    table = "\n".join(lines) + f"\n\nat the start: {start}\nat the end: {conditions()}"
    print(table)
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / f"bench_xpbd_newton{'_quick' if args.quick else ''}.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
