"""Validation against published granular figures — issue 24: does the XPBD aggregate behave like granular
matter, and what does matching reality cost in time? Each case sets up an experiment, compares our figure
with a published one and writes the set-up, the reference and its source, our figure and the error, the
knobs the case needed and the seconds it took into benchmarks/measured/validation.jsonl, rendered as a table in
docs/validation.md by ``python tools/measured_tables.py`` (plots: docs/images/validation/).

    python benchmarks/validation.py            # full sizes (minutes on 2 cores)
    python benchmarks/validation.py --quick    # reduced sizes (≈ 1–2 min), what tests/simulation pins

Friction models (the node's ``friction_model``, ``nodes/simulation/friction_models.py``): 'anchored' (the
default) measures the drift since a contact began sticking (``nodes/simulation/friction.py``); 'substep' is Macklin
et al. 2014's position-level rule applied to each substep's displacement.
"""

import argparse
import dataclasses
import time
from datetime import UTC
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported


REPO = Path(__file__).resolve().parents[1]

DOC = REPO / "docs" / "validation.md"
RECORD = REPO / "benchmarks" / "measured" / "validation.jsonl"
IMAGES = REPO / "docs" / "images" / "validation"
EFFECTS = frozenset({"gravity", "contact", "friction", "collider", "damping"})
# the node's parameters but no sleeping: the measurements here read the settling itself (as measured before issue 45)
NO_SLEEP = dict(sleep_speed=0.0)
SPHERE_MASS = 0.025e-3 * 1000  # g: 25 mg per sphere, as a grain (rest positions do not depend on it)


# -- measuring a heap ---------------------------------------------------------------------------
def heap_angle(centres: np.ndarray) -> float:
    """Angle of repose of a heap on flat ground (degrees): the slope of its upper surface. The heap's
    radius R is the 95th percentile of the centres' distance ρ from its axis; the surface height in each
    of 8 rings over [0, R] is the highest centre there (a percentile scales the heights of a filled cone:
    the 90th read 27.3° for 30°); a line fitted to rings 2–7 (the apex ring and the skirt left out) gives
    the slope."""
    c = np.asarray(centres)
    rho = np.hypot(c[:, 0] - np.median(c[:, 0]), c[:, 1] - np.median(c[:, 1]))
    edges = np.linspace(0.0, np.percentile(rho, 95), 9)
    mid, top = [], []
    for lo, hi in zip(edges[1:-2], edges[2:-1]):
        ring = (rho >= lo) & (rho < hi)
        if ring.sum() >= 3:
            mid.append(0.5 * (lo + hi))
            top.append(c[ring, 2].max())
    if len(mid) < 2:
        return 0.0
    return float(np.degrees(np.arctan(max(0.0, -np.polyfit(mid, top, 1)[0]))))


def mound_angle(centres: np.ndarray) -> float:
    """atan(H/R) of a heap (degrees): H the 99th percentile of the centres' height, R the 95th percentile of
    their distance from the axis — the issue's reading, which also answers for a mound that is no cone."""
    c = np.asarray(centres)
    rho = np.hypot(c[:, 0] - np.median(c[:, 0]), c[:, 1] - np.median(c[:, 1]))
    return float(np.degrees(np.arctan(np.percentile(c[:, 2], 99) / np.percentile(rho, 95))))


def ball(n: int, spacing, seed: int = 0) -> np.ndarray:
    """n points of a jittered lattice (spacing per axis) in a ball resting 2 mm above z = 0, nearest the
    centre first: what is dropped to form a heap."""
    rng = np.random.default_rng(seed)
    sp = np.asarray(spacing, float)
    reach = (3 * n * sp.prod() / (4 * np.pi)) ** (1 / 3) * 1.4
    axes = [np.arange(-reach, reach + s, s) for s in sp]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    grid = grid[np.argsort(np.linalg.norm(grid / sp * sp.mean(), axis=1), kind="stable")][:n]
    grid = grid + rng.uniform(-0.05, 0.05, grid.shape) * sp
    grid[:, 2] += 2.0 - grid[:, 2].min()
    return grid


def ground(half: float, top: float, pitch: float):
    """φ of a ground slab (top face z = 0) over [−half, half]² × [−3, top]."""
    from scene_builders import box_mesh

    from nodes.simulation.collider import signed_distance_grid

    slab = box_mesh([-half - 5, -half - 5, -6], [half + 5, half + 5, 0], "ground")
    return signed_distance_grid([slab], np.array([-half, -half, -3.0]), np.array([half, half, top]), pitch)


# -- sphere heaps ----------------------------------------------------------------------------------
def sphere_run(x, radius, mu, anchored, sdf, **solver):
    """A solver run of loose spheres of one ``radius`` (one particle per element) at sliding friction μs = ``mu``
    (μk = 0.7 μs), rigid contacts, against the collider field ``sdf``; ``solver``: further xpbd node parameters."""
    from scene_builders import solver_run

    from nodes.simulation.settings import solver_settings_for

    n = len(x)
    settings = solver_settings_for(
        EFFECTS,
        radius,
        static_threshold=mu,
        friction_model="anchored" if anchored else "substep",
        **NO_SLEEP,
        **solver,
    )
    return solver_run(
        x,
        np.full(n, radius),
        np.full(n, 1.0 / SPHERE_MASS),
        np.arange(n + 1),
        np.zeros((n, 3)),
        np.tile([1.0, 0, 0, 0], (n, 1)),
        settings,
        sdf=sdf,
    )


def sphere_heap(n, mu, anchored, frames=(150,), substeps=10, radius=1.0, seed=0):
    """Drop a ball of n spheres (radius 1 mm, 25 mg, lattice spacing 2.2 r) on flat ground with the effects
    gravity, contact, friction, collider, damping (0.1) at μs = mu, μk = 0.7·mu; returns the heap angle
    after each count of ``frames`` (1/60 s each) and the seconds taken."""

    x = ball(n, (2.2 * radius,) * 3, seed)
    half = 2.0 * float(np.abs(x[:, :2]).max()) + 30.0
    run = sphere_run(x, radius, mu, anchored, ground(half, float(x[:, 2].max()) + 5.0, 0.8 * radius), substeps=substeps)
    start = time.perf_counter()
    angles = []
    for f in range(1, max(frames) + 1):
        run.frame()
        if f in frames:
            angles.append(heap_angle(run.state.x))
    return angles, time.perf_counter() - start


def rice_heap(
    n,
    anchored,
    frames=(150,),
    substeps=10,
    friction=1.0,
    seed=0,
    shape="stream",
    effects=EFFECTS,
    read=None,
    watch=None,
    **params,
):
    """Pour n rice-like grains (ellipsoids 5 × 3 × 2.5 mm ±10 %, 8 particles each) on flat ground: a column
    2 × 2 grains wide, one layer per 3.2 mm, random yaw, falls as a stream onto the heap's apex (at most the
    speed clamp, ≈ 0.5 m/s), at the xpbd node's defaults (effects gravity, contact, friction, collider,
    damping; no adhesion: dry rice, unless ``effects`` say otherwise). Returns (``heap_angle``, ``mound_angle``)
    after each of ``frames`` and the seconds; with ``read``, a function of the simulation, its value joins each
    pair (what the contacts do: ``physics_at_defaults.contact_state``); ``watch``, called with the simulation
    before its first frame (to trace the solver: ``physics_at_defaults.pass_overlap``)."""
    from scene_builders import box_mesh, rice_library
    from scipy.spatial.transform import Rotation

    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.setup import build_simulation
    from nodes.simulation.xpbd import xpbd
    from nodes.values import Aggregate, Placement

    rng = np.random.default_rng(seed)
    k = np.arange(n)
    x = np.stack([(k % 2 - 0.5) * 5.8 + (k // 4) % 2, ((k // 2) % 2 - 0.5) * 3.6, 3.0 + (k // 4) * 3.2], axis=1)
    if shape == "ball":
        x = ball(n, (6.0, 3.6, 3.2), seed)
    yaw = np.c_[rng.uniform(-np.pi, np.pi, n), rng.uniform(-0.1, 0.1, (n, 2))]
    placement = Placement(
        x,
        np.tile([0, 0, 1.0], (n, 1)),
        Rotation.from_euler("zyx", yaw).as_matrix(),
        variants=rng.integers(0, 4, n).astype(np.int32),
        kind_names=("japonica",),
    )
    params = XpbdParams(
        **xpbd.resolve_params(
            {
                "frames": max(frames),
                "substeps": substeps,
                "friction": friction,
                "friction_model": "anchored" if anchored else "substep",
                "log_every": 0,
                "log_meshes_every": 0,
                **params,
            }
        )
    )
    half = 3.0 * n ** (1 / 3) * 6.0
    slab = box_mesh([-half, -half, -6], [half, half, 0], "ground")
    sim = build_simulation(Aggregate(placement, (rice_library(seed=seed),)), [slab], effects, params)
    if watch:
        watch(sim)
    start = time.perf_counter()
    angles = []
    for f in range(1, max(frames) + 1):
        sim.frame()
        if f in frames:
            centres = sim.model.centres(sim.state.x)
            angles.append((heap_angle(centres), mound_angle(centres)) + ((read(sim),) if read else ()))
    return angles, time.perf_counter() - start


# -- packing ----------------------------------------------------------------------------------------
def packing_fraction(n, mu, anchored, frames=150, radius=1.0, seed=0):
    """Pour n spheres (a loose lattice, spacing 2.3 r) into an open box and let them settle; the packing
    fraction is the spheres' volume inside the box's core (two diameters from the walls and floor, below
    the top two diameters of the bed), counted on a 0.1 r sample grid. Returns (φ, seconds)."""
    from scene_builders import open_box

    from nodes.simulation.collider import signed_distance_grid

    side = 16.0 * radius
    rng = np.random.default_rng(seed)
    per = int(side // (2.3 * radius))
    k = np.arange(n)
    x = (
        np.stack([k % per, (k // per) % per, k // (per * per)], axis=1) * 2.3 * radius
        + 1.2 * radius
        + rng.uniform(-0.1, 0.1, (n, 3)) * radius
    )
    top = float(x[:, 2].max()) + 4 * radius
    sdf = signed_distance_grid(
        open_box(side, wall=2.0, height=top), np.array([-3.0, -3, -3]), np.array([side + 3, side + 3, top]), 0.4
    )
    run = sphere_run(x, radius, mu, anchored, sdf)
    start = time.perf_counter()
    for _ in range(frames):
        run.frame()
    seconds = time.perf_counter() - start
    p = run.state.x
    bed = np.percentile(p[:, 2], 98)
    lo = np.array([4 * radius, 4 * radius, 4 * radius])
    hi = np.array([side - 4 * radius, side - 4 * radius, bed - 4 * radius])
    if np.any(hi <= lo):
        raise ValueError("packing: the bed is too shallow for a core two diameters from every boundary")
    axes = [np.arange(a, b, 0.1 * radius) for a, b in zip(lo, hi)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    from scipy.spatial import cKDTree

    d, _ = cKDTree(p).query(grid)
    return float(np.mean(d < radius)), seconds


# -- the Janssen effect -------------------------------------------------------------------------------
def silo_field(diameter: float, top: float, pitch: float):
    """φ of a vertical cylindrical silo (inner diameter ``diameter``, a 96-sided tube 8 mm thick) on a floor
    slab (top face z = 0), up to ``top``; the grid covers the walls' whole thickness, so no particle a contact
    pushes into a wall finds free space behind it."""
    import trimesh
    from scene_builders import box_mesh

    from nodegraph.values import Mesh
    from nodes.simulation.collider import signed_distance_grid

    radius = diameter / 2
    tube = trimesh.creation.annulus(radius, radius + 8.0, height=top + 6.0, sections=96)
    tube.apply_translation([0.0, 0.0, (top + 6.0) / 2 - 1.0])
    floor = box_mesh([-radius - 9, -radius - 9, -8], [radius + 9, radius + 9, 0], "floor")
    reach = radius + 5.0
    return signed_distance_grid(
        [Mesh(tube.vertices, tube.faces, name="silo"), floor],
        np.array([-reach, -reach, -5.0]),
        np.array([reach, reach, top]),
        pitch,
    )


def wall_gauge(particles: int, follow: bool = False):
    """A ``KernelDispatch`` that also sums each particle's position corrections by the collider (the wall and
    floor projections of pre-stabilisation and of every iteration) while ``on``: a correction Δx of a particle
    of mass m is an impulse m·Δx/h, so over k substeps the collider's force on it is m·ΣΔx/(k·h²) (SPEC §3:
    XPBD forces are corrections over h²). Built on the solver's public dispatch hook, not a solver change.
    ``follow``: see ``_follow``."""
    from nodes.simulation.solver import KernelDispatch

    class WallGauge(KernelDispatch):
        def __init__(self, particles: int, follow: bool = False):
            super().__init__()
            self.follow = follow
            self.mark = None
            self.on = False
            self.sum = np.zeros((particles, 3))  # every collider correction
            self.solve = np.zeros((particles, 3))  # those of the iterations (pre-stabilisation's: frictionless)

        def __call__(self, family, kernel, *args):
            if self.follow:
                self._follow(family, args)
            if family != "collider" or not self.on:
                return super().__call__(family, kernel, *args)
            x = args[0].x  # the kernels take the state's arrays as one bundle (``state.StateArrays``)
            before = x.copy()
            out = super().__call__(family, kernel, *args)
            self.sum += x - before
            if args[0].x_prev is not x:  # pre-stabilisation projects with x_prev = x and no friction
                self.solve += x - before
            return out

        def _follow(self, family, args):
            """Shift the wall anchors by pre-stabilisation's moves (its contact sweep, wake_step inf, to its
            wall projection): what anchors would do if they followed those moves, a solver change tried
            from outside."""
            state = args[0]  # ``state.StateArrays``
            if isinstance(family, tuple) and np.isinf(args[5].wake_step):  # the sweep's ``ContactRule``
                self.mark = state.x.copy()
            elif family == "collider" and state.x_prev is state.x and self.mark is not None:
                anchor = state.wall_anchor
                held = ~np.isnan(anchor[:, 0])
                anchor[held] += (state.x - self.mark)[held]  # before the wall's push: the sweep's moves
                self.mark = None

    return WallGauge(particles, follow)


def silo_fill(
    n,
    mu,
    anchored=False,
    diameter=12.0,
    frames=120,
    window=30,
    substeps=20,
    iterations=4,
    shock=1.0,
    seed=0,
    follow=False,
):
    """Pour n spheres (r = 1 mm, 25 mg) into a silo of inner ``diameter`` from a loose lattice (spacing 2.2 r,
    alternate layers offset, ±0.2 r jitter) at μs = ``mu`` (walls and grains alike), μk = 0.7 μs, and let them
    settle for ``frames``; over the last ``window`` frames the gauge (``wall_gauge``) splits the collider's
    vertical force into the floor's (centres below 1.5 r) and the walls' (friction: the walls are vertical).
    Returns a dict: filled mass M, apparent mass at the base (floor force / g) and the walls' share (g), the
    walls' normal force (g-force), bed height H (mm, 98th percentile of the centres + r), seconds. ``follow``:
    the wall anchors follow pre-stabilisation's moves (``wall_gauge``), a solver change tried from outside."""
    from scene_builders import solver_run

    from nodes.simulation.settings import solver_settings_for

    radius = 1.0
    rng = np.random.default_rng(seed)
    spacing = 2.2 * radius
    inner = diameter / 2 - 1.3 * radius
    axis = np.arange(-inner, inner + 1e-9, spacing)
    layer = np.stack(np.meshgrid(axis, axis, indexing="ij"), -1).reshape(-1, 2)
    layers = []
    for k in range(n):
        grid = layer + (k % 2) * 0.5 * spacing
        grid = grid[np.hypot(grid[:, 0], grid[:, 1]) < inner]
        layers.append(np.c_[grid, np.full(len(grid), 1.2 * radius + k * spacing)])
        if sum(map(len, layers)) >= n:
            break
    x = np.concatenate(layers)[:n] + rng.uniform(-0.2, 0.2, (n, 3)) * radius
    top = float(x[:, 2].max()) + 4 * radius
    settings = solver_settings_for(
        EFFECTS,
        radius,
        substeps=substeps,
        iterations=iterations,
        static_threshold=mu,
        shock_propagation=shock,
        friction_model="anchored" if anchored else "substep",
        **NO_SLEEP,
    )
    gauge = wall_gauge(n, follow)
    run = solver_run(
        x,
        np.full(n, radius),
        np.full(n, 1.0 / SPHERE_MASS),
        np.arange(n + 1),
        np.zeros((n, 3)),
        np.tile([1.0, 0, 0, 0], (n, 1)),
        settings,
        sdf=silo_field(diameter, top, 0.4 * radius),
        dispatch=gauge,
    )
    start = time.perf_counter()
    for f in range(frames):
        gauge.on = f >= frames - window
        run.frame()
    p = run.state.x
    grams = SPHERE_MASS / (window * settings.substeps * settings.h**2 * settings.gravity)  # mm → g-force
    on_floor = p[:, 2] < 1.5 * radius
    rho = np.maximum(np.hypot(p[:, 0], p[:, 1]), 1e-9)
    inward = -(gauge.sum[:, 0] * p[:, 0] + gauge.sum[:, 1] * p[:, 1]) / rho
    inward_solve = -(gauge.solve[:, 0] * p[:, 0] + gauge.solve[:, 1] * p[:, 1]) / rho
    return {
        "M": n * SPHERE_MASS,
        "apparent": float(grams * gauge.sum[on_floor, 2].sum()),
        "walls": float(grams * gauge.sum[~on_floor, 2].sum()),
        "normal": float(grams * inward[~on_floor].sum()),
        "normal_solve": float(grams * inward_solve[~on_floor].sum()),
        "H": float(np.percentile(p[:, 2], 98) + radius),
        "seconds": time.perf_counter() - start,
    }


def janssen_fit(filled, apparent) -> float:
    """M_sat of Janssen's saturation M_app = M_sat(1 − e^(−M/M_sat)) fitted to (M, M_app) by least squares."""
    from scipy.optimize import curve_fit

    m, a = np.asarray(filled, float), np.asarray(apparent, float)
    (sat,), _ = curve_fit(lambda x, s: s * (1 - np.exp(-x / s)), m, a, p0=[max(a.max(), 1e-3)], bounds=(1e-6, np.inf))
    return float(sat)


# -- packing of ellipsoids -------------------------------------------------------------------------------
def ellipsoid_fraction(centres, turns, axes, lo, hi, pitch) -> float:
    """Share of the box [lo, hi] inside ellipsoids of semi-axes ``axes`` centred at ``centres`` with rotations
    ``turns`` (body to world), counted on a grid of ``pitch``: a point is inside when one of the ellipsoids of its
    12 nearest centres holds it."""
    from scipy.spatial import cKDTree

    n = len(centres)
    grid = np.stack(np.meshgrid(*[np.arange(a, b, pitch) for a, b in zip(lo, hi)], indexing="ij"), -1).reshape(-1, 3)
    tree = cKDTree(centres)
    inside = np.zeros(len(grid), bool)
    for a in range(0, len(grid), 20000):
        part = grid[a : a + 20000]
        _, near = tree.query(part, k=min(12, n), distance_upper_bound=float(np.max(axes)))
        near = near.reshape(len(part), -1)
        found = near < n
        near = np.where(found, near, 0)
        local = np.einsum("gkj,gkji->gki", part[:, None, :] - centres[near], turns[near])
        inside[a : a + 20000] = (found & (np.sum((local / axes) ** 2, axis=-1) <= 1.0)).any(axis=1)
    return float(inside.mean())


def ellipsoid_packing(alpha, n, size=1.5, particles=8, frames=150, seed=0):
    """Pour n ellipsoids of semi-axes size·(α, 1, 1/α) (equal volumes; Donev et al. 2004's a:b:c family), each a
    cluster of ``particles`` (``clusters.element_cluster``), from a loose lattice (spacing 2.2 a, random
    orientations) into an open box 16·size wide, frictionless (as Donev's jammed packings), and let them settle
    for ``frames``. φ = the share of the box's core (4·size from the walls, floor and the bed's top) inside the
    ellipsoids themselves at the clusters' poses (the grains as drawn; they interpenetrate where the particles do
    not reach their surface), and of the particles (the solid the solver sees), on a 0.1·size sample grid.
    Returns (φ of the ellipsoids, φ of the particles, seconds)."""
    from scene_builders import grain_mesh, open_box, solver_run
    from scipy.spatial.transform import Rotation

    from nodes.simulation.clusters import element_cluster, matrix_to_quat
    from nodes.simulation.collider import signed_distance_grid
    from nodes.simulation.settings import solver_settings_for

    axes = size * np.array([alpha, 1.0, 1.0 / alpha])
    cluster = element_cluster(grain_mesh(*(2 * axes)), particles, quadratic=False)
    c0 = cluster.centres.mean(axis=0)
    side = 16.0 * size
    spacing = 2.2 * axes.max()
    per = max(1, int((side - 0.2 * size) // spacing))
    k = np.arange(n)
    origins = np.stack([k % per, (k // per) % per, k // (per * per)], axis=1) * spacing + 0.5 * spacing
    origins[:, :2] += 0.5 * (side - per * spacing)
    turns = Rotation.random(n, random_state=seed).as_matrix()
    m = len(cluster.radii)
    x = np.concatenate([cluster.centres @ t.T + o for t, o in zip(turns, origins)])
    top = float(x[:, 2].max()) + 2 * axes.max()
    # frictionless; β = 0 as measured
    settings = solver_settings_for(EFFECTS, size, static_threshold=0.0, linear_deformation=0.0, **NO_SLEEP)
    run = solver_run(
        x,
        np.tile(cluster.radii, n),
        np.full(n * m, m / (GRAIN_MG * 1e-3)),
        np.arange(n + 1) * m,
        np.tile(cluster.centres - c0, (n, 1)),
        matrix_to_quat(turns),
        settings,
        sdf=signed_distance_grid(
            open_box(side, wall=2.0, height=top), np.array([-3.0, -3, -3]), np.array([side + 3, side + 3, top]), 0.4
        ),
    )
    start = time.perf_counter()
    for _ in range(frames):
        run.frame()
    seconds = time.perf_counter() - start
    turns = run.state.rotations()
    centres = run.model.centres(run.state.x) - np.einsum("nij,j->ni", turns, c0)  # each ellipsoid's own centre
    bed = np.percentile(centres[:, 2], 98)
    margin = 4 * size
    lo = np.array([margin, margin, margin])
    hi = np.array([side - margin, side - margin, bed - margin])
    if np.any(hi <= lo):
        raise ValueError("ellipsoid packing: the bed is too shallow for a core 4·size from every boundary")
    from scipy.spatial import cKDTree

    grid = np.stack(np.meshgrid(*[np.arange(a, b, 0.1 * size) for a, b in zip(lo, hi)], indexing="ij"), -1)
    grid = grid.reshape(-1, 3)
    p, r = run.state.x, run.model.r
    d, near = cKDTree(p).query(grid, k=8, distance_upper_bound=float(r.max()))
    solid = ((near < len(p)) & (d <= r[np.minimum(near, len(p) - 1)])).any(axis=1)
    return ellipsoid_fraction(centres, turns, axes, lo, hi, 0.1 * size), float(solid.mean()), seconds


# -- a squeezed grain ------------------------------------------------------------------------------------
GRAIN_MG = 25.0  # mg, the xpbd node's element mass


def grain_extent(x: np.ndarray, r: np.ndarray, rest: np.ndarray) -> float:
    """A cluster's thickness (mm) along its rest z axis turned with it: the particles at ``x`` (radii ``r``) aligned
    to their ``rest`` offsets (Kabsch), their extent along that axis, spheres included; a tilt does not change it."""
    from scipy.spatial.transform import Rotation

    turn = Rotation.align_vectors(x - x.mean(axis=0), rest - rest.mean(axis=0))[0]
    s = (x - x.mean(axis=0)) @ turn.apply([0.0, 0.0, 1.0])
    return float((s + r).max() - (s - r).min())


# mm: the flat plate's radius (``squeeze_xpbd``): a sphere this large sags 0.02 mm over a grain 6.5 mm off its axis
FLAT_PLATE = 1000.0


def squeeze_xpbd(
    load: float, particles: int = 8, frames: int = 90, layers: int = 1, after: int = 0, flat: bool = False, **params
) -> dict:
    """Three rice grains of the element library (``scenes.grain_mesh``, 5 × 3 × 2.5 mm, ``particles`` per cluster in
    ``layers`` through the thickness, 25 mg) lying flat on the ground 120° apart under one disc plate (particles
    r 0.5 mm on a 1 mm grid, one cluster) whose weight is 3 × ``load`` (N): a plate that cannot tip, each grain
    carrying ``load``. At the xpbd node's defaults (stiffness 2,000 N/m, β 0.3, 10 substeps × 2 iterations, shock
    propagation 4) or ``params`` over them (node units). ``after`` > 0: the plate is then lifted off and the grains
    left ``after`` frames to spring back. Returns the plate's mean height above the ground (mm), the grain's
    unloaded thickness, the grains' mean thickness under the load and after it (``grain_extent``), the grains that
    left the plate (centre > 5.5 mm from its axis), the grains' particles above the plate's mid-plane (it passed
    them) and seconds. ``flat``: the plate is one sphere of radius ``FLAT_PLATE`` instead (flat over the grains, one
    contact per grain particle, as a compression tester's platen)."""
    from scene_builders import grain_mesh, solver_run

    from nodes.simulation.clusters import element_cluster
    from nodes.simulation.settings import solver_settings_for

    cluster = element_cluster(grain_mesh(), particles, quadratic=False, layers=layers)
    grain = cluster.centres - cluster.centres.mean(axis=0)
    grain[:, 2] -= (grain[:, 2] - cluster.radii).min() - 0.01
    thickness = float((grain[:, 2] + cluster.radii).max() - (grain[:, 2] - cluster.radii).min())
    grains = []
    for k in range(3):
        c, s = np.cos(2 * np.pi * k / 3), np.sin(2 * np.pi * k / 3)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        grains.append(grain @ turn.T + turn @ [4.0, 0.0, 0.0])
    axis = np.arange(-7.0, 7.01, 1.0)
    disc = np.stack(np.meshgrid(axis, axis, indexing="ij"), -1).reshape(-1, 2)
    disc = disc[np.hypot(disc[:, 0], disc[:, 1]) <= 7.0]
    plate = np.c_[disc, np.full(len(disc), float((grain[:, 2] + cluster.radii).max()) + 0.51)]
    plate_r = 0.5
    if flat:
        plate_r = FLAT_PLATE
        plate = np.array([[0.0, 0.0, float((grain[:, 2] + cluster.radii).max()) + 0.01 + FLAT_PLATE]])
    n = len(grain)
    x = np.concatenate(grains + [plate])
    plate_g = 3 * load / 9.81 * 1000  # N → g
    settings = solver_settings_for(EFFECTS, 0.5, **{**NO_SLEEP, **params})
    run = solver_run(
        x,
        np.concatenate([cluster.radii] * 3 + [np.full(len(plate), plate_r)]),
        np.concatenate([np.full(3 * n, n / (GRAIN_MG * 1e-3)), np.full(len(plate), len(plate) / plate_g)]),
        np.array([0, n, 2 * n, 3 * n, len(x)]),
        np.concatenate([g - g.mean(axis=0) for g in grains] + [plate - plate.mean(axis=0)]),
        np.tile([1.0, 0, 0, 0], (4, 1)),
        settings,
        sdf=ground(10.0, float(x[: 3 * n, 2].max()) + 3.0, 0.25),
    )

    def extent() -> float:
        return float(np.mean([grain_extent(run.state.x[k * n : (k + 1) * n], cluster.radii, grain) for k in range(3)]))

    def top() -> float:  # the grains' mean top above the ground (mm)
        tops = (run.state.x[: 3 * n, 2] + np.tile(cluster.radii, 3)).reshape(3, n).max(axis=1)
        return float(tops.mean())

    start = time.perf_counter()
    for _ in range(frames):
        run.frame()
    centres = run.state.x[: 3 * n].reshape(3, n, 3).mean(axis=1)
    out = {
        "gap": float((run.state.x[3 * n :, 2] - plate_r).mean()),
        "thickness": thickness,
        "loaded": extent(),
        "escaped": int((np.hypot(centres[:, 0], centres[:, 1]) > 5.5).sum()),
        "top": top(),
        # grain particles over its mid-plane (over its underside: a flat plate)
        "above": int((run.state.x[: 3 * n, 2] > run.state.x[3 * n :, 2].mean() - (plate_r if flat else 0.0)).sum()),
    }
    if after:
        run.state.x[3 * n :, 2] += 2000.0  # the plate lifted off (it falls 0.7 m in 0.4 s: out of reach)
        run.state.v[3 * n :] = 0.0
        rise = 0.0
        for _ in range(after):
            run.frame()
            rise = max(rise, top())
        out["after"] = extent()
        out["top_after"] = top()
        out["rise"] = rise - out["top_after"]  # how far the released grains rose above where they came to rest
    out["seconds"] = time.perf_counter() - start
    return out


def drop_bounce(height: float = 10.0, frames: int = 60, **params) -> dict:
    """A landing: one library grain (8 particles, 25 mg) lying flat on the ground and a second one, turned 90° about
    the vertical, dropped onto it from ``height`` mm above contact, at the xpbd node's defaults (no sleeping) or
    ``params`` over them. Returns its rebound (mm: the highest its centre rises after its lowest point, over its
    height at rest at the end), its speed at impact (mm/s) and the two grains' compression at rest (mm: how far the
    dropped one's centre ends below where the rigid grains would hold it)."""
    from scene_builders import grain_mesh, solver_run

    from nodes.simulation.clusters import element_cluster
    from nodes.simulation.settings import solver_settings_for

    cluster = element_cluster(grain_mesh(), 8, quadratic=False, layers=1)
    grain = cluster.centres - cluster.centres.mean(axis=0)
    grain[:, 2] -= (grain[:, 2] - cluster.radii).min() - 0.01
    top = float((grain[:, 2] + cluster.radii).max())
    turned = grain[:, [1, 0, 2]] * [-1.0, 1.0, 1.0] + [0.0, 0.0, top + height]
    n = len(grain)
    x = np.concatenate([grain, turned])
    settings = solver_settings_for(EFFECTS, 0.5, **{**NO_SLEEP, **params})
    run = solver_run(
        x,
        np.concatenate([cluster.radii] * 2),
        np.full(2 * n, n / (GRAIN_MG * 1e-3)),
        np.array([0, n, 2 * n]),
        np.concatenate([g - g.mean(axis=0) for g in (grain, turned)]),
        np.tile([1.0, 0, 0, 0], (2, 1)),
        settings,
        sdf=ground(10.0, float(x[:, 2].max()) + 3.0, 0.25),
    )
    z, speed = [], []
    for _ in range(frames * run.solver.steps):  # substep by substep: a rebound shorter than a frame shows
        run.step()
        z.append(float(run.state.x[n:, 2].mean()))
        speed.append(float(-run.state.v[n:, 2].mean()))
    low = int(np.argmin(z))
    rest = z[-1]
    return {
        "rebound": max(z[low:]) - rest,
        "impact": max(speed),
        "compression": float(x[n:, 2].mean() - height - rest),
    }


# the elastic body's stiffness (1/s², U eq. 3.16) at which a 25 mg grain strains 25 % at 0.2 N (fitted once:
# k = 1/h² at 300 substeps, 3.24e8, gave 22.1 %; strain ∝ 1/k); α = k·h² ≤ 1 needs ≥ 282 substeps per 1/60 s
TOMITA_STIFFNESS = 2.85e8


def squeeze_body(
    load, stiffness=TOMITA_STIFFNESS, substeps=300, frames=30, ramp=10, tearing=True, threshold=3.0
) -> dict:
    """One grain (``scenes.grain_mesh`` surface, 25 mg) as the tearing node's elastic body (``tearing.body``: shape
    matching per piece, β 0.3, damping 50/s, break rule 'vertex' at ``threshold`` × stretch): its bottom tenth (of the
    thickness) held, ``load`` (N) pressing its top tenth down, ramped up over ``ramp`` frames. Strain = 1 − the
    distance between the two patches' mean heights over the rest one; the largest edge stretch (current over
    rest length, what the break test reads), tears and pieces at the end."""
    from scene_builders import grain_mesh

    from nodes.tearing.body import BodySettings, ElasticBody

    tm = grain_mesh().to_trimesh()
    tm.merge_vertices()
    x, faces = np.asarray(tm.vertices), np.asarray(tm.faces)
    z = x[:, 2]
    bottom = z < z.min() + 0.1 * np.ptp(z)
    top = z > z.max() - 0.1 * np.ptp(z)
    mass = GRAIN_MG * 1e-3
    push = load * 1e6 / (mass / len(x) * top.sum())  # N → g·mm/s², over the patch's mass: mm/s²
    h = 1 / 60 / substeps
    body = ElasticBody(
        x,
        faces,
        mass,
        BodySettings(h=h, stiffness=stiffness, beta=0.3, damping=50.0, tearing=tearing, threshold=threshold),
        moving=~bottom,
    )
    start = time.perf_counter()
    rest = x[top, 2].mean() - x[bottom, 2].mean()
    for frame in range(frames):
        pressed = body.x0[:, 2] > z.max() - 0.1 * np.ptp(z)  # the vertices reorder when pieces split
        body.accel[:] = 0.0
        body.accel[pressed, 2] = -push * min(1.0, (frame + 1) / ramp)
        for _ in range(substeps):
            body.step()
    held = body.x0[:, 2] < z.min() + 0.1 * np.ptp(z)
    pressed = body.x0[:, 2] > z.max() - 0.1 * np.ptp(z)
    m = body.mesh
    return {
        "strain": float(1 - (body.x[pressed, 2].mean() - body.x[held, 2].mean()) / rest),
        "stretch": float((np.linalg.norm(body.x[m.origin] - body.x[m.dest], axis=1) / body.rest_length).max()),
        "tears": int(body.tears),
        "pieces": int(body.n_clusters),
        "seconds": time.perf_counter() - start,
    }


# -- grain geometry -------------------------------------------------------------------------------------
def grain_geometry():
    """The base_mesh node's rice presets: length × width × thickness (bounding box, mm) and volume."""
    from nodes.elements.base_mesh import base_mesh
    from nodes.elements.rice_variety import rice_variety

    rows = []
    for variety in ("japonica", "indica", "aromatic"):
        mesh = base_mesh.call(shape="rice", variety=rice_variety.call(variety=variety))
        import trimesh

        tm = trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.faces))
        ext = np.sort(tm.bounds[1] - tm.bounds[0])[::-1]
        rows.append((variety, *ext, float(tm.volume)))
    return rows


# -- the report ----------------------------------------------------------------------------------------
@dataclasses.dataclass
class Case:
    name: str
    setup: str
    reference: str
    ours: str
    error: str
    knobs: str
    seconds: float
    plot: str | None = None


def run_cases(quick: bool, ellipsoids: bool | None = None) -> tuple[list[Case], dict]:
    """Every case at quick or full size; returns the cases and the raw figures (what the tests pin).
    ``ellipsoids``: run the ellipsoid packing (≈ 1 min CPU at quick size); None: in full mode only."""
    ellipsoids = not quick if ellipsoids is None else ellipsoids
    figures: dict = {}
    cases: list[Case] = []
    n_sph = 600 if quick else 2000
    mus = (0.0, 0.3, 0.6) if quick else (0.0, 0.15, 0.3, 0.45, 0.6, 0.8, 1.0)

    # 1. angle of repose of spheres against μ, both friction models, at 2.5 s
    t = time.perf_counter()
    curve = {}
    for anchored in (False, True):
        curve[anchored] = [sphere_heap(n_sph, mu, anchored)[0][0] for mu in mus]
    figures["sphere_repose"] = {"mu": mus, "substep": curve[False], "anchored": curve[True]}
    plot = _plot_curve(
        "sphere_repose",
        mus,
        {"substep friction": curve[False], "anchored friction (default)": curve[True]},
        "sliding friction μs",
        "heap angle (°)",
    )
    cases.append(
        Case(
            "Angle of repose of spheres vs μ",
            f"{n_sph} spheres (r = 1 mm) dropped as a ball on flat ground, 2.5 s; μk = 0.7 μs",
            "rises with μ and saturates; insensitive to stiffness and density (Zhou et al. 2001, PRE 64:021301); "
            "frictionless: flat",
            "substep: "
            + ", ".join(f"{a:.1f}°" for a in curve[False])
            + "; anchored: "
            + ", ".join(f"{a:.1f}°" for a in curve[True])
            + f" at μ = {', '.join(f'{m:g}' for m in mus)}",
            "trend only (no rolling DOF: our particles do not rotate, so rolling resistance is effectively infinite)",
            "10 substeps × 2 iterations, shock propagation 4, damping 0.1",
            time.perf_counter() - t,
            plot,
        )
    )

    # 2. stability: 2.5 s against 7 s (quick: 5 s), 10 against 40 substeps
    late = 300 if quick else 420
    t = time.perf_counter()
    stab = {}
    for anchored in (False, True):
        (a25, a_late), _ = sphere_heap(n_sph, 0.6, anchored, frames=(150, late))
        (a40,), _ = sphere_heap(n_sph, 0.6, anchored, frames=(150,), substeps=40)
        stab[anchored] = (a25, a_late, a40)
    figures["sphere_stability"] = {"substep": stab[False], "anchored": stab[True], "late_s": late / 60}
    cases.append(
        Case(
            "Heap at rest (spheres, μ = 0.6)",
            f"as above; angle at 2.5 s and {late / 60:g} s, and at 2.5 s with 40 substeps",
            "a pile comes to rest: ≤ 3° change over time and from 10 to 40 substeps (issue 24)",
            "; ".join(
                f"{k}: {v[0]:.1f}° → {v[1]:.1f}° ({late / 60:g} s), {v[2]:.1f}° (40 substeps)"
                for k, v in (("substep", stab[False]), ("anchored", stab[True]))
            ),
            "; ".join(
                f"{k}: Δt {v[1] - v[0]:+.1f}°, Δsubsteps {v[2] - v[0]:+.1f}°"
                for k, v in (("substep", stab[False]), ("anchored", stab[True]))
            ),
            "10 or 40 substeps × 2 iterations",
            time.perf_counter() - t,
        )
    )

    # 3. rice-like grains at the node's defaults: a poured stream, over time, against μ and the substeps
    n_rice = 300
    t = time.perf_counter()
    frames = (150, 300) if quick else (150, 300, 420)
    rice = {anchored: rice_heap(n_rice, anchored, frames=frames)[0] for anchored in (False, True)}
    dry = rice_heap(n_rice, True, frames=(150,), friction=0.0)[0][0][1]
    figures["rice_repose"] = {"substep": rice[False], "anchored": rice[True], "frictionless": dry}
    extra = ""
    if not quick:
        # 4× the substeps at the same top speed (the speed clamp is in radii per substep: at 40 substeps and
        # clamp 1 the stream lands 4× faster, a higher pour, which lowers any heap)
        (fine, _), _ = rice_heap(n_rice, True, frames=(150, 300), substeps=40, speed_clamp=0.25)
        (fast,), _ = rice_heap(n_rice, True, frames=(150,), substeps=40)
        by_mu = {m: rice_heap(n_rice, True, frames=(150,), friction=m)[0][0] for m in (0.5, 0.8)}
        figures["rice_repose"].update({"substeps40": fine, "substeps40_fast": fast, "by_friction": by_mu})
        extra = (
            f"; 40 substeps (same top speed) H/R {fine[1]:.1f}° (at clamp 1, landing 4× faster: {fast[1]:.1f}°); "
            + ", ".join(f"friction ×{m:g}: H/R {v[1]:.1f}°" for m, v in by_mu.items())
        )
    low, high = 30.0, 45.0
    hold = rice[True][-1][1] - rice[True][0][1]
    cases.append(
        Case(
            "Angle of repose of rice-like grains",
            f"{n_rice} ellipsoid grains 5 × 3 × 2.5 mm (8 particles each) poured as a stream on flat ground, xpbd "
            "defaults (μs 0.6, μk 0.42, damping 0.1, sleeping 2 mm/s), no adhesion; H/R = atan(height / radius)",
            "35.7–44.4° (paddy, Zareiforoush et al. 2009); milled rice static friction 0.37 glass, 0.48 wood "
            "(Jouki & Khazaei 2012); issue 24: 30–45°, ≤ 3° change from 2.5 s on",
            "; ".join(
                f"{k}: " + " → ".join(f"surface {a:.1f}°, H/R {b:.1f}°" for a, b in v)
                for k, v in (("substep", rice[False]), ("anchored (default)", rice[True]))
            )
            + f" ({' and '.join(f'{f / 60:g} s' for f in frames)}); frictionless H/R {dry:.1f}°"
            + extra,
            f"anchored H/R {rice[True][0][1]:.1f}° at 2.5 s: "
            + ("inside" if low <= rice[True][0][1] <= high else "OUTSIDE")
            + f" 30–45°, {hold:+.1f}° by {frames[-1] / 60:g} s; the substep rule creeps flat",
            "node defaults: 10 substeps × 2 iterations, 8 particles per grain",
            time.perf_counter() - t,
        )
    )
    if not quick:
        # the issue's own set-up: a loose ball of 900 grains dropped on the ground
        t = time.perf_counter()
        ball10 = rice_heap(900, True, frames=(150, 420), shape="ball")[0]
        ball40 = rice_heap(900, True, frames=(150,), shape="ball", substeps=40)[0][0]
        figures["rice_ball"] = {"substeps10": ball10, "substeps40": ball40}
        cases.append(
            Case(
                "Collapse of a ball of rice-like grains",
                "900 grains on a jittered lattice (a loose ball, φ ≈ 0.3) dropped 2 mm onto flat ground, xpbd defaults",
                "issue 24's set-up: 12° at the old defaults, creeping to 7°; a collapsing column spreads below the "
                "angle of repose",
                f"H/R {ball10[0][1]:.1f}° (2.5 s) → {ball10[1][1]:.1f}° (7 s); 40 substeps {ball40[1]:.1f}°",
                "a flat-topped mound below 30°: the loose ball compacts and flows as it lands; it rests "
                f"({ball10[1][1] - ball10[0][1]:+.1f}° by 7 s, {ball40[1] - ball10[0][1]:+.1f}° at 4× the substeps)",
                "node defaults",
                time.perf_counter() - t,
            )
        )

    # 4. packing of settled spheres
    t = time.perf_counter()
    n_pack = 1500 if quick else 4000
    pack = {mu: packing_fraction(n_pack, mu, True)[0] for mu in (0.0, 0.3)}
    pack_sub = packing_fraction(n_pack, 0.3, False)[0]
    figures["packing"] = {"frictionless": pack[0.0], "mu0.3_anchored": pack[0.3], "mu0.3_substep": pack_sub}
    cases.append(
        Case(
            "Random packing of settled spheres",
            f"{n_pack} spheres poured into a 16 r box, 2.5 s; φ in the core (2 d from walls and top)",
            "frictionless ≈ 0.639, μ = 0.3 ≈ 0.593 (Agnolin & Roux 2007)",
            f"frictionless {pack[0.0]:.3f}; μ 0.3: anchored {pack[0.3]:.3f}, substep {pack_sub:.3f}",
            f"{pack[0.0] - 0.639:+.3f}, {pack[0.3] - 0.593:+.3f} (anchored)",
            "10 substeps × 2 iterations, shock propagation 4",
            time.perf_counter() - t,
        )
    )

    # 5. grain geometry
    t = time.perf_counter()
    geo = grain_geometry()
    figures["geometry"] = geo
    japonica = geo[0]
    cases.append(
        Case(
            "Rice-grain geometry",
            "base_mesh shape rice, each variety preset (SPEC §1.1: length factors 1.8 / 1.0 / 0.7 on "
            "5.2 × 3.0 × 2.0 mm, docs/sizes.md)",
            "7.43 × 2.75 × 2.53 mm, 26.91 g per 1,000 grains, one milled variety (Jouki & Khazaei 2012); cooked "
            "grains are larger (expansion P, G eq. 6)",
            "; ".join(f"{v}: {a:.2f} × {b:.2f} × {c:.2f} mm, {vol:.1f} mm³" for v, a, b, c, vol in geo)
            + "; xpbd mass default 25 mg",
            f"japonica length {japonica[1] - 7.43:+.2f} mm, width {japonica[2] - 2.75:+.2f}, thickness "
            f"{japonica[3] - 2.53:+.2f}; mass {25.0 - 26.91:+.2f} mg",
            "none (the presets are G's factors on a raw short grain, not a measured variety)",
            time.perf_counter() - t,
        )
    )
    cases.append(glue_case(quick, figures))
    cases.append(janssen_case(quick, figures))
    cases.append(squeeze_case(quick, figures))
    if ellipsoids:
        cases.append(ellipsoid_case(quick, figures))
    return cases, figures


def glue_case(quick: bool, figures: dict) -> Case:
    """A pressed block of sticky rice set down under gravity, glued and not, against the substeps (``glue``)."""
    from scene_builders import block_heights, pressed_block

    t = time.perf_counter()
    block = pressed_block()
    runs = {}
    for glue, substeps in ((0.0, 30), (1.0, 30)) + (() if quick else ((1.0, 10), (1.0, 20), (1.0, 60))):
        start = time.perf_counter()
        kept, sim = block_heights(block, glue, substeps=substeps)
        links = sim.state.glued[~sim.model.glue.link_own].mean() if sim.model.glue is not None else float("nan")
        runs[(glue, substeps)] = (float(kept.min()), float(kept[-1]), float(links), time.perf_counter() - start)
    figures["glue"] = runs
    loose, glued = runs[(0.0, 30)], runs[(1.0, 30)]
    return Case(
        "A pressed block of sticky rice set down (onigiri)",
        "90 randomly turned ellipsoid grains pressed on a 3 × 3 × 10 grid (3.2 mm: they overlap), relaxed 10 frames "
        "without gravity, then set on the ground under gravity for 40 frames, clumping 0.5; height = particles' z "
        "range over its start, worst frame and last",
        "a pressed onigiri of sticky rice holds its shape (issue 24: the recipe keeps ≥ 95 % of its height)",
        "; ".join(
            f"glue {g:g}, {s} substeps: {lo:.3f} / {last:.3f}"
            + (f", {links:.0%} of the glue holds" if g else "")
            + f" ({sec:.1f} s)"
            for (g, s), (lo, last, links, sec) in runs.items()
        )
        + ". The full-size onigiri recipe (3,086 grains, 20 frames, 30 substeps, glue 1): 98.1 % of its pressed "
        "height on the exported meshes (79.7 → 78.2 mm), lowest grain 0.03 mm above the plate; without glue 78 %; "
        "392 grains (onigiri.size 24, 40 frames): 93.6 / 97.4 / 98.7 % at 10 / 20 / 30 substeps",
        f"glued {glued[0] - 0.95:+.3f} over 95 % at worst; loose {loose[1]:.2f}: a heap",
        "glue 1 (lattice shape matching of each grain's glued neighbourhood, tearing at one particle radius), "
        "30 substeps × 2 iterations: the glue's stiffness is bounded by the iterations a substep has",
        time.perf_counter() - t,
    )


def ellipsoid_case(quick: bool, figures: dict) -> Case:
    """Random packing of frictionless ellipsoids of the a:b:c = α:1:1/α family against α."""
    t = time.perf_counter()
    alphas = (1.0, 1.25, 1.5) if quick else (1.0, 1.125, 1.25, 1.5, 2.0)
    cover = []  # the share of each ellipsoid's volume its 8 particles fill
    rng = np.random.default_rng(0)
    from scene_builders import grain_mesh

    from nodes.simulation.clusters import element_cluster

    for a in alphas:
        axes = 1.5 * np.array([a, 1.0, 1.0 / a])
        cluster = element_cluster(grain_mesh(*(2 * axes)), 8, quadratic=False)
        p = rng.uniform(-axes, axes, (100000, 3))
        p = p[np.sum((p / axes) ** 2, axis=1) <= 1.0]
        gap = np.linalg.norm(p[:, None, :] - cluster.centres[None], axis=2)
        cover.append(float((gap <= cluster.radii).any(axis=1).mean()))
    # as many grains as give a bed ≈ 18 mm deep: the particles fill less of each ellipsoid as α grows
    counts = [int(round(480 / c)) for c in cover]
    runs = [ellipsoid_packing(a, n) for a, n in zip(alphas, counts)]
    solid = [r[1] for r in runs]
    peak = int(np.argmax(solid))
    figures["ellipsoids"] = {
        "alpha": alphas,
        "ellipsoids": [r[0] for r in runs],
        "particles": [r[1] for r in runs],
        "cover": cover,
        "counts": counts,
    }
    plot = _plot_curve(
        "ellipsoid_packing",
        alphas,
        {
            "ellipsoids as drawn": [r[0] for r in runs],
            "their particles (the solver's solid)": [r[1] for r in runs],
            "Donev et al. 2004; Man et al. 2005": [{1.0: 0.64, 1.25: 0.735}.get(a, np.nan) for a in alphas],
        },
        "aspect ratio α (a:b:c = α:1:1/α)",
        "packing fraction φ",
    )
    return Case(
        "Random packing of ellipsoids vs aspect ratio",
        f"{', '.join(map(str, counts))} ellipsoids (semi-axes 1.5 mm × (α, 1, 1/α), equal volumes, 8 particles "
        "each, 25 mg) "
        "poured frictionless into a 24 mm box from a loose lattice with random orientations, 2.5 s; φ in the core "
        "(6 mm from walls, floor and top) of the ellipsoids at the clusters' poses, and of the particles",
        "rises from the sphere value (≈ 0.64) to ≈ 0.74 near 1.25:1:0.8, then falls (Donev et al. 2004, Science "
        "303:990; Man et al. 2005, PRL 94:198001)",
        "ellipsoids "
        + ", ".join(f"{r[0]:.3f}" for r in runs)
        + "; particles "
        + ", ".join(f"{r[1]:.3f}" for r in runs)
        + f" at α = {', '.join(f'{a:g}' for a in alphas)}; the particles fill "
        + ", ".join(f"{c * 100:.0f} %" for c in cover)
        + " of each ellipsoid",
        f"particles: highest at α {alphas[peak]:g} ({solid[peak]:.3f}), "
        f"{'a rise then a fall as' if 0 < peak < len(alphas) - 1 else 'unlike'} Donev's; {solid[0] - 0.64:+.3f} at α 1"
        + (f", {solid[alphas.index(1.25)] - 0.735:+.3f} at 1.25" if 1.25 in alphas else "")
        + ": denser than hard ellipsoids, as our spheres are (case 4: +0.028) and more, since 8-particle clusters are "
        "bumpy and their bumps nest; the drawn ellipsoids interpenetrate where the particles do not reach (they fill "
        f"{cover[-1] * 100:.0f}–{cover[0] * 100:.0f} % of them), so theirs is no packing fraction; a like-for-like "
        "check needs clusters that fill the ellipsoid (more particles per grain)",
        "10 substeps × 2 iterations, shock propagation 4, frictionless, 8 particles per grain",
        time.perf_counter() - t,
        plot,
    )


def squeeze_case(quick: bool, figures: dict) -> Case:
    """A squeezed grain: the xpbd cluster under a flat plate and the grid plate with compliant contacts,
    and with rigid ones (one layer of particles, and two through the thickness), the tearing node's elastic body under
    a pressed patch."""
    t = time.perf_counter()
    loads = (0.001, 0.05, 0.2, 1.0) if quick else (0.001, 0.02, 0.05, 0.1, 0.2, 0.4, 1.0)
    soft = [squeeze_xpbd(f, flat=True, squeeze_strain=25.0) for f in loads]
    soft_strain = [1 - r["gap"] / soft[0]["gap"] for r in soft]
    grid = [squeeze_xpbd(f, squeeze_strain=25.0) for f in (0.001, 0.2)]
    rigid = dict(squeeze_strain=0.0)
    plate = [squeeze_xpbd(f, after=30 if f == 0.2 else 0, **rigid) for f in loads]
    rest = plate[0]["gap"]  # the plate on unloaded grains (≈ 1 mN): the reference height
    xpbd_strain = [1 - r["gap"] / rest for r in plate]
    dense = squeeze_xpbd(0.2, particles=16, **rigid)
    dense_rest = squeeze_xpbd(0.001, particles=16, **rigid)
    # two layers through the thickness (``particle_layers`` 2), at the defaults and with 8 iterations
    layered = {f: squeeze_xpbd(f, particles=16, layers=2, **rigid) for f in (0.001, 0.05, 0.2)}
    held = {
        f: squeeze_xpbd(f, particles=16, layers=2, after=30, iterations=8, stiffness=100.0, **rigid)
        for f in (0.001, 0.2)
    }
    body_loads = (
        (0.05, 0.1, 0.2, 0.3, 0.4, 0.6, 0.8) if quick else (0.02, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
    )
    body = [squeeze_body(f) for f in body_loads]
    crushed = squeeze_body(0.002, stiffness=2.0e4, substeps=10)  # the elastic_body node's stiffness and substeps
    low = squeeze_body(0.4, threshold=1.2)  # a break threshold below the longest edge at 50 % strain
    half = min(body, key=lambda r: abs(r["strain"] - 0.5))
    at02 = body[body_loads.index(0.2)]["strain"]
    one = plate[loads.index(0.2)]
    figures["squeeze"] = {
        "loads": loads,
        "soft_strain": soft_strain,
        "grid_strain": 1 - grid[1]["gap"] / grid[0]["gap"],
        "xpbd_strain": xpbd_strain,
        "xpbd_flattening": 1 - one["loaded"] / one["thickness"],
        "xpbd16_strain": 1 - dense["gap"] / dense_rest["gap"],
        "layered_rest_flattening": 1 - layered[0.001]["loaded"] / layered[0.001]["thickness"],
        "layered_005_strain": 1 - layered[0.05]["gap"] / layered[0.001]["gap"],
        "layered_02_above": layered[0.2]["above"],
        "held_strain": 1 - held[0.2]["gap"] / held[0.001]["gap"],
        "held_flattening": 1 - held[0.2]["loaded"] / held[0.2]["thickness"],
        "held_left": 1 - held[0.2]["after"] / held[0.2]["thickness"],
        "body_loads": body_loads,
        "body_strain": [r["strain"] for r in body],
        "body_stretch": [r["stretch"] for r in body],
        "body_tears": [r["tears"] for r in body],
        "crushed_strain": crushed["strain"],
        "low_threshold_tears": low["tears"],
    }
    sq = figures["squeeze"]
    plot = _plot_squeeze(loads, (soft_strain, xpbd_strain), body_loads, body)
    return Case(
        "Squeezed grain",
        "(a) xpbd: three library grains (5 × 3 × 2.5 mm ellipsoids, 8 particles, 25 mg) flat on the ground under one "
        "flat plate (a sphere of radius 1 m) of weight 3 × load, 1.5 s, compliant contacts "
        "(squeeze_strain 25 %); strain = 1 − plate height / its height at 1 mN; the same under the grid plate "
        "(particles r 0.5 mm on a 1 mm grid, one cluster: a plate that cannot tip). (a′) rigid contacts "
        "(squeeze_strain 0), grid plate; flattening = 1 − the grain's thickness along its own axis / the unloaded "
        "one; springback: the plate lifted off, 0.5 s. (c) the same with 16 particles in two layers through the "
        "thickness (particle_layers 2), rigid contacts. "
        "(b) the tearing node's elastic body (the same grain's surface, 162 vertices, 25 mg): bottom tenth held, "
        "top tenth pressed, load ramped over 1/6 s, 0.5 s; strain from the two patches' heights; tearing on "
        "(rule vertex, 3× stretch)",
        "cooked rice strains ≈ 25 % at 0.2 N in its elastic range and fractures near 50 % (Tomita, via G; SPEC §3)",
        "(a) strain "
        + ", ".join(f"{e * 100:.1f} %" for e in soft_strain)
        + f" at {', '.join(f'{f:g}' for f in loads)} N (grid plate: {sq['grid_strain'] * 100:.1f} % at 0.2 N); "
        "(a′) strain "
        + ", ".join(f"{e * 100:.1f} %" for e in xpbd_strain)
        + f" at {', '.join(f'{f:g}' for f in loads)} N (16 particles: {sq['xpbd16_strain'] * 100:.1f} % at 0.2 N); "
        f"the grain itself does not flatten ({sq['xpbd_flattening'] * 100:.1f} % at 0.2 N); (c) at the defaults "
        f"{sq['layered_rest_flattening'] * 100:.0f} % flat under 1 mN, and at 0.05 N the plate sinks "
        f"{sq['layered_005_strain'] * 100:.0f} % into the grains (at 0.2 N it passes through them: "
        f"{sq['layered_02_above']} of their 48 particles end above it); at 8 iterations and 100 N/m strain "
        f"{sq['held_strain'] * 100:.0f} % at 0.2 N, the grain flattened {sq['held_flattening'] * 100:.1f} %, "
        f"{sq['held_left'] * 100:.1f} % left 0.5 s after the lift; (b) strain "
        + ", ".join(f"{r['strain'] * 100:.0f} %" for r in body)
        + f" at {', '.join(f'{f:g}' for f in body_loads)} N, tears {sum(r['tears'] for r in body)}; largest edge "
        f"stretch {half['stretch']:.2f}× at {half['strain'] * 100:.0f} % strain; at the node's stiffness "
        f"(2·10⁴/s², 10 substeps) crushed through itself at 2 mN (strain {crushed['strain']:.0f}×)",
        f"(a) {soft_strain[loads.index(0.2)] * 100:.1f} % against 25 % at 0.2 N: the grain gives at its contacts, "
        "by an XPBD compliance derived from Tomita's strain (``contact_constraints.face_compliance``), rigid past "
        "50 % (the 1 N row stops there: fracture, which no rule here models); the grid plate's small particles "
        "touch each grain particle 1–4 times, contacts in parallel, so it reads stiffer. (a′) "
        f"{xpbd_strain[loads.index(0.2)] * 100:.1f} %: with rigid contacts the xpbd grain is rigid across its "
        "thickness — its particles are spheres that do not deform and at 8 per grain lie in one plane, so the only "
        "give is the contacts' tolerated overlap; stiffness and β cannot change it. (c) two layers can flatten, but "
        "the give is the solve's, not the stiffness's: at 10 × 2 two iterations of contacts then shape matching do "
        "not hold a top layer that touches nothing below, whatever the stiffness (1–2,000 N/m), and the plate "
        "passes between the smaller particles; with more iterations the grain holds and springs back but stays "
        "stiffer than its compliance (most of the plate's strain is its sinking between the top particles): with "
        "rigid contacts no layout reaches 20–30 % at the defaults (candidates, heap angles and costs: the table "
        "below). (b) "
        f"{at02 * 100:.0f} % at 0.2 N by construction (the stiffness is fitted to it), linear to "
        f"{body[-1]['strain'] * 100:.0f} % (the top passes through the bottom: no contact inside the body); the "
        "tearing effect never breaks it: its test is edge stretch (3×), which a squeeze does not produce "
        f"(≤ {max(r['stretch'] for r in body):.2f}×); even at threshold 1.2 it holds at 50 % ({low['tears']} tears: "
        "rule vertex needs every edge at a vertex past it); fracture near 50 % needs a compressive rule",
        "(a) xpbd defaults but squeeze_strain 25 %: 10 substeps × 2 iterations, stiffness 2,000 N/m, β 0.3, 8 "
        "particles per grain; (a′) the defaults (squeeze_strain 0); (c) 16 particles, particle_layers 2, "
        "squeeze_strain 0; "
        f"(b) 300 substeps per 1/60 s (α = k·h² ≤ 1 caps k at 1/h²: a 25 mg grain as stiff as Tomita's needs "
        f"k = {TOMITA_STIFFNESS:.2g}/s², ≥ 282 substeps), β 0.3, damping 50/s",
        time.perf_counter() - t,
        plot,
    )


def _axes():
    """pyplot (headless), a new figure and its axes, the plot folder made: the cases' plots all start so."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    IMAGES.mkdir(parents=True, exist_ok=True)
    fig, ax = plt.subplots(figsize=(5, 3.2))
    return plt, fig, ax


def _saved(plt, fig, ax, path, legend: int | None = 8) -> str:
    """Grid and legend on, the figure written to ``path`` and closed; its path as the doc links it."""
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return str(path.relative_to(DOC.parent))


def _plot_squeeze(loads, xpbd_strains, body_loads, body):
    plt, fig, ax = _axes()
    soft, rigid = xpbd_strains
    ax.plot(loads, np.array(soft) * 100, "o-", label="xpbd grain (8 particles), compliant contacts, flat plate")
    ax.plot(loads, np.array(rigid) * 100, "o--", label="xpbd grain, rigid contacts")
    ax.plot(body_loads, [r["strain"] * 100 for r in body], "s-", label="elastic body (tearing on), k fitted")
    torn = [(f, r["strain"] * 100) for f, r in zip(body_loads, body) if r["tears"]]
    if torn:
        ax.plot(*zip(*torn), "rx", ms=9, label="torn")
    ax.plot([0.2], [25], "k*", ms=11, label="Tomita: 25 % at 0.2 N")
    ax.axhline(50, color="gray", ls=":", label="fracture near 50 %")
    ax.set_xlabel("load (N)")
    ax.set_ylabel("strain (%)")
    return _saved(plt, fig, ax, IMAGES / "squeezed_grain.png", legend=7)


SILO_D = 12.0  # mm, six sphere diameters
JAKY_PHI = 30.1  # °, the anchored sphere heap's angle at μs 0.6 (case 1): the grains' internal friction angle


def janssen_case(quick: bool, figures: dict) -> Case:
    """The Janssen effect: fills of a silo with frictional walls, the fit of M_sat and λ, the controls."""
    t = time.perf_counter()
    fills = (150, 300, 600, 900) if quick else (150, 300, 450, 600, 900, 1200, 1500)
    runs = [silo_fill(n, 0.6) for n in fills]
    filled = np.array([r["M"] for r in runs])
    apparent = np.array([r["apparent"] for r in runs])
    sat = janssen_fit(filled, apparent)
    per_mm = np.polyfit([r["H"] for r in runs], filled, 1)[0]  # bulk density × cross-section, g/mm
    lam = sat / per_mm
    deep = runs[-1]
    mobilised = deep["walls"] / deep["normal"]  # the wall friction's share of the walls' normal force
    mobilised_solve = deep["walls"] / deep["normal_solve"]  # … of the normal force of the iterations alone
    k_jaky = 1.0 - np.sin(np.radians(JAKY_PHI))
    lam_janssen = SILO_D / (4 * 0.6 * k_jaky)
    k_eff = SILO_D / (4 * mobilised * lam)
    smooth = silo_fill(300, 0.0)  # frictionless walls (and grains): the floor carries everything
    anchored = silo_fill(600, 0.6, anchored=True)  # the default friction model
    followed = silo_fill(600, 0.6, anchored=True, follow=True)  # … with anchors that follow pre-stabilisation
    scaled = silo_fill(300, 0.0, shock=4.0)  # the default shock propagation
    figures["janssen"] = {
        "M": filled.tolist(),
        "apparent": apparent.tolist(),
        "M_sat": sat,
        "lambda": lam,
        "per_mm": per_mm,
        "mobilised": mobilised,
        "mobilised_solve": mobilised_solve,
        "K_eff": k_eff,
        "smooth_ratio": smooth["apparent"] / smooth["M"],
        "anchored_ratio": anchored["apparent"] / anchored["M"],
        "anchored_follow_ratio": followed["apparent"] / followed["M"],
        "shock4_ratio": scaled["apparent"] / scaled["M"],
    }
    plot = _plot_janssen(filled, apparent, sat, smooth)
    return Case(
        "Janssen effect",
        f"r = 1 mm spheres (25 mg) poured into a silo D = {SILO_D:g} mm (a 96-sided tube on a floor), "
        f"{len(fills)} fills of {fills[0]}–{fills[-1]} spheres, settled 2 s; μs 0.6 (grains and walls), μk 0.42; "
        "apparent mass = the floor's force / g (the collider's corrections on the particles touching the floor, "
        "m·ΣΔz/(k·h²), averaged over the last 0.5 s), the walls' = their friction",
        "M_app = M_sat(1 − e^(−M/M_sat)), λ = M_sat/(ρ_b A) = D/(4 μ_wall K) (Janssen 1895; Sperl 2006, "
        f"Granular Matter 8:59); Jaky K = 1 − sin φ = {k_jaky:.2f} at φ = {JAKY_PHI:g}° (our sphere heap) → "
        f"λ = {lam_janssen:.1f} mm = {lam_janssen / SILO_D:.2f} D",
        "M_app/M "
        + ", ".join(f"{a / m:.2f}" for a, m in zip(apparent, filled))
        + f" at M = {', '.join(f'{m:g}' for m in filled)} g; fit M_sat {sat:.1f} g, λ {lam:.1f} mm "
        f"({lam / SILO_D:.2f} D; ρ_b A {per_mm:.3f} g/mm); wall friction mobilised F_wall/F_N {mobilised:.3f} "
        f"({mobilised_solve:.2f} of the iterations' normal force) → K_eff = D/(4 μ_mob λ) {k_eff:.2f}; "
        f"frictionless: M_app/M {smooth['apparent'] / smooth['M']:.3f}",
        f"λ {lam / lam_janssen:.1f}× Janssen's with μ_wall 0.6 and Jaky's K: the walls carry the weight, their "
        f"friction mobilised to F_wall/F_N = {mobilised:.2f} of 0.6 (pre-stabilisation's wall pushes carry no "
        f"friction; the iterations' own mobilise {mobilised_solve:.2f}), K_eff {k_eff:.2f} against Jaky's "
        f"{k_jaky:.2f}. At the node's defaults the gauge misreads: anchored friction gives M_app/M "
        f"{anchored['apparent'] / anchored['M']:.2f} at 600 spheres (> 1: the walls pull the bed down, since wall "
        "anchors do not follow pre-stabilisation's lift; with anchors shifted by its moves "
        f"{followed['apparent'] / followed['M']:.2f}), and shock propagation 4 gives "
        f"{scaled['apparent'] / scaled['M']:.2f} with frictionless walls (mass scaling does not conserve momentum, "
        "so forces inside a bed are physical only without it)",
        "20 substeps × 4 iterations (a 50-layer column sinks 1.5–1.8 r into itself at 10 × 2), shock propagation "
        "off, substep friction (Macklin), 1 particle per grain",
        time.perf_counter() - t,
        plot,
    )


def _plot_janssen(filled, apparent, sat, smooth):
    plt, fig, ax = _axes()
    m = np.linspace(0, filled.max() * 1.05, 100)
    ax.plot(m, m, ":", color="gray", label="M_app = M (no wall friction)")
    ax.plot(m, sat * (1 - np.exp(-m / sat)), "-", label=f"Janssen fit, M_sat = {sat:.1f} g")
    ax.plot(filled, apparent, "o", label="walls μ 0.6")
    ax.plot([smooth["M"]], [smooth["apparent"]], "s", label="frictionless")
    ax.set_xlabel("filled mass M (g)")
    ax.set_ylabel("apparent mass at the base (g)")
    return _saved(plt, fig, ax, IMAGES / "janssen.png")


def _plot_curve(name, xs, series, xlabel, ylabel):
    plt, fig, ax = _axes()
    for label, ys in series.items():
        ax.plot(xs, ys, "o-", label=label)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    return _saved(plt, fig, ax, IMAGES / f"{name}.png", legend=None)


def write_record(cases: list[Case], quick: bool, total: float, ellipsoids: bool = False) -> None:
    """One JSON line per case into benchmarks/measured/validation.jsonl (``tools/measured_tables.py`` renders the
    table in docs/validation.md)."""
    import json
    import os
    from datetime import datetime

    command = f"python benchmarks/validation.py{' --quick' if quick else ''}{' --ellipsoids' if ellipsoids else ''}"
    date = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = f"{os.getloadavg()[0]:.1f}"
    lines = [
        json.dumps(
            {
                "what": c.name,
                **{f: getattr(c, f) for f in ("setup", "reference", "ours", "error", "knobs")},
                "values": {"seconds": round(c.seconds, 1)},
                "unit": "s",
                "command": command,
                "load": load,
                "date": date,
                "machine": f"{os.cpu_count()} cores",
            }
        )
        for c in cases
    ]
    RECORD.write_text("\n".join(lines) + "\n", encoding="utf-8")


def replace_record(case: Case) -> None:
    """``case``'s line in benchmarks/measured/validation.jsonl measured anew (by ``--squeeze``), the others kept."""
    import json

    keep = [line for line in RECORD.read_text(encoding="utf-8").splitlines() if line.strip()]
    write_record([case], True, case.seconds)
    (fresh,) = [json.loads(line) for line in RECORD.read_text(encoding="utf-8").splitlines()]
    fresh["command"] = "python benchmarks/validation.py --squeeze"
    lines = [json.dumps(fresh) if json.loads(line)["what"] == case.name else line for line in keep]
    RECORD.write_text("".join(line + "\n" for line in lines), encoding="utf-8")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="reduced sizes (CI)")
    parser.add_argument(
        "--ellipsoids", action="store_true", help="with --quick: also the ellipsoid packing (≈ 1 min CPU)"
    )
    parser.add_argument(
        "--squeeze", action="store_true", help="the squeezed grain only: its line in the record is replaced (≈ 1 min)"
    )
    args = parser.parse_args(argv)
    start = time.perf_counter()
    if args.squeeze:
        case = squeeze_case(True, {})
        print(f"{case.name}: {case.ours}  [{case.error}]  {case.seconds:.1f} s")
        replace_record(case)
        return
    cases, figures = run_cases(args.quick, ellipsoids=True if args.ellipsoids else None)
    for c in cases:
        print(f"{c.name}: {c.ours}  [{c.error}]  {c.seconds:.1f} s")
    write_record(cases, args.quick, time.perf_counter() - start, ellipsoids=args.quick and args.ellipsoids)
    print(f"wrote {RECORD.relative_to(REPO)}; python tools/measured_tables.py renders {DOC.relative_to(REPO)}")


if __name__ == "__main__":
    main()
