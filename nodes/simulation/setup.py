"""Aggregate → solver state and back — SPEC §3: clusters per element, colliders as signed distance,
yolks for buoyancy, parameters in solver units (mm, g, s); and the transforms after the run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..values import Aggregate, ParticleState, Placement

from .aggregate import DeformedAggregate
from .clusters import element_cluster, matrix_to_quat
from .collider import free_space_field
from .deformation import element_bends, element_transforms
from .moisture import moisture_scales
from .solver import SolverSettings, XpbdSolver

ADHESION_STIFFNESS = 10.0  # N/m at clumping 1: pulls a 25 mg grain with ≈ 40× its weight per mm of gap


@dataclass
class Simulation:
    solver: XpbdSolver
    aggregate: Aggregate
    local_centre: np.ndarray  # (m, 3) particle centre of mass in each element's local frame
    yolk_local: np.ndarray | None  # (m, 3) yolk centre in the local frame (rows of elements without one unused)


def settings_from_params(effects, params, radius) -> SolverSettings:
    """Table-3 style parameters → solver settings; 'moisture' rescales stiffness, friction, adhesion."""
    scale = moisture_scales(params["water_content"]) if "moisture" in effects else \
        {"stiffness": 1.0, "friction": 1.0, "adhesion": 1.0}
    stiffness = params["stiffness"] * scale["stiffness"]
    adhesion = params["clumping"] * scale["adhesion"] * ADHESION_STIFFNESS
    mu_s = params["static_threshold"] * params["friction"] * scale["friction"]
    return SolverSettings(
        effects=frozenset(effects), substeps=params["substeps"], iterations=params["iterations"], dt=params["dt"],
        gravity=params["gravity"],
        compliance=1.0 / (1000.0 * stiffness) if stiffness > 0 else np.inf,  # N/m → s²/g
        linear_deformation=params["linear_deformation"], quadratic=params["deformation"] == "quadratic",
        bend_compliance=1.0 / (1000.0 * stiffness * params["bend_stiffness"])
        if stiffness * params["bend_stiffness"] > 0 else np.inf,
        mu_s=mu_s, mu_k=mu_s * params["dynamic_scale"],
        capture=params["capture_radius"] * radius,
        adhesion_compliance=1.0 / (1000.0 * adhesion) if adhesion > 0 else np.inf,
        damping=params["damping"], sleep_speed=params["sleep_speed"], speed_clamp=params["speed_clamp"],
        shock_propagation=params["shock_propagation"],
        yolk_accel=params["gravity"] * (params["white_density"] / params["part_density"] - 1.0)
        if "gravity" in effects else 0.0,
    )


def full_placement(aggregate: Aggregate, colliders) -> Placement:
    """G §3.2.1: as many copies of the first element as the placement has, on a regular grid in one
    orientation, stacked above the colliders' (or the placement's) footprint, ready to drop."""
    n = len(aggregate.placement)
    mesh = aggregate.libraries[0].meshes[0]
    size = (mesh.bounds[1] - mesh.bounds[0]) * 1.05
    if colliders:
        lo = np.min([c.bounds[0] for c in colliders], axis=0)
        hi = np.max([c.bounds[1] for c in colliders], axis=0)
    else:
        lo, hi = aggregate.placement.positions.min(axis=0), aggregate.placement.positions.max(axis=0) + size
    centre = 0.5 * (lo + hi)
    span = np.maximum(0.5 * (hi - lo)[:2], size[:2])  # central half of the footprint
    nx, ny = np.maximum(1, (span // size[:2]).astype(int))
    k = np.arange(n)
    ix, iy, iz = k % nx, (k // nx) % ny, k // (nx * ny)
    grid = np.stack([(ix - (nx - 1) / 2) * size[0] + centre[0], (iy - (ny - 1) / 2) * size[1] + centre[1],
                     hi[2] + size[2] * (iz + 1)], axis=1)
    grid -= 0.5 * (mesh.bounds[0] + mesh.bounds[1])
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    return Placement(grid, normals, kinds=np.zeros(n, np.int32), variants=np.zeros(n, np.int32),
                     kind_names=aggregate.placement.kind_names)


def static_obstacles(obstacles, effects):
    """(positions, radii) of the settled particles of other aggregates, or None when none are wired
    or no pair effect (contact, friction, adhesion) would touch them."""
    states = [o for o in (obstacles or []) if len(o)]
    if not states or not {"contact", "friction", "adhesion"} & set(effects):
        return None
    x = np.concatenate([o.positions for o in states])
    r = np.concatenate([o.radii for o in states])
    if not (np.isfinite(x).all() and np.all(r > 0)):
        raise ValueError("obstacles: particle positions must be finite and radii > 0")
    return x, r


def build_simulation(aggregate: Aggregate, colliders, effects, params, obstacles=None, moulds=(),
                     threads: int | None = None) -> Simulation:
    if len(aggregate.placement) == 0:
        raise ValueError("aggregate: the placement is empty; nothing to simulate")
    moulds = list(moulds or [])
    if "collider" in effects and not (colliders or moulds):
        raise ValueError("effect 'collider' is requested but no mesh is wired to input 'colliders' or 'moulds'")
    if params["mode"] == "full" and moulds and "collider" in effects:
        raise ValueError("mode 'full' drops elements in from above, which a closed mould does not let in: "
                         "use mode 'short' with moulds, or an open container on 'colliders'")
    if params["mode"] == "full":
        aggregate = Aggregate(full_placement(aggregate, colliders), aggregate.libraries)
    p = aggregate.placement
    cache = {}
    xs, rs, ws, qs, sizes, local_centre, yolk_local = [], [], [], [], [], [], []
    for i in range(len(p)):
        lib = aggregate.libraries[p.kinds[i]]
        key = (int(p.kinds[i]), int(p.variants[i]) % len(lib))
        if key not in cache:
            cache[key] = element_cluster(lib.meshes[key[1]], params["particles_per_element"])
        cl = cache[key]
        c0 = cl.centres.mean(axis=0)
        xs.append(cl.centres @ p.rotations[i].T + p.positions[i])
        rs.append(cl.radii)
        ws.append(np.full(len(cl.radii), len(cl.radii) / (params["mass"] * 1e-3)))  # mg → g
        qs.append(cl.centres - c0)
        sizes.append(len(cl.radii))
        local_centre.append(c0)
        yolk_local.append(cl.yolk_centre if cl.yolk_centre is not None else np.full(3, np.nan))
    x, r, w, q = (np.concatenate(a) for a in (xs, rs, ws, qs))
    start = np.concatenate([[0], np.cumsum(sizes)])
    settings = settings_from_params(effects, params, float(np.median(r)))
    sdf = None
    if "collider" in effects:
        shapes = colliders + moulds
        lo = np.min([c.bounds[0] for c in shapes] + [x.min(axis=0)], axis=0) - 4 * r.max()
        hi = np.max([c.bounds[1] for c in shapes] + [x.max(axis=0)], axis=0) + 4 * r.max()
        pitch = max(0.5 * r.min(), float((hi - lo).max()) / 192)
        sdf = free_space_field(colliders, moulds, lo, hi, pitch)
    yolk_local = np.array(yolk_local)
    yolks = None
    has_yolk = ~np.isnan(yolk_local[:, 0])
    if "buoyancy" in effects and has_yolk.any():
        owner = np.flatnonzero(has_yolk)
        room, centre = [], []
        for i in owner:
            cl = cache[(int(p.kinds[i]), int(p.variants[i]) % len(aggregate.libraries[p.kinds[i]]))]
            room.append(max(0.0, cl.membrane_radius - cl.yolk_radius))
            centre.append(cl.membrane_centre - local_centre[i])  # membrane centre relative to the cluster's
        yolks = {"x": np.einsum("nij,nj->ni", p.rotations[owner], yolk_local[owner]) + p.positions[owner],
                 "owner": owner.astype(np.int64), "centre": np.array(centre), "room": np.array(room)}
    solver = XpbdSolver(x, r, w, start, q, matrix_to_quat(p.rotations), settings, sdf=sdf, yolks=yolks,
                        obstacles=static_obstacles(obstacles, effects), threads=threads)
    return Simulation(solver, aggregate, np.array(local_centre), yolk_local if yolks is not None else None)


def snapshot_aggregate(sim: Simulation) -> Aggregate:
    """The aggregate as the particles stand now: per-element positions, rotations, deformations,
    bends when the solver ran the quadratic goal (``deformation.element_transforms``,
    ``deformation.element_bends``) and yolk offsets, fitted to the clusters."""
    s = sim.solver
    rotations = s.rotations()
    if s.matching:
        pinv, null = s.aqq_pinv, s.null_proj
    else:
        m = len(s.start) - 1
        pinv, null = np.zeros((m, 3, 3)), np.tile(np.eye(3), (m, 1, 1))
    n = s.n_moving  # static obstacle particles (after n) are not part of the output
    centres = s.centres()
    positions, rotations, deformations = element_transforms(s.x[:n], s.w[:n], s.start, s.q_rest, rotations, centres,
                                                            pinv, null, sim.local_centre)
    bends = None
    if s.matching and s.s.quadratic and s.quadratic_fit[2].any():  # (qt, qpinv, flags): flagged clusters bend
        positions, deformations, bends = element_bends(s.x[:n], s.w[:n], s.start, s.q_rest, rotations, centres,
                                                       positions, deformations, s.quadratic_fit[2], sim.local_centre)
    old = sim.aggregate.placement
    placement = Placement(positions, old.normals, rotations, old.kinds, old.variants, old.p_num, old.offsets,
                          old.overlap, old.kind_names)
    if sim.yolk_local is None:
        return Aggregate(placement, sim.aggregate.libraries, deformations, bends)
    offsets = np.zeros((len(positions), 3))
    y = s.yolks
    owner, local = y["owner"], sim.yolk_local[y["owner"]]  # the yolk's rest centre under its element's map
    rest = np.einsum("nij,njk,nk->ni", deformations[owner], rotations[owner], local)
    if bends is not None:
        rest += np.einsum("nij,njk,nk->ni", rotations[owner], bends[owner], Aggregate.monomials(local))
    offsets[owner] = y["x"] - (positions[owner] + rest)
    return DeformedAggregate(placement, sim.aggregate.libraries, deformations, bends, part_offsets=offsets)


def finish_simulation(sim: Simulation) -> dict:
    """The relaxed aggregate (positions, rotations, deformations, yolk offsets) and the particle state."""
    s, n = sim.solver, sim.solver.n_moving
    particles = ParticleState(s.x[:n].copy(), s.v[:n].copy(), s.r[:n].copy(), s.w[:n].copy(),
                              s.elem[:n].astype(np.int32), s.time)
    return {"aggregate": snapshot_aggregate(sim), "particles": particles}
