"""The ``xpbd`` node: relax a placed aggregate into a resting, touching, slightly squashed pile —
SPEC §3 (G §3.3, XPBD) with shape-matching clusters (SPEC §5). Thin: its parameters become one typed
``settings.XpbdParams``, ``setup`` builds the model, state and solver from it, ``solver.XpbdSolver``
runs frame by frame, and the outputs are typed values.
"""

from __future__ import annotations

import numpy as np

from nodegraph.cost import Cost, CostQuery, Lever, estimated_by
from nodegraph.node import In, Moved, Out, node
from nodegraph.values import Mesh

from ..values import Aggregate, CookedMaterial, ParticleState
from .settings import EFFECTS, PARAMS, XpbdParams, slender_m, solver_settings, xpbd_params
from .step_limits import check_gravity_step, most_pieces, solve_pieces

# particle-iterations per CPU second of a substep's work: what ``expect_cost`` tells before a long run starts (and
# ``--max-minutes`` refuses above), in the node's CPU seconds. `nodegraph run graphs/rice_bowl.yaml --set
# rice_sim.frames=N --output rice_sim --no-rrd --no-cache --yes` (15,424 particles × 10 substeps × 2 iterations,
# kernels already compiled), rice_sim's CPU time from the closing table: N = 60 in 43.0 s (4.3e5), 120 in 88.2 s
# (4.2e5), 240 in 158 s (4.7e5; frames 61–240 at 4.8e5: later frames cost less as grains come to rest); 2 cores,
# load 3.0–5.8, 2026-12-06 17:40–17:49 UTC
PARTICLE_ITERATIONS_PER_SECOND = 4.5e5
# the node's memory at its peak, for the cost estimate before any work (``nodegraph.cost``): its colliders' fields
# and the rest it holds whatever the size, and per simulated particle its model, state and neighbour lists. The
# closing table's peak of rice_sim: 31 MiB at 624 particles (the rice bowl's draft), 117 MiB at 15,424 (full size);
# the onigiri's press 74 MiB at 13,368 (benchmarks/bench_cost.py)
FIXED_BYTES = 25 * 2**20
# CPU seconds of a simulation's setup before its first frame (its colliders' fields, the elements' clusters), which
# its run's own estimate does not count (it is made after them): fixed and per particle, fitted to the rice bowl's,
# the ikura don's and the onigiri's simulations at full size and as drafts (benchmarks/bench_cost.py)
SETUP_SECONDS = 0.5
SETUP_SECONDS_PER_PARTICLE = 1e-4
BYTES_PER_PARTICLE = 6_000
# static obstacle particles (another simulation's, e.g. eggs dropped on settled rice) are hashed with the moving ones
# every substep and give the setup their fields: the ikura don's egg_sim (972 particles, 30 frames) on the rice's
# 11,016 against none, its inputs loaded from the cache in one process, kernels loaded, the least of 3 at 1 and 21
# frames: 3.19 / 3.63 CPU s with them, 2.38 / 2.66 without (egg_sim called alone, NodeSpec.call); 2 cores,
# load 9.7, 2026-12-07
SETUP_SECONDS_PER_OBSTACLE = 7e-5
OBSTACLE_SUBSTEPS_PER_SECOND = 1.3e7


def _solve(
    particles: int, obstacles: int, frames: int, substeps: int, iterations: int, about: str = ""
) -> tuple[float, str]:
    """The frames' CPU seconds (``PARTICLE_ITERATIONS_PER_SECOND``, ``OBSTACLE_SUBSTEPS_PER_SECOND``) and what they
    are, in words: one formula for the estimate before any work and the run's own after its setup."""
    what = f"{frames:,} frames × {substeps} substeps × {iterations} iterations of {about}{particles:,} particles"
    what += f" among {about}{obstacles:,} obstacle particles" if obstacles else ""
    moving = particles * frames * substeps * iterations / PARTICLE_ITERATIONS_PER_SECOND
    return moving + obstacles * frames * substeps / OBSTACLE_SUBSTEPS_PER_SECOND, what


def _step_refused(q: CostQuery) -> tuple[tuple[str, str, bool], ...]:
    """The run's refusal of a step in which gravity alone sinks resting stacks (``step_limits.check_gravity_step``),
    weighed before any work with the elements' smallest inscribed radius for the particles' radii: the particles lie
    inside their elements, so where the elements are alike the run, with its particles' own radii, refuses at least
    what this refuses."""
    r = q.inscribed("aggregate")
    if r is None or not r > 0 or "gravity" not in q.effects:
        return ()
    settings = solver_settings(xpbd_params(**q.params), q.effects, r)
    try:
        check_gravity_step(settings, solve_pieces(settings.gravity * settings.h**2 / r, most_pieces(settings)), r, r)
    except ValueError as refused:
        said = str(refused).removeprefix("substeps: ")
        said += f" (weighed with the elements' smallest inscribed radius, {r:.3g} mm, for the particles')"
        return (("substeps", said, False),)
    return ()


def _cost(q: CostQuery) -> Cost:
    """Particles, CPU seconds and memory from the elements its aggregate carries and its parameters, before any work
    (its run says the same from the particles it made, ``expect_cost``); its levers: the frames that keep it under
    ``--max-minutes``, the particles per element that keep it within the machine's memory (``cost.limit_over``)."""
    elements = q.elements("aggregate")
    if elements is None:
        return Cost()
    p = q.params
    elongation = q.elongation("aggregate")
    m = slender_m(elongation) if p["slender"] and elongation is not None else 1  # as the run's ``slender_factor``
    particles = elements * p["particles_per_element"] * m * m
    obstacles = sum(c.particles for c in q.inputs.get("obstacles", []))  # what the wired simulations simulate
    setup = SETUP_SECONDS + particles * SETUP_SECONDS_PER_PARTICLE + obstacles * SETUP_SECONDS_PER_OBSTACLE
    solve, what = _solve(particles, obstacles, p["frames"], p["substeps"] * m**3, p["iterations"], about="≈ ")
    seconds = setup + solve
    frames = p["frames"]

    def fewer_frames(budget: float) -> str:
        """The frames that keep its seconds within ``budget`` (its setup stays)."""
        kept = max(1, int(frames * (budget - setup) / (seconds - setup)))
        return f"frames ≤ {kept:,} (or fewer elements, substeps or iterations, or a larger --max-minutes)"

    def fewer_particles(budget: float) -> str:
        """The particles per element that keep its memory within ``budget`` bytes."""
        kept = int((budget - FIXED_BYTES) / BYTES_PER_PARTICLE / elements)
        return f"particles_per_element ≤ {kept:,}" if kept >= 1 else "fewer elements (one particle each is over)"

    return Cost(
        elements=elements,
        faces=q.faces("aggregate"),
        particles=particles,
        seconds=seconds,
        memory=FIXED_BYTES + particles * BYTES_PER_PARTICLE,
        what=what,
        time_lever=Lever("frames", fewer_frames),
        memory_lever=Lever("particles_per_element", fewer_particles),
        over=_step_refused(q),
    )


def _check(params):
    problems = []
    if params.get("mode") == "full" and params.get("frames", 0) < 30:
        problems.append(("frames", "mode 'full' drops a packed block from above: give it ≥ 30 frames"))
    return problems


@estimated_by(_cost)
@node(
    "xpbd",
    inputs={
        "aggregate": In(Aggregate, "placed elements (aperiodic placement for mode 'short')"),
        "material": In(
            CookedMaterial,
            "the cooked material (a cooked_rice node, the one the shade node reads): effect 'moisture' scales "
            "stiffness, friction and adhesion by its water content; unwired: the cooked_rice defaults (15 %)",
            optional=True,
        ),
        "colliders": In(Mesh, "watertight container / ground solids (mm)", optional=True, many=True),
        "moulds": In(
            Mesh,
            "watertight shapes the elements must stay inside (onigiri mould, bunny; mm): the "
            "free space is their inside (effect 'collider')",
            optional=True,
            many=True,
        ),
        # particles, not the Aggregate: the settled pile's own collision geometry, no re-clustering
        "obstacles": In(
            ParticleState,
            "settled particles of other aggregates (static, w = 0): contact and "
            "friction, no adhesion bonds; never moved, not in the outputs",
            optional=True,
            many=True,
        ),
    },
    outputs={
        "aggregate": Out(Aggregate, "elements at rest: new positions, rotations, per-element deformations"),
        "particles": Out(ParticleState, "the simulation particles at the last frame"),
    },
    params=PARAMS,
    effects=EFFECTS,
    check=_check,
    moved={"water_content": Moved("material", "water_content", "cooked_rice")},
)
def xpbd(ctx, aggregate, material=None, colliders=None, moulds=None, obstacles=None, **params):
    """XPBD aggregate simulation — SPEC §3: elastic clusters, contact, friction, clumping, containers
    and moulds, buoyant yolks, static obstacle particles (e.g. eggs on settled rice); only the effects in
    ``ctx.effects`` are computed."""
    from .setup import build_simulation, finish_simulation, snapshot_aggregate

    p = XpbdParams(**params)
    sim = build_simulation(
        aggregate, list(colliders or []), ctx.effects, p, obstacles=obstacles, moulds=moulds, material=material
    )
    frames, every, meshes_every = p.frames, p.log_every, p.log_meshes_every
    substeps = sim.solver.settings.substeps  # ``slender``: more than p.substeps
    n_moving = sim.model.n_moving
    ctx.expect_cost(*_solve(n_moving, len(sim.model.r) - n_moving, frames, substeps, p.iterations))
    done = 0
    resumed = ctx.checkpoint.load() if ctx.checkpoint is not None else None
    if resumed is not None:
        done = sim.resume(resumed)
        if ctx.reporter is not None:
            ctx.reporter.info(f"{ctx.node_id}: resuming at frame {done:,} of {frames:,} (checkpoint)")
    elif ctx.rerun.enabled:  # the start, at sim_step 0; the state after frame f is logged at (f + 1)·substeps
        _log_step(ctx, sim, 0, every, meshes_every, snapshot_aggregate)
    with ctx.progress(frames, "frames") as bar:
        bar.advance(done)
        for frame in range(done + 1, frames + 1):
            sim.frame()
            if ctx.rerun.enabled and frame < frames:  # the last frame's meshes are the output's: logged below
                _log_step(ctx, sim, frame, every, meshes_every, snapshot_aggregate)
            if ctx.checkpoint is not None and ctx.checkpoint.due() and frame < frames:
                ctx.checkpoint.save(sim.progress(frame))
            bar.advance()
    out = finish_simulation(sim)
    solves = sim.solver.diagnostics.solves  # per frame, a resumed run's earlier frames too (its checkpoint's)
    extra = sum(solves) - len(solves) * substeps
    if extra and ctx.reporter is not None:  # what the fast particles cost (``step_limits.solve_pieces``)
        ctx.reporter.info(f"{ctx.node_id}: {extra:,} extra solves for particles faster than 1 radius per substep")
    if ctx.rerun.enabled:
        if every:
            _log_particles(ctx, sim, frames * substeps)
        if meshes_every:
            _log_meshes(ctx, out["aggregate"], frames * substeps)
        _log_scalars(ctx, sim.solver.diagnostics, substeps)
    return out


def _log_step(ctx, sim, frame, every, meshes_every, snapshot_aggregate):
    """Particles every ``every`` frames, element meshes every ``meshes_every``, at sim_step frame·substeps."""
    step = frame * sim.solver.settings.substeps
    if every and frame % every == 0:
        _log_particles(ctx, sim, step)
    if meshes_every and frame % meshes_every == 0:
        _log_meshes(ctx, snapshot_aggregate(sim), step)


def _log_particles(ctx, sim, step):
    import rerun as rr

    n = sim.model.n_moving  # static obstacles are another node's output
    keep = slice(None, n, max(1, n // 20000))  # subsample big scenes
    ctx.rerun.set_time("sim_step", step)
    ctx.rerun.log("particles", rr.Points3D(sim.state.x[keep], radii=sim.model.r[keep]))


def _log_meshes(ctx, aggregate, step):
    """The elements at ``step`` as instanced library meshes (a pose each; the meshes once), or, where the
    library cannot be instanced, one world-space mesh."""
    import rerun as rr

    from ..element_poses import log_element_poses

    ctx.rerun.set_time("sim_step", step)
    if not log_element_poses(ctx.rerun, aggregate, static=False):
        mesh = aggregate.combined_mesh()  # never empty: build_simulation refuses that
        vertices, faces = mesh.vertices.astype(np.float32), mesh.faces.astype(np.uint32)
        ctx.rerun.log("elements", rr.Mesh3D(vertex_positions=vertices, triangle_indices=faces))


def _log_scalars(ctx, dg, substeps):
    import rerun as rr

    steps = (np.arange(len(dg.penetration)) + 1) * substeps
    for name, values in (
        ("penetration_over_radius", dg.penetration),
        ("residual", dg.residual),
        ("kinetic_energy", dg.kinetic_energy),
        ("sleeping_share", dg.sleeping),
        ("solves_per_frame", dg.solves),
    ):
        ctx.rerun.send_columns(
            f"scalars/{name}",
            indexes=[rr.TimeColumn("sim_step", sequence=steps)],
            columns=rr.Scalars.columns(scalars=np.asarray(values)),
        )
