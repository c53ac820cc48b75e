"""The ``xpbd`` node: relax a placed aggregate into a resting, touching, slightly squashed pile —
SPEC §3 (G §3.3, XPBD) with shape-matching clusters (SPEC §5). Thin: its parameters become one typed
``settings.XpbdParams``, ``setup`` builds the model, state and solver from it, ``solver.XpbdSolver``
runs frame by frame, and the outputs are typed values.
"""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Moved, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh

from ..values import Aggregate, CookedMaterial, ParticleState
from .settings import EFFECTS, XpbdParams

# particle-iterations per second of a substep's work (10 substeps × 2 iterations of a 2,000-grain bowl,
# 16,000 particles, 60 frames in 7.3 s on 2 cores: 2.6e6; ``frames: 100000`` of ikura don's rice took
# 42 min, 2.4e6): what ``expect_cost`` tells before a long run starts, a rough figure by design
PARTICLE_ITERATIONS_PER_SECOND = 2.0e6


def _check(params):
    problems = []
    if params.get("mode") == "full" and params.get("frames", 0) < 30:
        problems.append(("frames", "mode 'full' drops a packed block from above: give it ≥ 30 frames"))
    return problems


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
    params={
        "mode": Param(
            str,
            "short",
            "short: relax the given placement; full: drop identical elements "
            "packed on a regular grid in one orientation (G §3.2.1)",
            choices=("short", "full"),
        ),
        "frames": Param(int, 60, "frames to simulate", range=(1, 100000), units="frames"),
        "dt": Param(float, 1 / 60, "frame duration", range=(1e-4, 1.0), units="s"),
        # 10 × 2 from the accuracy sweeps (bench_xpbd.py --only accuracy: 150-grain bowl, 8-cube stack):
        # on the stack each doubling of substeps cuts the rest error ≈ 4×, of iterations ≈ 2×; 10 × 2
        # is on the bowl's front and rests the stack within 0.19 r, gaining no energy; settings with
        # few substeps and many iterations win on the resting stack but let the bowl's drop sink in
        # (1 × 8: 1.07 r). The 2,000-grain bowl runs in ≈ 8.5 s of its 30 s budget at 10 × 2.
        # Re-checked in CPU time (benchmarks/bench_solver_default.py, docs/accuracy.md): at equal passes a substep
        # costs more than an iteration (20 × 1: 1.2–1.4× the CPU, for half the stack's rest error); no setting of
        # 16–20 passes is better on every error at no more CPU, so 10 × 2 stays.
        "substeps": Param(
            int,
            10,
            "XPBD substeps per frame (accuracy: see the accuracy benchmark); a run is refused when gravity's "
            "step g·h² exceeds iterations/4 × the median particle radius (resting stacks would sink past 1 r)",
            range=(1, 256),
        ),
        "iterations": Param(int, 2, "constraint iterations per substep", range=(1, 64)),
        # 8 from `nodegraph sweep graphs/sweeps/rice_bowl_particles.yaml` (≈ 340 grains, covering clusters, p95 / max
        # mesh overlap in grain lengths after flatten_contacts; straight after the run): 4 → 0.022 / 0.151 (0.187 /
        # 0.244), 8 → 0.015 / 0.044 (0.144 / 0.244) in 15.8 s, 16 → 0.011 / 0.089 (0.105 / 0.153) in 16.3 s, 32 →
        # 0.011 / 0.026 (0.101 / 0.163) in 19.4 s. 8 is on the time–metric Pareto front of every metric and meets
        # issue 17's 0.03 / 0.10 after the flattening.
        "particles_per_element": Param(
            int, 8, "particles per element cluster (G Table 3 'number of points')", range=(1, 64)
        ),
        "slender": Param(
            bool,
            False,
            "clusters sized to the element's cross-section: an element m times as elongated as a japonica grain "
            "(length / width over 5/3, rounded, ≥ 1; indica 2) gets m² × particles_per_element particles, and the run "
            "m³ × the substeps (a cluster of more particles gives way to its contacts more slowly per substep), "
            "with a depenetration speed (50 mm/s unless set)",
        ),
        "rigid_start": Param(
            bool,
            False,
            "move each element whole into the containers' free space before the run where it reaches through a wall "
            "(a long grain near a bowl's rim): else its particles are pushed out on both sides and the cluster is torn",
        ),
        # 0.1: the dry japonica bowl's exported skin 0.133 → 0.078 (packing 0.76 → 0.66); docs/look.md
        "contact_offset": Param(
            float,
            0.0,
            "added to every particle's radius, in median particle radii: a cluster's spheres sit inside the element "
            "and leave its surface uncovered between them, so touching clusters let the meshes nest into each other "
            "(deep dents after the run); the offset keeps them apart by up to twice as much where the cover is tight",
            range=(0.0, 0.5),
            units="radii",
        ),
        "mass": Param(float, 25.0, "mass of one element (G Table 3)", range=(1e-3, 1000.0), units="mg"),
        "stiffness": Param(
            float,
            2000.0,
            "shape-matching stiffness, compliance = 1/stiffness; 0 lets a cluster fall apart",
            range=(0.0, 100000.0),
            units="N/m",
        ),
        "linear_deformation": Param(
            float,
            0.3,
            "β: share of the volume-preserving linear fit in the goal (SPEC §5, U eq. 3.19); 0 = rigid goal",
            range=(0.0, 1.0),
        ),
        "deformation": Param(
            str,
            "linear",
            "goal of the β share: linear (A) or quadratic (Ã, 3×9: also bends "
            "and twists, SPEC §5); clusters with < 10 particles or collinear/planar ones stay "
            "linear",
            choices=("linear", "quadratic"),
        ),
        "bend_stiffness": Param(
            float,
            0.0,
            "bend constraints along the long axis of elongated grains (G: 10 for "
            "rice): stiffness of each chain triple's midpoint offset, in units of the shape-"
            "matching stiffness; 0 = none",
            range=(0.0, 10.0),
        ),
        "damping": Param(float, 0.1, "velocity fraction removed per 1/60 s (effect 'damping')", range=(0.0, 1.0)),
        "friction": Param(float, 1.0, "multiplier on both friction coefficients (effect 'friction')", range=(0.0, 1.0)),
        "static_threshold": Param(float, 0.6, "μs, static friction coefficient (Houdini's reading)", range=(0.0, 1.0)),
        "dynamic_scale": Param(float, 0.7, "μk / μs", range=(0.0, 1.0)),
        # substep by default until the bounds of the tests it moves are re-measured (docs/validation.md)
        "friction_model": Param(
            str,
            "anchored",
            "anchored: static friction restores the slip since the contact began sticking, against the normal "
            "load the contact carried this substep (rice heaps rest at 30–40°, docs/validation.md); substep: it "
            "holds each substep's slip only (Macklin et al. 2014; heaps creep flat)",
            choices=("substep", "anchored"),
        ),
        "capture_radius": Param(
            float,
            0.2,
            "adhesion reach beyond contact, in particle radii (effect 'adhesion')",
            range=(0.0, 1.0),
            units="radii",
        ),
        "clumping": Param(
            float, 0.3, "adhesion strength (breakable bonds within the capture radius)", range=(0.0, 1.0)
        ),
        "glue": Param(
            float,
            0.0,
            "glued grains (pressed sticky rice, effect 'adhesion'): grains within the capture radius of each other "
            "at the start keep their places in each grain's neighbourhood (lattice shape matching), this share of "
            "the way per iteration, until one stands a particle radius from its place (the paste tears); "
            "stiff piles need substeps (an onigiri keeps 98 % of its height at 30); 0 = none",
            range=(0.0, 1.0),
        ),
        "sleep_speed": Param(
            float,
            2.0,
            "elements slower than this are put to rest each substep (0 = never)",
            range=(0.0, 1000.0),
            units="mm/s",
        ),
        "shock_propagation": Param(
            float,
            4.0,
            "contact mass ratio of a particle to one a diameter above it "
            "(Macklin et al. 2014 mass scaling): carries a tall pile's weight down in few "
            "iterations; 1 = off (a 2,000-sphere pile then sinks to 2 r of overlap)",
            range=(1.0, 1000.0),
        ),
        "speed_clamp": Param(
            float,
            1.0,
            "max particle travel per substep (anti-tunnelling); above 1 the substep runs as ceil(clamp) solves of "
            "≤ 1 r each (a wall or particle is never crossed); refused when gravity alone exceeds it (g·h² > clamp·r)",
            range=(0.1, 2.0),
            units="radii",
        ),
        "depenetration_speed": Param(
            float,
            0.0,
            "max depenetration speed: the constraints leave a particle no faster than this or its predicted speed "
            "(gravity's and its own), so deep overlaps come apart without launching elements; 0 = unbounded, but "
            "50 mm/s in a slender run with m > 1 (its m³ × substeps would launch long grains)",
            range=(0.0, 100000.0),
            units="mm/s",
        ),
        "gravity": Param(
            float,
            9810.0,
            "gravitational acceleration (effect 'gravity'), along −z",
            range=(0.0, 100000.0),
            units="mm/s²",
        ),
        "white_density": Param(
            float, 1.03, "density of the medium around the buoyant part (ikura white)", range=(0.1, 10.0), units="g/cm³"
        ),
        "part_density": Param(
            float,
            0.93,
            "density of the buoyant part (faces with parts == 1: the yolk)",
            range=(0.1, 10.0),
            units="g/cm³",
        ),
        "log_every": Param(
            int, 10, "log particles to Rerun every k frames (0 = never)", range=(0, 100000), units="frames"
        ),
        "log_meshes_every": Param(
            int,
            30,
            "log the element meshes to Rerun every k frames and at the last "
            "(0 = never; a 2,000-grain bowl logs ≈ 10 MB per snapshot)",
            range=(0, 100000),
            units="frames",
        ),
    },
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
    moving = sim.model.n_moving
    ctx.expect_cost(
        moving * frames * substeps * p.iterations / PARTICLE_ITERATIONS_PER_SECOND,
        f"{frames:,} frames × {substeps} substeps × {p.iterations} iterations of {moving:,} particles",
    )
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
    ):
        ctx.rerun.send_columns(
            f"scalars/{name}",
            indexes=[rr.TimeColumn("sim_step", sequence=steps)],
            columns=rr.Scalars.columns(scalars=np.asarray(values)),
        )
