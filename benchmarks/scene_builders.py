"""Scenes for the solver's tests, benchmarks and scripts, built directly in Python (no placement nodes
needed): ellipsoid rice grains, ikura eggs with a yolk, a bowl and a ground slab as watertight solids,
grains on a jittered grid inside the bowl, and a small shaded-food scene. Dev-only (beside the benchmarks, not the
shipped package): tests and benchmarks import it, nothing in ``nodes`` does."""

from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from nodegraph.values import Mesh
from nodes.values import Aggregate, ElementLibrary, Placement


def grain_mesh(length=5.0, width=3.0, height=2.5, name="grain") -> Mesh:
    """A cooked japonica grain as an ellipsoid, mm."""
    sphere = trimesh.creation.icosphere(subdivisions=2)
    return Mesh.from_trimesh(
        trimesh.Trimesh(sphere.vertices * [length / 2, width / 2, height / 2], sphere.faces), name=name
    )


def long_grain(length=12.0, thickness=5.0) -> Mesh:
    """A long ellipsoid grain, mm: several particles along its axis, so its cluster can bend (SPEC §5)."""
    sphere = trimesh.creation.icosphere(subdivisions=3)
    scale = [length / 2, thickness / 2, thickness / 2]
    return Mesh.from_trimesh(trimesh.Trimesh(sphere.vertices * scale, sphere.faces), name="long")


def ikura_mesh(radius=3.5, lipid=0.145) -> Mesh:
    """Egg sphere (parts 0) with a yolk sphere inside (parts 1), r_yolk = r·∛L (SPEC §1, G eq. 10)."""
    egg = trimesh.creation.icosphere(subdivisions=2, radius=radius)
    yolk = trimesh.creation.icosphere(subdivisions=1, radius=radius * lipid ** (1 / 3))
    both = trimesh.util.concatenate([egg, yolk])
    parts = np.r_[np.zeros(len(egg.faces)), np.ones(len(yolk.faces))]
    return Mesh(both.vertices, both.faces, parts=parts, name="ikura")


def bowl_mesh(radius=60.0, wall=3.0, rim=0.35, segments=96) -> Mesh:
    """A hemispherical bowl, a watertight solid: the shell between two spheres below z = rim·radius."""
    import manifold3d as mf

    shell = mf.Manifold.sphere(radius, segments) - mf.Manifold.sphere(radius - wall, segments)
    return manifold_mesh(shell.trim_by_plane((0.0, 0.0, -1.0), -rim * radius), "bowl")


def manifold_mesh(manifold, name: str) -> Mesh:
    """A manifold3d solid as a ``Mesh``."""
    m = manifold.to_mesh()
    return Mesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), name=name)


def box_mesh(lo, hi, name="box") -> Mesh:
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    box = trimesh.creation.box(extents=hi - lo)
    return Mesh(box.vertices + 0.5 * (lo + hi), box.faces, name=name)


def open_box(inner, wall=1.0, height=None) -> list[Mesh]:
    """Floor and four walls (each a watertight slab) of an open box whose inside is [0, inner]²×[0, height]."""
    h = inner if height is None else height
    return [
        box_mesh([-wall, -wall, -wall], [inner + wall, inner + wall, 0.0], "floor"),
        box_mesh([-wall, -wall, 0.0], [0.0, inner + wall, h], "wall_x0"),
        box_mesh([inner, -wall, 0.0], [inner + wall, inner + wall, h], "wall_x1"),
        box_mesh([0.0, -wall, 0.0], [inner, 0.0, h], "wall_y0"),
        box_mesh([0.0, inner, 0.0], [inner, inner + wall, h], "wall_y1"),
    ]


def bowl_placement(n, spacing=4.0, radius=60.0, wall=3.0, seed=0, jitter=0.3) -> Placement:
    """n grain positions on a jittered grid inside the bowl cavity, lowest first; random rotations."""
    rng = np.random.default_rng(seed)
    inner = radius - wall - spacing
    axis = np.arange(-inner, inner + spacing, spacing)
    grid = np.stack(np.meshgrid(axis, axis, np.arange(-inner, 4 * inner, spacing), indexing="ij"), -1).reshape(-1, 3)
    xy = np.linalg.norm(grid[:, :2], axis=1)
    inside = (np.linalg.norm(grid, axis=1) < inner) | ((grid[:, 2] >= 0) & (xy < inner))
    grid = grid[inside]
    grid = grid[np.lexsort((grid[:, 0], grid[:, 1], grid[:, 2]))][:n]
    if len(grid) < n:
        raise ValueError(f"bowl holds only {len(grid)} grid points at spacing {spacing}")
    positions = grid + rng.uniform(-jitter, jitter, grid.shape)
    rotations = Rotation.random(n, random_state=seed).as_matrix()
    return Placement(
        positions,
        np.tile([0.0, 0.0, 1.0], (n, 1)),
        rotations,
        variants=rng.integers(0, 4, n).astype(np.int32),
        kind_names=("japonica",),
    )


def rice_library(count=4, seed=0) -> ElementLibrary:
    rng = np.random.default_rng(seed)
    meshes = [
        grain_mesh(*(np.array([5.0, 3.0, 2.5]) * rng.uniform(0.9, 1.1, 3)), name=f"grain{k}") for k in range(count)
    ]
    return ElementLibrary("japonica", meshes)


def rice_bowl(n=200, seed=0, spacing=4.0):
    """(aggregate, colliders) for n grains in a bowl of radius 60 mm."""
    placement = bowl_placement(n, spacing=spacing, seed=seed)
    return Aggregate(placement, (rice_library(seed=seed),)), [bowl_mesh()]


def ikura_don(n=310, seed=0, radius=3.5):
    """(aggregate, colliders): n eggs on a jittered grid in a bowl (ikura on rice, rice left out)."""
    rng = np.random.default_rng(seed)
    placement = bowl_placement(n, spacing=2 * radius + 0.2, seed=seed, jitter=0.1)
    placement = Placement(
        placement.positions,
        placement.normals,
        placement.rotations,
        variants=np.zeros(n, np.int32),
        kind_names=("ikura",),
    )
    del rng
    return Aggregate(placement, (ElementLibrary("ikura", [ikura_mesh(radius)]),)), [bowl_mesh()]


@dataclass
class SolverRun:
    """A model, the state a solver steps, and the solver: ``setup.Simulation`` without an aggregate."""

    model: object
    state: object
    solver: object

    def frame(self) -> None:
        self.solver.frame(self.state)

    def step(self) -> float:
        """One solve in place, Newton's way: ``step(state_in, state_out, control, contacts, dt)``."""
        s = self.solver
        return s.step(self.state, self.state, s.default_control, s.contacts, s.coefficients.h)

    def centres(self) -> np.ndarray:
        return self.model.centres(self.state.x)


def solver_run(x, r, w, start, q_rest, quats, settings, dispatch=None, threads=None, **model_options) -> SolverRun:
    """A solver on particles in clusters (``model.build_model``; ``model_options``: sdf, yolks, obstacles)."""
    from nodes.simulation.model import build_model
    from nodes.simulation.solver import XpbdSolver

    model = build_model(x, r, w, start, q_rest, quats, settings, **model_options)
    return SolverRun(model, model.state(), XpbdSolver(model, settings, dispatch=dispatch, threads=threads))


def stack_column(layers=8, radius=1.0, per_side=2, mass=25.0, gap=0.1, **settings):
    """The stack test of the accuracy benchmark (issue 6): ``layers`` cube elements, each per_side³
    particles of radius r touching on a grid of pitch 2r, in one vertical column over a ground slab
    (top face z = 0), dropped from ``gap``·r apart (the lowest ``gap``·r above the ground).

    Rigid stacking has an exact rest: particle layer j at z = (2j+1)·r, so element k is centred at
    z = per_side·(2k+1)·r over x = y = 0. ``settings``: xpbd node parameters (node units) over the node's
    defaults (stiffness 2,000 N/m, friction μs 0.6, μk 0.42, shock propagation 4) with β = 0, no sleeping and
    no damping: rigid elements (sag under the stack's weight < 1 µm) and nothing that hides an energy gain.
    Returns (``SolverRun``, rest element centres (layers, 3), element mass in g).
    """
    from nodes.simulation.collider import signed_distance_grid
    from nodes.simulation.settings import solver_settings_for

    side = 2.0 * radius * per_side
    grid = (np.stack(np.meshgrid(*[np.arange(per_side)] * 3, indexing="ij"), -1).reshape(-1, 3) + 0.5) * 2 * radius
    q = grid - grid.mean(axis=0)
    rest = np.array([[0.0, 0.0, side * (k + 0.5)] for k in range(layers)])
    lift = gap * radius * np.arange(1, layers + 1)
    x = np.concatenate([q + c + [0.0, 0.0, dz] for c, dz in zip(rest, lift)])
    n_el = len(q)
    # a thick slab (2·layers·side deep) and a grid around all of it: a stack that sinks at coarse
    # settings shows as penetration instead of falling out of the collider's reach
    depth = 2.0 * layers * side
    ground = box_mesh([-2 * side, -2 * side, -depth - side], [2 * side, 2 * side, 0.0], "ground")
    top = rest[-1, 2] + lift[-1] + side
    sdf = signed_distance_grid([ground], np.array([-side, -side, -depth]), np.array([side, side, top]), radius / 2)
    # the xpbd node's defaults (stiffness 2,000 N/m, μs 0.6, μk 0.42, shock propagation 4) but β = 0 (rigid elements)
    # and no sleeping: the accuracy benchmark measures the solve's rest error, which a stack put to sleep would freeze
    options = dict(linear_deformation=0.0, sleep_speed=0.0)
    options.update(settings)
    run = solver_run(
        x,
        np.full(len(x), radius),
        np.full(len(x), n_el / (mass * 1e-3)),
        np.arange(layers + 1) * n_el,
        np.tile(q, (layers, 1)),
        np.tile([1.0, 0, 0, 0], (layers, 1)),
        solver_settings_for(frozenset({"gravity", "contact", "friction", "collider"}), radius, **options),
        sdf=sdf,
    )
    return run, rest, mass * 1e-3


def mechanical_energy(run) -> float:
    """E = ½ Σ m|v|² + Σ m g z over the moving particles (g·mm²/s², z from the solver's origin) of a
    ``SolverRun`` or ``setup.Simulation``."""
    from nodes.simulation.integrate import kinetic_energy

    n, settings = run.model.n_moving, run.solver.settings
    x, v, w = run.state.x[:n], run.state.v[:n], run.model.w[:n]
    moving = w > 0
    gravity = settings.gravity if "gravity" in settings.effects else 0.0
    return float(kinetic_energy(v, w) + gravity * np.sum(x[moving, 2] / w[moving]))


def energy_drift(energies, mass, gravity, radius) -> tuple[float, float]:
    """Energy drift of a run that should be at rest over its last third (issue 6, accuracy table).

    With E_k = ``mechanical_energy`` after frame k, k = 1…T, and the window W = frames k0 = T − ⌊T/3⌋ … T:
    drift = (E_T − E_k0) / (M g r) and rise = max_{k ∈ W} (E_k − E_k0) / (M g r), M the moving mass and
    r the particle radius: energy as the lift of the whole mass, in radii. A resting scene must not
    gain energy (rise ≈ 0, drift ≤ 0); a pile still settling or sinking shows drift < 0.
    (The solver's velocities of a resting contact are (x − x_prev)/h over the pre-stabilised start, not
    zero, so KE at rest is a small constant; it cancels in the differences.)
    """
    e = np.asarray(energies, float)
    k0 = -(len(e) // 3) - 1
    unit = mass * gravity * radius
    return float((e[-1] - e[k0]) / unit), float((e[k0:] - e[k0]).max() / unit)


def small_food_scene() -> dict:
    """Shade's inputs for a small synthetic dish: 16 capsule grains, three ikura eggs (membrane + yolk parts)
    and a bowl — what the shading/export tests and the preview benchmark's quick mode render."""
    from nodes.elements import base_mesh
    from nodes.shapes import shape

    bowl = shape.call(kind="bowl", size=12.0, depth=8.0, mound=2.0, resolution=2)
    egg = base_mesh.call(shape="ikura", subdivisions=1)
    grain = Mesh.from_trimesh(trimesh.creation.capsule(height=3.0, radius=1.0, count=[8, 8]))
    g = np.linspace(-6, 6, 4)
    xy = np.array([(x, y) for x in g for y in g])
    rice = Aggregate(
        Placement(np.c_[xy, np.full(len(xy), -3.0)], np.tile([0, 0, 1.0], (len(xy), 1)), kind_names=("japonica",)),
        (ElementLibrary("japonica", (grain,)),),
    )
    eggs = Aggregate(
        Placement([[0, 0, 0.5], [3, 0, 0.5], [-3, 1, 0.5]], np.tile([0, 0, 1.0], (3, 1)), kind_names=("ikura",)),
        (ElementLibrary("ikura", (egg,)),),
    )
    return {"aggregates": [rice, eggs], "scenery": [bowl["container"]]}


GLUE_EFFECTS = frozenset({"gravity", "contact", "friction", "adhesion", "collider", "damping"})


def pressed_block(nx=3, ny=3, nz=10, squeeze=0.8, seed=2, press_frames=10):
    """(aggregate, colliders): a tall block of randomly turned grains set on a grid a little tighter than the grains
    (pressed: they overlap), relaxed for ``press_frames`` without gravity as the recipes' press relaxes them in
    their mould, standing on a ground slab: sticky rice ready to be set down (``glue``; tests and validation)."""
    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.setup import build_simulation, finish_simulation
    from nodes.simulation.xpbd import xpbd

    size = np.full(3, 4.0 * squeeze)
    ix, iy, iz = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    grid = np.stack([ix.ravel(), iy.ravel(), iz.ravel()], axis=1) * size
    grid[:, :2] -= 0.5 * size[:2] * [nx - 1, ny - 1]
    grid[:, 2] += 2.6
    n = len(grid)
    turns = Rotation.random(n, random_state=seed).as_matrix()
    placement = Placement(
        grid, np.tile([0.0, 0.0, 1.0], (n, 1)), turns, kinds=np.zeros(n, np.int32), variants=np.arange(n) % 4
    )
    colliders = [box_mesh([-40, -40, -4], [40, 40, 0], name="ground")]
    params = XpbdParams(**xpbd.resolve_params({"frames": press_frames}))
    press = build_simulation(
        Aggregate(placement, (rice_library(seed=1),)), colliders, GLUE_EFFECTS - {"gravity"}, params
    )
    for _ in range(press_frames):
        press.frame()
    return finish_simulation(press)["aggregate"], colliders


def block_heights(block, glue, frames=40, **given):
    """Per frame, the particles' height over the height at the start of ``block`` (``pressed_block``) set down
    under gravity with ``glue`` and the xpbd parameters ``given``; and the simulation."""
    from nodes.simulation.settings import XpbdParams
    from nodes.simulation.setup import build_simulation
    from nodes.simulation.xpbd import xpbd

    aggregate, colliders = block
    p = XpbdParams(**xpbd.resolve_params({"frames": frames, "glue": glue, "clumping": 0.5, **given}))
    sim = build_simulation(aggregate, colliders, GLUE_EFFECTS, p)
    start = np.ptp(sim.state.x[: sim.model.n_moving, 2])
    kept = []
    for _ in range(frames):
        sim.frame()
        kept.append(np.ptp(sim.state.x[: sim.model.n_moving, 2]) / start)
    return np.array(kept), sim
