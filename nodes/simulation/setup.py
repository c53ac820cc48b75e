"""Aggregate → model, state and solver, and back — SPEC §3: clusters per element, colliders as signed
distance, yolks for buoyancy, the node's parameters as solver settings (mm, g, s); and the element
transforms after the run (SPEC §5).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..values import Aggregate, ParticleState, Placement
from .aggregate import DeformedAggregate
from .buffers import Contacts
from .clusters import element_cluster, matrix_to_quat
from .collider import free_space_field, rigid_into_free_space
from .deformation import element_bends, element_transforms
from .model import Model, Yolks, build_model
from .parting import deep_pairs
from .settings import PAIR_EFFECTS, XpbdParams, slender_m, solver_settings
from .solver import Diagnostics, XpbdSolver
from .state import State

# mm/s: the depenetration speed of a slender run (m > 1) that sets none (``XpbdParams.depenetration_speed``)
SLENDER_DEPENETRATION = 50.0


def slender_factor(mesh) -> int:
    """m ≥ 1: the element's length over its width (its longest and middle extent in its own frame, where the
    library lays the long axis on x) in units of a japonica grain's (``settings.slender_m``), rounded. An indica
    grain (11.1 × 3.7 × 2.6 mm) is 2: a cluster of 8 spheres, each no deeper than the grain is thick, leaves its
    skin up to 0.94 mm outside every sphere, 16 leave 0.59 mm (japonica's 8: 0.47 mm; docs/look.md)."""
    extent = np.sort(np.ptp(np.asarray(mesh.vertices), axis=0))[::-1]
    return slender_m(extent[0] / max(extent[1], 1e-12))


@dataclass
class Simulation:
    """One run of the ``xpbd`` node: the model, its state, the solver stepping it, and what maps the
    particles back onto the aggregate's elements."""

    model: Model
    state: State
    solver: XpbdSolver
    aggregate: Aggregate
    local_centre: np.ndarray  # (m, 3) particle centre of mass in each element's local frame
    yolk_local: np.ndarray | None  # (m, 3) yolk centre in the local frame (rows of elements without one unused)

    def frame(self) -> None:
        """One frame of the solver on the state (``XpbdSolver.frame``)."""
        self.solver.frame(self.state)

    def progress(self, frames_done: int) -> SimulationProgress:
        """What a resumed run needs to go on bit for bit: the state, the Verlet lists with their build
        positions (a fresh build would change the contacts' order), the diagnostics so far."""
        return SimulationProgress(frames_done, self.state, self.solver.contacts, self.solver.diagnostics)

    def resume(self, progress: SimulationProgress) -> int:
        """Continue from ``progress`` (writable arrays); returns the frames already done."""
        self.state = progress.state
        self.solver.contacts = progress.contacts
        self.solver.diagnostics = progress.diagnostics
        return progress.frames_done


@dataclass(eq=False)
class SimulationProgress:
    """A checkpoint of the ``xpbd`` node at a frame boundary (``Simulation.progress``)."""

    frames_done: int
    state: State
    contacts: Contacts | None
    diagnostics: Diagnostics


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
    grid = np.stack(
        [
            (ix - (nx - 1) / 2) * size[0] + centre[0],
            (iy - (ny - 1) / 2) * size[1] + centre[1],
            hi[2] + size[2] * (iz + 1),
        ],
        axis=1,
    )
    grid -= 0.5 * (mesh.bounds[0] + mesh.bounds[1])
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    return Placement(
        grid,
        normals,
        kinds=np.zeros(n, np.int32),
        variants=np.zeros(n, np.int32),
        kind_names=aggregate.placement.kind_names,
    )


def static_obstacles(obstacles, effects):
    """(positions, radii) of the settled particles of other aggregates, or None when none are wired
    or no pair effect (contact, friction, adhesion) would touch them."""
    states = [o for o in (obstacles or []) if len(o)]
    if not states or not PAIR_EFFECTS & set(effects):
        return None
    x = np.concatenate([o.positions for o in states])
    r = np.concatenate([o.radii for o in states])
    if not (np.isfinite(x).all() and np.all(r > 0)):
        raise ValueError("obstacles: particle positions must be finite and radii > 0")
    return x, r


# particles of other elements a particle may start touching, on average: the main job's rice and eggs start with
# 3.2 and 2.7 (at most 19 and 12), the drafts of the rice bowl, onigiri and sushi with 1.6–6.7 (at most 20);
# 33,874 eggs placed 0.6 mm apart started with ≈ 2,300, 310 million pairs, and the run was killed for memory
# (23.7 GB) before its first frame
MAX_START_CONTACTS = 200
SAMPLE = 2000  # particles sampled for the estimate


def refuse_crowding(x: np.ndarray, r: np.ndarray, start: np.ndarray) -> None:
    """Refuse elements that start inside one another by the hundred, before the contact lists are allocated:
    the mean count of other elements' particles within touching distance of a particle, from a sample."""
    from scipy.spatial import cKDTree

    n = len(x)
    if n < 2:
        return
    rng = np.random.default_rng(0)
    sample = rng.choice(n, min(n, SAMPLE), replace=False)
    within = cKDTree(x).query_ball_point(x[sample], 2.0 * float(r.max()), return_length=True)
    own = np.diff(start)[np.searchsorted(start, sample, side="right") - 1]
    mean = float(np.mean(np.maximum(within - own, 0)))
    if mean <= MAX_START_CONTACTS:
        return
    elements = len(start) - 1
    pairs = mean * n / 2
    raise ValueError(
        f"its {elements:,} elements start inside one another: each particle touches ≈ {mean:,.0f} particles of "
        f"other elements (≈ {pairs / 1e6:,.0f} million contact pairs, ≈ {pairs * 2 * 72 / 2**30:,.1f} GiB of "
        f"contact lists); allowed: ≤ {MAX_START_CONTACTS} each. The placement that makes the aggregate spaces them "
        "far below their size: raise its r (eggs: r ≥ their radius), or refine and cull the overlaps before the "
        "simulation"
    )


def build_simulation(
    aggregate: Aggregate,
    colliders,
    effects,
    params: XpbdParams,
    obstacles=None,
    moulds=(),
    threads: int | None = None,
    material=None,
) -> Simulation:
    """Clusters per element (``element_cluster``), the free-space field of the colliders and moulds
    with effect 'collider', yolks with 'buoyancy', static obstacles with a pair effect; the model,
    its initial state and a solver with the settings of ``params`` and the cooked ``material``'s moisture
    factors (``solver_settings``; None: the cooked_rice defaults)."""
    if len(aggregate.placement) == 0:
        raise ValueError("aggregate: the placement is empty; nothing to simulate")
    moulds = list(moulds or [])
    if "collider" in effects and not (colliders or moulds):
        raise ValueError("effect 'collider' is requested but no mesh is wired to input 'colliders' or 'moulds'")
    if params.mode == "full" and moulds and "collider" in effects:
        raise ValueError(
            "mode 'full' drops elements in from above, which a closed mould does not let in: "
            "use mode 'short' with moulds, or an open container on 'colliders'"
        )
    if params.mode == "full":
        aggregate = Aggregate(full_placement(aggregate, colliders), aggregate.libraries)
    p = aggregate.placement
    cache = {}
    slender = 1  # the largest ``slender_factor`` of the elements (``params.slender``)
    xs, rs, ws, qs, sizes, local_centre, yolk_local = [], [], [], [], [], [], []
    for i in range(len(p)):
        lib = aggregate.libraries[p.kinds[i]]
        key = (int(p.kinds[i]), int(p.variants[i]) % len(lib))
        if key not in cache:
            m = slender_factor(lib.meshes[key[1]]) if params.slender else 1
            slender = max(slender, m)
            cache[key] = element_cluster(
                lib.meshes[key[1]],
                m * m * params.particles_per_element,
                quadratic=params.deformation == "quadratic",
                layers=params.particle_layers,
            )
        cl = cache[key]
        c0 = cl.centres.mean(axis=0)
        xs.append(cl.centres @ p.rotations[i].T + p.positions[i])
        rs.append(cl.radii)
        ws.append(np.full(len(cl.radii), len(cl.radii) / (params.mass * 1e-3)))  # mg → g
        qs.append(cl.centres - c0)
        sizes.append(len(cl.radii))
        local_centre.append(c0)
        yolk_local.append(cl.yolk_centre if cl.yolk_centre is not None else np.full(3, np.nan))
    x, r, w, q = (np.concatenate(a) for a in (xs, rs, ws, qs))
    radius = float(np.median(r))  # the unit of the capture radius and of the contact offset
    r = r + params.contact_offset * radius
    start = np.concatenate([[0], np.cumsum(sizes)])
    # a cluster of m× the particles gives way to its contacts more slowly per substep (shape matching shares each
    # correction over its particles), and long grains jam: the run settles them at m³ × the substeps, where the speed
    # the constraints add is capped (SLENDER_DEPENETRATION unless given: 16 × 80 threw 38 of 60 indica grains out of
    # a reduced bowl at up to 1,226 mm/s; docs/look.md)
    speed = params.depenetration_speed or (SLENDER_DEPENETRATION if slender > 1 else 0.0)
    stepped = dataclasses.replace(params, substeps=params.substeps * slender**3, depenetration_speed=speed)
    # a glued run keeps a handed-on state's overlaps in its regions' goal, so there is nothing to bound (bounded, a
    # pressed block set down glued rocked at 2.2 mm/s where it rests at ≤ 1.2: tests/simulation/test_glue.py)
    handed = aggregate.deformations is not None and params.glue == 0
    settings = solver_settings(stepped, effects, radius, material, handed=handed)
    sdf = None
    if "collider" in effects:
        shapes = colliders + moulds
        lo = np.min([c.bounds[0] for c in shapes] + [x.min(axis=0)], axis=0) - 4 * r.max()
        hi = np.max([c.bounds[1] for c in shapes] + [x.max(axis=0)], axis=0) + 4 * r.max()
        pitch = max(0.5 * r.min(), float((hi - lo).max()) / 192)
        sdf = free_space_field(colliders, moulds, lo, hi, pitch, float(r.max()))
        if params.rigid_start:
            rigid_into_free_space(x, r, start, *sdf)
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
        yolks = Yolks(
            np.einsum("nij,nj->ni", p.rotations[owner], yolk_local[owner]) + p.positions[owner],
            owner.astype(np.int64),
            np.array(centre),
            np.array(room),
        )
    if PAIR_EFFECTS & set(effects):
        refuse_crowding(x, r, start)
    model = build_model(
        x,
        r,
        w,
        start,
        q,
        matrix_to_quat(p.rotations),
        settings,
        sdf=sdf,
        yolks=yolks,
        obstacles=static_obstacles(obstacles, effects),
    )
    solver = XpbdSolver(model, settings, threads=threads)
    if solver.contacts is not None and "friction" in effects and aggregate.deformations is None:
        # placed, not handed on: pairs placed inside one another part without friction (``parting``)
        solver.contacts.deep = deep_pairs(model.x0, model.r, model.elem, model.n_moving)
    return Simulation(
        model,
        model.state(),
        solver,
        aggregate,
        np.array(local_centre),
        yolk_local if yolks is not None else None,
    )


def snapshot_aggregate(sim: Simulation) -> Aggregate:
    """The aggregate as the particles stand now: per-element positions, rotations, deformations,
    bends when the solver ran the quadratic goal (``deformation.element_transforms``,
    ``deformation.element_bends``) and yolk offsets, fitted to the clusters."""
    m, st = sim.model, sim.state
    rotations = st.rotations()
    if m.moments is not None:
        pinv, null = m.moments.aqq_pinv, m.moments.null_proj
    else:
        pinv, null = np.zeros((m.elements, 3, 3)), np.tile(np.eye(3), (m.elements, 1, 1))
    n = m.n_moving  # static obstacle particles (after n) are not part of the output
    x, w = st.x[:n], m.w[:n]
    centres = m.centres(st.x)
    positions, rotations, deformations = element_transforms(
        x, w, m.start, m.q_rest, rotations, centres, pinv, null, sim.local_centre
    )
    bends = None
    if m.quadratic is not None and m.quadratic.flags.any():  # flagged clusters bend
        positions, deformations, bends = element_bends(
            x, w, m.start, m.q_rest, rotations, centres, positions, deformations, m.quadratic.flags, sim.local_centre
        )
    placement = dataclasses.replace(sim.aggregate.placement, positions=positions, rotations=rotations)
    if sim.yolk_local is None:
        return Aggregate(placement, sim.aggregate.libraries, deformations, bends)
    offsets = np.zeros((len(positions), 3))
    owner = m.yolks.owner
    local = sim.yolk_local[owner]  # the yolk's rest centre under its element's map
    rest = np.einsum("nij,njk,nk->ni", deformations[owner], rotations[owner], local)
    if bends is not None:
        rest += np.einsum("nij,njk,nk->ni", rotations[owner], bends[owner], Aggregate.monomials(local))
    offsets[owner] = st.yolks.x - (positions[owner] + rest)
    return DeformedAggregate(placement, sim.aggregate.libraries, deformations, bends, part_offsets=offsets)


def finish_simulation(sim: Simulation) -> dict:
    """The relaxed aggregate (positions, rotations, deformations, yolk offsets) and the particle state."""
    m, st, n = sim.model, sim.state, sim.model.n_moving
    particles = ParticleState(
        st.x[:n].copy(), st.v[:n].copy(), m.r[:n].copy(), m.w[:n].copy(), m.elem[:n].astype(np.int32), st.time
    )
    return {"aggregate": snapshot_aggregate(sim), "particles": particles}
