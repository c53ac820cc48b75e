"""The held-out granular cases at the xpbd node's defaults and at 4× its substeps (issue 46): a rice grain on
an inclined plane, and rice heaps, dry and sticky, dropped as a ball and poured as a stream (and the stream with
the speed clamp at 1, the old default, under which a fall is braked to 1 r per substep), read at 2.5 s and 7 s.
Each case writes one line to benchmarks/measured/physics_defaults.jsonl; ``python tools/measured_tables.py``
renders the table in docs/validation.md.

    python benchmarks/physics_at_defaults.py            # every case (≈ 6 min on 2 cores)
    python benchmarks/physics_at_defaults.py --quick    # the inclined planes only (≈ 1 min), prints, writes nothing
    python benchmarks/physics_at_defaults.py --convergence   # the substep curve (docs/accuracy.md), ≈ 8 min
    python benchmarks/physics_at_defaults.py --funnel        # the fixed-funnel heap at 5–80 substeps, ≈ 5 min
    python benchmarks/physics_at_defaults.py --passes        # substeps against iterations; the stream's landing
    python benchmarks/physics_at_defaults.py --levers        # what each solver setting does to the heaps, ≈ 12 min
    python benchmarks/physics_at_defaults.py --mechanism     # what shapes a dropped heap: the contacts, ≈ 15 min
    python benchmarks/physics_at_defaults.py --creep         # how far the dropped ball's grains move at rest, ≈ 6 min
    python benchmarks/physics_at_defaults.py --passes-overlap  # the grains' overlap after each step of a pass, ≈ 3 min

``--convergence`` runs the poured heap (two seeds) and the grain sliding across its length at 5–80 substeps and
writes benchmarks/measured/granular_convergence.jsonl, with its plot docs/images/accuracy/granular_convergence.png:
the curve the default substeps are read from.
"""

import argparse
import json
import os
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

RECORD = Path(__file__).resolve().parent / "measured" / "physics_defaults.jsonl"
CONVERGENCE = RECORD.with_name("granular_convergence.jsonl")
FUNNEL = RECORD.with_name("funnel_heap.jsonl")
PASSES_RECORD = RECORD.with_name("solver_passes.jsonl")
LEVERS = RECORD.with_name("heap_levers.jsonl")
MECHANISM = RECORD.with_name("heap_mechanism.jsonl")
CREEP = RECORD.with_name("heap_creep.jsonl")
CREEP_MM = 0.2  # mm: a grain that moves further between 2.5 s and 7 s creeps (issue 46's reading)
PASS_OVERLAP = RECORD.with_name("pass_overlap.jsonl")
# the solver's kernels after which ``pass_overlap`` sums the grains' overlap, and what each step is called there
PASS_STEPS = {
    "contact_sweep": "sweep",
    "predict": "predicted",
    "shape_match_project": "shape matching",
    "collider_project": "walls",
}
# (grains, seeds, frames, (substeps, iterations) ...): the dropped ball's collapse read at 0.1 s, 0.3 s and the end
COLLAPSES = (
    (300, (0, 1, 2), 45, ((10, 2), (20, 1), (10, 4), (20, 2), (40, 1), (40, 2), (80, 2), (40, 4))),
    (890, (0,), 60, ((10, 2), (10, 4), (20, 2), (40, 2), (40, 4))),
)
# (what, node parameters) changed from the defaults, one at a time: what each does to the heaps at 10 and 40 substeps
HEAP_LEVERS = (
    ("the node's defaults", {}),
    ("speed clamp 1 (the old default)", {"speed_clamp": 1.0}),
    ("no damping", {"damping": 0.0}),
    ("no mass scaling (shock propagation 1)", {"shock_propagation": 1.0}),
    ("μk = μs (dynamic scale 1)", {"dynamic_scale": 1.0}),
    ("μs 1.0", {"static_threshold": 1.0}),
)
PLOT = Path(__file__).resolve().parents[1] / "docs" / "images" / "accuracy" / "granular_convergence.png"
SUBSTEPS = (5, 10, 20, 40, 80)  # the convergence curve's points; the node's default is 20
EFFECTS = frozenset({"gravity", "contact", "friction", "collider", "damping"})
ANGLES = tuple(range(24, 45))  # degrees, the inclined plane's tilts
# (substeps, iterations): 20, 30 and 40 passes per frame, and 160 (40 × 4) as the reference
PASSES = ((10, 2), (20, 1), (10, 3), (10, 4), (20, 2), (40, 4))
MU_S = 0.6  # the node's default static_threshold: atan 0.6 = 30.96°


def grain_on_plane(
    theta: float, substeps: int, seconds: float = 1.0, on: str = "wall", across: bool = False, **params
) -> float:
    """One japonica grain (``rice_library``, 8 particles) set flat on level ground (``on`` "wall": a slab; "grains":
    ``grain_bed``) at the node's defaults, settled 0.5 s; then gravity tilted by ``theta`` (an inclined plane) for
    ``seconds``: how far (mm) its centre slid. ``across``: the grain turned 90° about the vertical, so it slides
    across its length instead of along it. ``params``: other node parameters (iterations)."""
    from scene_builders import box_mesh, rice_library

    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.setup import build_simulation
    from nodes.simulation.xpbd import xpbd
    from nodes.values import Aggregate, Placement

    placement = Placement(
        np.array([[0.0, 0.0, 1.3]]),
        np.array([[0, 0, 1.0]]),
        (np.eye(3) if not across else np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]))[None],
        variants=np.zeros(1, np.int32),
        kind_names=("japonica",),
    )
    params = XpbdParams(**xpbd.resolve_params({"substeps": substeps, "log_every": 0, "log_meshes_every": 0, **params}))
    aggregate = Aggregate(placement, (rice_library(seed=0),))
    if on == "wall":
        ground = box_mesh([-200, -200, -6], [200, 200, 0], "ground")
        sim = build_simulation(aggregate, [ground], EFFECTS, params)
    else:
        sim = build_simulation(aggregate, [], EFFECTS - {"collider"}, params, obstacles=[grain_bed()])
    for _ in range(30):
        sim.frame()
    before = sim.model.centres(sim.state.x).copy()
    t = np.radians(theta)
    sim.solver.default_control.accel[:] = [params.gravity * np.sin(t), 0.0, -params.gravity * np.cos(t)]
    for _ in range(int(round(seconds / params.dt))):
        sim.frame()
    return float(np.linalg.norm((sim.model.centres(sim.state.x) - before)[0]))


def grain_set_on_slab(theta: float, substeps: int, shift: float = 0.0, yaw: float = 0.0, seconds: float = 1.5) -> float:
    """One japonica grain set down on a slab tilted by ``theta`` under plain gravity: its lowest particle just
    touching the slab's face, ``shift`` mm along the slope and turned by ``yaw`` degrees about the face's normal (the
    slab's distance field is sampled at other points of its grid); how far (mm) its centre moved in ``seconds``,
    its landing included. Unlike ``grain_on_plane`` nothing settles first: the grain lands on a tilted wall."""
    from scene_builders import box_mesh, rice_library
    from scipy.spatial.transform import Rotation

    from nodegraph.values import Mesh
    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.setup import build_simulation
    from nodes.simulation.xpbd import xpbd
    from nodes.values import Aggregate, Placement

    tilt = Rotation.from_euler("y", theta, degrees=True).as_matrix()
    turn = tilt @ Rotation.from_euler("z", yaw, degrees=True).as_matrix()
    normal = tilt @ [0.0, 0.0, 1.0]
    slab = box_mesh([-40, -20, -4], [40, 20, 0], "slab")
    slab = Mesh(np.asarray(slab.vertices) @ tilt.T, np.asarray(slab.faces), name="slab")
    params = XpbdParams(**xpbd.resolve_params({"substeps": substeps, "log_every": 0, "log_meshes_every": 0}))
    library = rice_library(seed=0)

    def at(height):
        placement = Placement(
            (tilt @ [shift, 0.0, height])[None],
            normal[None],
            turn[None],
            variants=np.zeros(1, np.int32),
            kind_names=("japonica",),
        )
        return build_simulation(Aggregate(placement, (library,)), [slab], EFFECTS, params)

    probe = at(2.0)
    m = probe.model.n_moving
    lowest = float(np.min(probe.state.x[:m] @ normal - probe.model.r[:m]))
    sim = at(2.0 - lowest)
    before = sim.model.centres(sim.state.x).copy()
    for _ in range(int(round(seconds / params.dt))):
        sim.frame()
    return float(np.linalg.norm((sim.model.centres(sim.state.x) - before)[0]))


def slab_case(substeps: int) -> dict:
    """The largest tilt at which a grain set down on a slab (``grain_set_on_slab``) moves < 1 mm in 1.5 s at every
    one of four placements, and the smallest at which it slides at one."""
    # along the slope or turned from it: across it (90°) a japonica grain rolls from 29° (an ellipse of its 3.9 × 2.7
    # mm section rests on a slope only to atan((a² − b²)/2ab) = 21°, so rolling is no defect of friction)
    placements = ((0.0, 0.0), (0.3, 0.0), (0.6, 45.0), (0.15, 30.0))
    angles = tuple(range(24, 36))
    moved = {a: [grain_set_on_slab(a, substeps, s, y) for s, y in placements] for a in angles}
    holds = max([a for a in angles if max(moved[a]) < 1.0], default=None)
    slides = min([a for a in angles if max(moved[a]) >= 1.0], default=None)
    return {
        "case": "grain set down on a tilted slab (grain–wall, landing)",
        "setup": "one japonica grain (8 particles) set down touching a slab tilted 24–35° in 1° steps, at four "
        "placements (shifted 0–0.6 mm, turned 0–45°), μs 0.6, μk 0.42; held = moved < 1 mm in 1.5 s at all four",
        "substeps": substeps,
        "ours": f"holds to {holds}°, slides at {slides}°" if slides else f"holds at every tilt to {angles[-1]}°",
        "published": "holds below atan μs = 31.0°, slides above (Coulomb)",
        "values": {
            "holds": holds,
            "slides": slides,
            "moved_mm": {str(a): [round(v, 3) for v in moved[a]] for a in angles},
        },
    }


def grain_bed(seed: int = 0):
    """A bed of japonica grains lying flat side by side (``rice_library`` grains' particle clusters on a grid
    5.2 × 3.1 mm, touching, random yaw within ±5°) as static obstacles with their top at z = 0: a plane of grains."""
    from scene_builders import rice_library
    from scipy.spatial.transform import Rotation

    from nodes.simulation.clusters import element_cluster
    from nodes.values import ParticleState

    rng = np.random.default_rng(seed)
    clusters = [element_cluster(m, 8) for m in rice_library(seed=seed).meshes]
    xs, rs = [], []
    for gx in np.arange(-60.0, 60.0, 5.2):
        for gy in np.arange(-60.0, 60.0, 3.1):
            c = clusters[rng.integers(len(clusters))]
            turn = Rotation.from_euler("z", rng.uniform(-5, 5), degrees=True).as_matrix()
            xs.append((c.centres - c.centres.mean(axis=0)) @ turn.T + [gx, gy, 0.0])
            rs.append(c.radii)
    x, r = np.concatenate(xs), np.concatenate(rs)
    x[:, 2] -= (x[:, 2] + r).max()
    n = len(x)
    return ParticleState(x, np.zeros_like(x), r, np.zeros(n), np.zeros(n, np.int64))


def plane_case(substeps: int, on: str = "wall", across: bool = False, **params) -> dict:
    """The largest tilt at which the grain moves < 1 mm in 1 s, and the smallest at which it slides."""
    slid = {a: grain_on_plane(a, substeps, on=on, across=across, **params) for a in ANGLES}
    holds = max([a for a in ANGLES if slid[a] < 1.0], default=None)
    slides = min([a for a in ANGLES if slid[a] >= 1.0], default=None)
    plane = "a plane" if on == "wall" else "a bed of grains lying flat (static)"
    return {
        "case": f"grain on an inclined plane ({'grain–wall' if on == 'wall' else 'grain–grain'}"
        + (", sliding across its length)" if across else ")"),
        "setup": f"one japonica grain (8 particles) flat on {plane} tilted 24–44° in 1° steps, μs 0.6, μk 0.42; "
        "held = moved < 1 mm in 1 s",
        "substeps": substeps,
        "ours": f"holds to {holds}°, slides at {slides}°" if slides else f"holds at every tilt to {ANGLES[-1]}°",
        "published": "holds below atan μs = 31.0°, slides above (Coulomb)"
        + ("" if on == "wall" else "; on grains the bed's bumps add to μs"),
        "values": {"holds": holds, "slides": slides, "slid_mm": {str(a): round(slid[a], 3) for a in ANGLES}},
    }


# cooked rice: the rice recipes' effects, adhesion at the node's clumping and the moisture's factors
STICKY = frozenset({"gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping"})


def heap_case(shape: str, n: int, substeps: int, seed: int = 0, sticky: bool = False, **params) -> dict:
    """A heap at the node's defaults (but ``params``): its H/R angle at 2.5 s and 7 s (``validation.rice_heap``);
    ``sticky``: cooked rice (``STICKY``), else dry."""
    from validation import EFFECTS, rice_heap

    start = time.perf_counter()
    effects = STICKY if sticky else EFFECTS
    angles, _ = rice_heap(
        n, True, frames=(150, 420), substeps=substeps, shape=shape, seed=seed, effects=effects, **params
    )
    (s25, hr25), (s7, hr7) = angles
    how = "dropped as a ball" if shape == "ball" else "poured as a stream"
    kind = "sticky (adhesion at clumping 0.3, moisture)" if sticky else "dry (no adhesion)"
    given = "".join(f", {k} {v}" for k, v in params.items())
    return {
        "case": f"rice heap, {n} {'sticky ' if sticky else ''}grains {how}{given}",
        "setup": f"{n} ellipsoid grains 5 × 3 × 2.5 mm ±10 % (8 particles) {how} on flat ground, {kind}{given}",
        "substeps": substeps,
        "ours": f"H/R {hr25:.1f}° at 2.5 s → {hr7:.1f}° at 7 s (surface slope {s25:.1f}° → {s7:.1f}°)",
        "published": "at rest (≤ 3° change); piling angle of rough rice 29.6–36.9° (Appl. Eng. Agric., "
        "doi:10.13031/aea.13156), paddy 35.7–44.4° (Zareiforoush et al. 2009)",
        "values": {
            "hr_2_5": round(hr25, 1),
            "hr_7": round(hr7, 1),
            "surface_2_5": round(s25, 1),
            "surface_7": round(s7, 1),
            "seconds": round(time.perf_counter() - start, 1),
        },
    }


def funnel_heap(
    substeps: int, seed: int = 0, grains: int = 400, hole: float = 18.0, drop: float = 15.0, **params
) -> dict:
    """The fixed-funnel method (the funnel held at a fixed height; tan θ = H/R once the heap reaches it, as for
    powders in ISO 4324): ``grains`` japonica grains fill a silo 24 mm across (``silo_discharge.fill``) whose floor
    has a round outlet ``hole`` mm wide, ``drop`` mm above flat ground, and flow out onto it for 3 s at the node's
    defaults. A grain leaves the outlet at about √(g·D) and lands at ≤ 0.7 m/s, under the speed clamp's cap from
    10 substeps up, so unlike the stream the set-up does not depend on the clamp. Returns the heap's surface slope
    and atan H/R at 3 s, its grains, its top (mm) and the seconds. ``params``: other node parameters (iterations)."""
    import manifold3d as mf
    from scene_builders import box_mesh, manifold_mesh, rice_library
    from silo_discharge import fill
    from validation import heap_angle, mound_angle

    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.setup import build_simulation
    from nodes.simulation.xpbd import xpbd
    from nodes.values import Aggregate, Placement

    radius, wall, floor = 12.0, 3.0, 3.0
    filled = fill(grains, radius, seed)
    x = filled.positions + [0.0, 0.0, drop + floor]
    placement = Placement(x, filled.normals, filled.rotations, variants=filled.variants, kind_names=("japonica",))
    tall = float(x[:, 2].max()) + 8.0 - drop
    outer = mf.Manifold.cylinder(tall, radius + wall, radius + wall, 96)
    tube = (outer - mf.Manifold.cylinder(tall, radius, radius, 96)).translate((0, 0, drop + floor))
    base = mf.Manifold.cylinder(floor, radius + wall, radius + wall, 96)
    outlet = (base - mf.Manifold.cylinder(floor, hole / 2, hole / 2, 96)).translate((0, 0, drop))
    ground = box_mesh([-90, -90, -4], [90, 90, 0], "ground")
    params = XpbdParams(**xpbd.resolve_params({"substeps": substeps, "log_every": 0, "log_meshes_every": 0, **params}))
    aggregate = Aggregate(placement, (rice_library(seed=seed),))
    sim = build_simulation(aggregate, [manifold_mesh(tube + outlet, "funnel"), ground], EFFECTS, params)
    start = time.perf_counter()
    for _ in range(180):
        sim.frame()
    c = sim.model.centres(sim.state.x)
    heap = c[c[:, 2] < drop]
    return {
        "surface": round(heap_angle(heap), 1),
        "hr": round(mound_angle(heap), 1),
        "grains": int(len(heap)),
        "top_mm": round(float(np.percentile(heap[:, 2], 99)), 1),
        "seconds": round(time.perf_counter() - start, 1),
    }


def funnel_curve() -> list[dict]:
    """The fixed-funnel heap at each of ``SUBSTEPS``, seeds 0 and 1."""
    rows = []
    for substeps in SUBSTEPS:
        runs = [funnel_heap(substeps, seed) for seed in (0, 1)]
        values = {k: [r[k] for r in runs] for k in ("surface", "hr", "grains", "top_mm")}
        values["seconds"] = round(sum(r["seconds"] for r in runs) / 2, 1)
        rows.append({"case": "rice heap, fixed funnel", "substeps": substeps, "values": values})
        print(rows[-1], flush=True)
    return rows


def passes() -> list[dict]:
    """Substeps against iterations at about the same solver passes per frame: the fixed-funnel heap (seeds 0 and 1)
    and the grain on a plane along and across its length, for each of ``PASSES``."""
    rows = []
    for substeps, iterations in PASSES:
        runs = [funnel_heap(substeps, seed, iterations=iterations) for seed in (0, 1)]
        values = {k: [r[k] for r in runs] for k in ("surface", "hr")}
        values["seconds"] = round(sum(r["seconds"] for r in runs) / 2, 1)
        for key, across in (("along", False), ("across", True)):
            plane = plane_case(substeps, across=across, iterations=iterations)["values"]
            values[f"holds_{key}"] = plane["holds"] if plane["slides"] else f">{ANGLES[-1]}"
        rows.append({"case": "solver passes", "substeps": substeps, "iterations": iterations, "values": values})
        print(rows[-1], flush=True)
    return rows


def landing() -> list[dict]:
    """The poured stream (seed 0, surface slope and H/R at 2.5 s) at 10 and 80 substeps, and at 80 with the speed
    clamp cut to 1/8 radius, so that its grains land no faster than at 10: what flattens the stream at 80."""
    from validation import rice_heap

    rows = []
    for substeps, clamp in ((10, 1.0), (80, 1.0), (80, 0.125)):
        (early,), seconds = rice_heap(300, True, frames=(150,), substeps=substeps, speed_clamp=clamp)
        values = {"surface_2_5": round(early[0], 1), "hr_2_5": round(early[1], 1), "seconds": round(seconds, 1)}
        rows.append({"case": "stream landing", "substeps": substeps, "speed_clamp": clamp, "values": values})
        print(rows[-1], flush=True)
    return rows


def levers() -> list[dict]:
    """Each of ``HEAP_LEVERS``: the 300-grain stream and ball (seed 0) at 10 and 40 substeps, atan H/R and the
    surface slope at 2.5 s."""
    from validation import rice_heap

    rows = []
    for what, params in HEAP_LEVERS:
        values, start = {}, time.perf_counter()
        for shape in ("stream", "ball"):
            for substeps in (10, 40):
                ((surface, hr),), _ = rice_heap(300, True, frames=(150,), substeps=substeps, shape=shape, **params)
                values[f"{shape}_{substeps}"] = round(hr, 1)
                values[f"{shape}_{substeps}_surface"] = round(surface, 1)
        values["seconds"] = round(time.perf_counter() - start, 1)
        rows.append({"case": "heap lever", "lever": what, "params": params, "values": values})
        print(rows[-1], flush=True)
    return rows


def contact_state(sim) -> tuple[float, float, float]:
    """What the contacts of a heap do: grain–grain contacts per grain (pairs of grains that carried a load in the
    last substep, counted once), the share of them in the static branch (``friction.STICKING``), and the largest
    overlap the solve left over the last 10 frames, in radii (``Diagnostics.penetration``)."""
    from nodes.simulation.friction import STICKING

    c = sim.solver.contacts
    touching = (c.groups.group >= 0) & (c.held > 0)
    groups, first = np.unique(c.groups.group[touching], return_index=True)
    sticking = float(np.mean(c.mode[touching][first] == STICKING)) if len(groups) else 0.0
    grains = len(sim.model.start) - 1
    return 2.0 * len(groups) / grains, sticking, max(sim.solver.diagnostics.penetration[-10:])


def collapses() -> list[dict]:
    """Each of ``COLLAPSES``: a dry ball of grains dropped on flat ground (``validation.rice_heap``) at each
    (substeps, iterations), per seed: atan H/R and the surface slope at 0.1 s, 0.3 s and the end, and there the
    contacts (``contact_state``)."""
    from validation import rice_heap

    rows = []
    for n, seeds, end, settings in COLLAPSES:
        for substeps, iterations in settings:
            digits = {"hr": 1, "surface": 1, "contacts_per_grain": 2, "sticking": 2, "penetration": 3}
            values, start = {k: [] for k in (*digits, "hr_0_1", "hr_0_3")}, time.perf_counter()
            for seed in seeds:
                early, mid, last = rice_heap(
                    n, True, (6, 18, end), substeps, seed=seed, shape="ball", read=contact_state, iterations=iterations
                )[0]
                values["hr_0_1"].append(round(early[1], 1))
                values["hr_0_3"].append(round(mid[1], 1))
                for k, v in zip(digits, (last[1], last[0], *last[2])):
                    values[k].append(round(v, digits[k]))
            values["seconds"] = round((time.perf_counter() - start) / len(seeds), 1)
            rows.append(
                {
                    "case": "dropped ball",
                    "grains": n,
                    "substeps": substeps,
                    "iterations": iterations,
                    "end_s": round(end / 60, 2),
                    "values": values,
                }
            )
            print(rows[-1], flush=True)
    return rows


def creep() -> list[dict]:
    """The 890-grain ball (seed 0) at the node's substeps and 4× them: how far each grain's centre moves between
    2.5 s and 7 s, for all grains and for those on the ground (centre below 2 mm), against ``CREEP_MM``."""
    from validation import rice_heap

    from nodes.simulation.settings import PARAMS

    default = PARAMS["substeps"].default
    rows = []
    for substeps in (default, 4 * default):
        (early, late), seconds = rice_heap(
            890, True, (150, 420), substeps, shape="ball", read=lambda sim: sim.model.centres(sim.state.x).copy()
        )
        moved = np.linalg.norm(late[2] - early[2], axis=1)
        ground = early[2][:, 2] < 2.0
        values = {
            "hr_2_5": round(early[1], 1),
            "hr_7": round(late[1], 1),
            "median_mm": round(float(np.median(moved)), 4),
            "p95_mm": round(float(np.percentile(moved, 95)), 3),
            "max_mm": round(float(moved.max()), 3),
            "creeping": round(float(np.mean(moved > CREEP_MM)), 3),
            "creeping_on_ground": round(float(np.mean(moved[ground] > CREEP_MM)), 3),
            "seconds": round(seconds, 1),
        }
        rows.append({"case": "dropped ball at rest", "grains": 890, "substeps": substeps, "values": values})
        print(rows[-1], flush=True)
    return rows


def pass_overlap(substeps: int, frames: int = 12) -> dict:
    """The 890-grain ball (seed 0) over its first ``frames`` (its collapse): the summed overlap of particles of
    different grains (mm) after each step of each solve — the prediction, every contact sweep, shape matching and
    the walls — and after pre-stabilisation's sweep, averaged per call: how much of what a contact sweep separates
    the grains' shape matching puts back in the same pass."""
    from scipy.spatial import cKDTree
    from validation import rice_heap

    from nodes.simulation.solver import KernelDispatch

    sums, calls = dict.fromkeys(["pre-stabilisation", *PASS_STEPS.values()], 0.0), {}

    class Trace(KernelDispatch):
        """The solver's dispatch, summing the overlap after the kernels of ``PASS_STEPS``."""

        def __init__(self, sim):
            super().__init__()
            self.sim, self.solving = sim, False
            m = sim.model.n_moving
            self.r, self.elem = sim.model.r[:m], sim.model.elem[:m]

        def overlap(self) -> float:
            r, elem = self.r, self.elem
            x = self.sim.state.x[: len(r)]
            i, j = cKDTree(x).query_pairs(2 * float(r.max()), output_type="ndarray").T
            depth = r[i] + r[j] - np.linalg.norm(x[i] - x[j], axis=1)
            return float(depth[(elem[i] != elem[j]) & (depth > 0)].sum())

        def __call__(self, family, kernel, *args):
            out = super().__call__(family, kernel, *args)
            name = kernel.__name__
            self.solving = (self.solving or name == "predict") and name != "update_velocity"
            step = PASS_STEPS.get(name) if self.solving else "pre-stabilisation" if name == "contact_sweep" else None
            if step:
                sums[step] += self.overlap()
                calls[step] = calls.get(step, 0) + 1
            return out

    def watch(sim):
        sim.solver.dispatch = Trace(sim)

    rice_heap(890, True, (frames,), substeps, shape="ball", watch=watch)
    values = {k: round(sums[k] / calls[k], 2) for k in sums if calls.get(k)}
    return {"case": "overlap through a pass", "grains": 890, "substeps": substeps, "frames": frames, "values": values}


def convergence() -> list[dict]:
    """The poured heap (seeds 0 and 1) and the grain sliding across its length at each of ``SUBSTEPS``: the
    heap's surface slope and H/R at 7 s, the tilt the grain holds to, and the seconds each costs."""
    rows = []
    for substeps in SUBSTEPS:
        heaps = [heap_case("stream", 300, substeps, seed) for seed in (0, 1)]
        start = time.perf_counter()
        plane = plane_case(substeps, across=True)
        values = {
            "surface_7": [h["values"]["surface_7"] for h in heaps],
            "hr_7": [h["values"]["hr_7"] for h in heaps],
            "heap_seconds": round(sum(h["values"]["seconds"] for h in heaps) / 2, 1),
            "holds": plane["values"]["holds"],
            "plane_seconds": round(time.perf_counter() - start, 1),
        }
        rows.append({"case": "granular convergence", "substeps": substeps, "values": values})
        print(rows[-1])
    return rows


def plot_convergence(rows: list[dict]) -> None:
    """The curve: the heap's slope and the plane's holding tilt against substeps, with what each costs."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = [r["substeps"] for r in rows]
    rows = [r["values"] for r in rows]
    fig, (ax, cost) = plt.subplots(1, 2, figsize=(9, 3.4))
    for k, label in (("surface_7", "poured heap: surface slope"), ("hr_7", "poured heap: atan H/R")):
        ax.errorbar(s, [np.mean(r[k]) for r in rows], yerr=[np.ptp(r[k]) / 2 for r in rows], marker="o", label=label)
    ax.plot(s, [r["holds"] for r in rows], marker="s", label="grain across its length holds to")
    ax.axhline(np.degrees(np.arctan(MU_S)), color="grey", ls=":", label="atan μs")
    ax.axhspan(29.6, 36.9, color="tan", alpha=0.3, label="rough rice piling angle")
    for a in (ax, cost):
        a.set_xscale("log")
        a.set_xticks(s, [str(v) for v in s])
        a.minorticks_off()
    ax.set(xlabel="substeps per frame", ylabel="degrees")
    ax.legend(fontsize=7)
    cost.plot(s, [r["heap_seconds"] for r in rows], marker="o", label="heap, 300 grains, 7 s")
    cost.plot(s, [r["plane_seconds"] for r in rows], marker="s", label="plane, 21 tilts × 1.5 s")
    cost.set(yscale="log", xlabel="substeps per frame", ylabel="wall seconds")
    cost.legend(fontsize=7)
    fig.tight_layout()
    PLOT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(PLOT, dpi=110)


def record(case: dict, command: str) -> str:
    """One measured line: the case and where, when and under what load it was measured."""
    return json.dumps(
        {
            "what": case.get("case", "granular convergence"),
            **case,
            "unit": "degrees (angles), mm (slid_mm), s (seconds)",
            "command": command,
            "load": f"{os.getloadavg()[0]:.1f}",
            "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
            "machine": f"{os.cpu_count()} cores",
        }
    )


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the inclined plane only; print, write nothing")
    ap.add_argument("--convergence", action="store_true", help="the substep curve only (docs/accuracy.md)")
    ap.add_argument("--replot", action="store_true", help="redraw the substep curve's plot from its data")
    ap.add_argument("--funnel", action="store_true", help="the fixed-funnel heap's substep curve only")
    ap.add_argument("--passes", action="store_true", help="substeps against iterations, and the stream's landing")
    ap.add_argument("--levers", action="store_true", help="what each solver setting does to the heaps")
    ap.add_argument("--mechanism", action="store_true", help="the dropped ball's collapse at substeps × iterations")
    ap.add_argument("--creep", action="store_true", help="how far the dropped ball's grains move at rest")
    ap.add_argument("--passes-overlap", action="store_true", help="the grains' overlap after each step of a pass")
    args = ap.parse_args(argv)
    if args.replot:
        plot_convergence([json.loads(line) for line in CONVERGENCE.read_text().splitlines()])
        return
    # each study: its option, the rows it measures and the data file they replace
    studies = {
        "passes_overlap": (lambda: [pass_overlap(s) for s in (10, 40)], PASS_OVERLAP),
        "creep": (creep, CREEP),
        "mechanism": (collapses, MECHANISM),
        "levers": (levers, LEVERS),
        "passes": (lambda: passes() + landing(), PASSES_RECORD),
        "funnel": (funnel_curve, FUNNEL),
        "convergence": (convergence, CONVERGENCE),
    }
    for option, (measure, path) in studies.items():
        if getattr(args, option):
            rows = measure()
            print(*rows, sep="\n")
            command = f"python benchmarks/physics_at_defaults.py --{option.replace('_', '-')}"
            path.write_text("".join(record(r, command) + "\n" for r in rows))
            if option == "convergence":
                plot_convergence(rows)
            return
    from nodes.simulation.settings import PARAMS

    default = PARAMS["substeps"].default
    pair = (default, 4 * default)  # the node's default and 4× it
    cases = [plane_case(s) for s in pair] + [plane_case(s, across=True) for s in pair]
    cases += [plane_case(s, on="grains") for s in pair]
    cases += [slab_case(s) for s in pair]
    if not args.quick:
        for shape, n in (("ball", 890), ("stream", 300)):
            cases += [heap_case(shape, n, s) for s in pair]
        cases += [heap_case("stream", 300, s, speed_clamp=1.0) for s in pair]  # the old default: falls braked
        for shape in ("ball", "stream"):
            cases += [heap_case(shape, 300, s, sticky=True) for s in pair]
    for c in cases:
        print(f"{c['case']:45s} {c['substeps']:>3} substeps  {c['ours']}")
    if args.quick:
        return
    RECORD.write_text("".join(record(c, "python benchmarks/physics_at_defaults.py") + "\n" for c in cases))


if __name__ == "__main__":
    main()
