"""The xpbd node's parameters and the solver's settings — SPEC §3 (G Table 3) and §5.

``PARAMS`` declares the node's parameters once: type, default, range, units and the measurement behind
each default. ``XpbdParams`` is generated from it (one typed field per parameter, user units: N/m, mg,
radii, %, g/cm³), and ``xpbd_params`` validates given values and fills in the declared defaults.
``solver_settings`` turns an ``XpbdParams`` into ``SolverSettings``, the solver's units (mm, g, s);
``SolverSettings`` has no defaults of its own, so tests, benchmarks and scenes build theirs through
``solver_settings_for`` with overrides in the node's units, and every solver they run is one a recipe
can ask for. ``EFFECTS`` is the one list of the physical effects the solver implements: the node
declares it and the solver checks requests against it. numpy only, no numba: the node's module imports
this at registry time.
"""

from __future__ import annotations

from dataclasses import dataclass, make_dataclass

import numpy as np

from nodegraph.params import Param, ParamValueError, resolve

from .friction_models import FRICTION_MODELS, AnchoredFriction, SubstepFriction
from .moisture import WATER_CONTENT, moisture_factors

# a japonica grain's length over its width (SPEC §1: 5 × 3 mm raw): the shape ``particles_per_element`` is set for
REFERENCE_ELONGATION = 5.0 / 3.0


def slender_m(elongation: float) -> int:
    """m ≥ 1 of a ``slender`` run: an element's length over its width in units of a japonica grain's
    (``REFERENCE_ELONGATION``), rounded; its run takes m² × the particles and m³ × the substeps."""
    return max(1, int(round(elongation / REFERENCE_ELONGATION)))


EFFECTS = ("gravity", "contact", "friction", "adhesion", "collider", "buoyancy", "moisture", "damping")
PAIR_EFFECTS = frozenset({"contact", "friction", "adhesion"})  # the effects that need neighbour lists
ADHESION_STIFFNESS = 10.0  # N/m at clumping 1: pulls a 25 mg grain with ≈ 40× its weight per mm of gap

# Solver constants no recipe sets (not node parameters), each with its reason:
# every this many frames one substep solves the asleep elements too (under gravity), so an element whose
# support went away falls and wakes; between probes only a push wakes it
SLEEP_PROBE = 1
# mm/s²: a sleeper wakes when the probe's substep, solved from rest, moves it as this net acceleration would
# (0.1 g: a rice grain sliding at μk 0.42 has it above 28.3°, from g(sin θ − μk cos θ) = 0.1 g, at any substep count;
# measured: a grain on a 36° plane woke at 40 substeps, where the speed test kept it asleep)
WAKE_ACCEL = 981.0
# s: an awake element sleeps after staying still this long in a row: the default substep (1/600 s), so the defaults
# test one substep, and 80 substeps test 8. Tested on one substep at any count, a grain set down from rest at 80
# substeps slept at once (its first substep under gravity moves it g·h·h with g·h ≈ 2 mm/s, the sleep speed), landed
# on one particle and never woke to 40°; a whole frame (1/60 s) left the long-rest pile awake (test_xpbd_core.py)
SETTLE_TIME = 1.0 / 600.0
# a run without glue that starts from another run's rest (its aggregate carries deformations) inherits the overlaps
# that run tolerated; at more substeps its solve separates them at overlap/h, a launch (150 grains settled at 10
# substeps, run on at 40: the bed's top rose 0.82 mm in one frame at 23 mm/s mean speed). For its first frames the
# depenetration speed is bounded, so the bed expands to the new settings' overlaps without being thrown (0.18 mm,
# 8.6 mm/s: tests/simulation/test_handoff.py); after them the run's own depenetration_speed applies. A placement's
# start is not bounded: bounded, the dropped and poured heaps parted by 5.6° (tests/simulation/test_heap_convergence.py)
HANDOFF_FRAMES = 3
HANDOFF_DEPENETRATION = 50.0  # mm/s
YOLK_DRAG = 40.0  # 1/s: a yolk's drag towards its egg's velocity (``buoyancy.yolk_predict``)
# N: the load at which ``squeeze_strain`` is given (Tomita et al., via G §2.2: ≈ 25 % at 0.2 N)
SQUEEZE_LOAD = 0.2
# a contact is rigid past this strain of its element: cooked rice fractures near 50 % (Tomita et al., via G §2.2), and
# beyond it the grain breaks (the tearing effect's business), it does not squeeze on; it also bounds how deep a
# pile's weight can press particles into each other
CRUSH_STRAIN = 0.5
# the damping ratio of a compliant contact (``contact_constraints.compliant_push``). The damping acts on the pair's
# motion within a substep, which two iterations leave unconverged under a heavy load, so it also carries part of a
# load at rest: a grain dropped 10 mm onto another (``validation.drop_bounce``) rebounds 0.145 / 1.07 mm at 10 / 40
# substeps undamped, 0.095 / 0.68 at 0.5 and 0.071 / 0.51 at 1 (rigid contacts: 0.074 / 0.67), while 0.2 N on the
# flat plate strains the grains 23.4 %, 23.7 % and 15.1 % (``validation.squeeze_xpbd``): 0.5 bounces no more than
# rigid contacts at 40 substeps and keeps the static strain
CONTACT_DAMPING = 0.5
ROTATION_ITERATIONS = 8  # iterations of the rotation extraction in shape matching and glue (Müller 2016)


PARAMS = {
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
    # 1 (particles in the mid-plane): with rigid contacts (squeeze_strain 0) a japonica grain squeezed under 0.2 N
    # strains 1.7 % (the compliant contacts give it 23.7 %: docs/validation.md);
    # 2 (16 particles) can flatten, but at 10 × 2 a 0.2 N plate passes through it at any stiffness, and with 8
    # iterations at 100 N/m it flattens 6.4 % and springs back, where cooked rice strains ≈ 25 % (Tomita, via G);
    # its stream heap does not rest (benchmarks/squeeze_candidates.py, docs/validation.md)
    "particle_layers": Param(
        int,
        1,
        "layers of particles through an element's thickness: 1 = the cluster lies in its mid-plane (rigid across "
        "its thickness); 2 = each half of the element covered by half the particles, a quarter of the thickness "
        "or more off the mid-plane, so shape matching can flatten it (needs iterations: see docs/validation.md)",
        range=(1, 2),
    ),
    "slender": Param(
        bool,
        False,
        "clusters sized to the element's cross-section: an element m times as elongated as a japonica grain "
        "(length / width over 5/3, rounded, ≥ 1; indica 2) gets m² × particles_per_element particles, and the run "
        "m³ × the substeps (a cluster of more particles gives way to its contacts more slowly per substep), "
        "with a depenetration speed (50 mm/s unless set)",
    ),
    # on: off, the main job tore one placed grain across the bowl's wall (its mesh stretched 1.70×, 2 mm into the wall
    # in the exported file: tools/vessel_check.py); on, every grain's stretch stays within 1 %
    "rigid_start": Param(
        bool,
        True,
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
    # cooked rice strains 25 % at SQUEEZE_LOAD in its elastic range (Tomita et al., via G §2.2; SPEC §3). Off (0) by
    # default: after the first substep pre-stabilisation leaves overlaps to the compliance, so overlaps one sweep does
    # not separate (64 particles started at one point) are pushed apart with speed, a 1000× heavier element sinks
    # 0.55–0.63 r into a light one, a 60-sphere column 0.12 r (tests/simulation/test_xpbd_core.py; docs/validation.md)
    "squeeze_strain": Param(
        float,
        0.0,
        "strain of an element squeezed between two rigid plates under 0.2 N: its contacts give by an XPBD "
        "compliance derived from it (``contact_constraints.face_compliance``), rigid past 50 % (crushed); 0 = rigid "
        "contacts",
        range=(0.0, 45.0),
        units="%",
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
    # anchored by default: under the per-substep rule rice heaps creep flat (issue 24, docs/validation.md)
    "friction_model": Param(
        str,
        "anchored",
        "anchored: static friction restores the slip since the contact began sticking, against the normal "
        "load the grain's contact carried in the last substep (heaps rest; a grain on a plane holds to within 1° of "
        "atan μs, docs/validation.md); substep: it holds each substep's slip only (Macklin et al. 2014; heaps creep "
        "flat)",
        choices=("substep", "anchored"),
    ),
    "capture_radius": Param(
        float,
        0.2,
        "adhesion reach beyond contact, in particle radii (effect 'adhesion')",
        range=(0.0, 1.0),
        units="radii",
    ),
    "clumping": Param(float, 0.3, "adhesion strength (breakable bonds within the capture radius)", range=(0.0, 1.0)),
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
    # 4 (issue 46): at 1 a 1 mm particle moves ≤ 0.6 m/s at 10 substeps and 2.4 m/s at 40, so a stream poured from
    # 240 mm landed braked at 10 and at its fall speed at 40, and its heap stood at H/R 36.5° and 21.3° (15° apart);
    # at 4 a fast substep runs as up to 4 solves of ≤ 1 r (``step_limits.solve_pieces``) and the stream lands at its
    # fall speed at either: H/R 24.3° and 21.3°, the dropped ball 24.3° and 22.5° (300 grains, 2.5 s;
    # benchmarks/physics_at_defaults.py, docs/validation.md). It costs the main job 13 % more CPU cold (80.8 → 91.5 s,
    # rice_sim 13.8 → 18.4 s: its grains relax out of their packed overlaps faster than 1 r per substep; load 5–6)
    "speed_clamp": Param(
        float,
        4.0,
        "max particle travel per substep; above 1, a substep in which a particle would travel more than 1 r runs "
        "as ceil(travel) solves of ≤ 1 r each, up to ceil(clamp) (a wall or particle is never crossed, and a fall "
        "keeps its speed: at 4, 2.4 m/s for 1 mm particles at 10 substeps); refused when gravity alone exceeds it",
        range=(0.1, 8.0),
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
    "log_every": Param(int, 10, "log particles to Rerun every k frames (0 = never)", range=(0, 100000), units="frames"),
    "log_meshes_every": Param(
        int,
        30,
        "log the element meshes to Rerun every k frames and at the last "
        "(0 = never; a 2,000-grain bowl logs ≈ 10 MB per snapshot)",
        range=(0, 100000),
        units="frames",
    ),
}


# the node's parameters as one typed value, a field per declared parameter (no hand-copied field list)
XpbdParams = make_dataclass(
    "XpbdParams",
    [(name, param.type) for name, param in PARAMS.items()],
    frozen=True,
)
XpbdParams.__module__ = __name__
XpbdParams.__doc__ = """The ``xpbd`` node's parameters, validated and with defaults filled in (``xpbd_params``, or the
node's ``NodeSpec.resolve_params``); generated from ``PARAMS``, where their meanings, units and ranges are declared."""


def xpbd_params(**given) -> XpbdParams:
    """``given`` node parameters (node units) validated by their declarations, the rest at the declared
    defaults. Raises ParamValueError naming the parameter and what is allowed, KeyError for an unknown name."""
    unknown = set(given) - set(PARAMS)
    if unknown:
        raise KeyError(f"xpbd has no parameter {', '.join(sorted(unknown))}; it has: {', '.join(PARAMS)}")
    for name, value in given.items():  # the error names the parameter
        try:
            PARAMS[name].validate(value)
        except ParamValueError as error:
            raise ParamValueError(f"xpbd.{name}: {error}", error.allowed) from None
    return XpbdParams(**resolve(PARAMS, given))


@dataclass(frozen=True)
class SolverSettings:
    """Physical and numerical settings in the solver's units (mm, g, s), derived from the node's parameters
    by ``solver_settings`` (no defaults here: see ``PARAMS``). Raises ValueError for an effect outside
    ``EFFECTS`` or a step that cannot run."""

    effects: frozenset[str]
    substeps: int
    iterations: int
    dt: float  # s
    gravity: float  # mm/s²
    compliance: float  # s²/g; inf = no shape matching
    linear_deformation: float  # β of SPEC §5
    quadratic: bool  # quadratic deformation (SPEC §5) for clusters that can support it
    bend_compliance: float  # s²/g of the long-axis bend constraints (``bending``); inf = none
    mu_s: float
    mu_k: float
    # the friction model, a strategy chosen once from the node's ``friction_model`` (``friction_models``)
    friction: SubstepFriction | AnchoredFriction
    capture: float  # mm
    adhesion_compliance: float  # s²/g
    glue: float  # share of the way to the glued regions' goal per iteration (``glue``); 0 = no glue
    # a glued grain further than this (mm) from its place in a neighbour's region tears off: one particle radius
    # (0.2 r tore most of a glued onigiri's paste as it settled onto its plate, 1 r none; docs/validation.md)
    glue_tear: float
    damping: float  # fraction of velocity removed per 1/60 s
    sleep_speed: float  # mm/s
    speed_clamp: float  # particle radii per substep
    yolk_accel: float  # mm/s², upward buoyant acceleration of the yolk
    shock_propagation: float  # mass ratio of a contact particle to one a diameter above it (1 = off)
    # mm/s: the solve leaves a particle no faster than max(its predicted speed, this) (``integrate.update_velocity``)
    depenetration_speed: float
    # s: until this time the depenetration speed is at most HANDOFF_DEPENETRATION (a state handed on by another run)
    handoff_until: float
    squeeze_strain: float  # an element's strain between rigid plates under SQUEEZE_LOAD (0 = rigid contacts)

    def __post_init__(self):
        object.__setattr__(self, "effects", frozenset(self.effects))
        unknown = self.effects - set(EFFECTS)
        if unknown:
            raise ValueError(f"unknown effects {sorted(unknown)}; allowed: {', '.join(EFFECTS)}")
        if self.substeps < 1 or self.iterations < 1 or not self.dt > 0:
            raise ValueError("substeps and iterations must be ≥ 1 and dt > 0")

    @property
    def h(self) -> float:
        """The substep, dt / substeps (s)."""
        return self.dt / self.substeps


def solver_settings(params: XpbdParams, effects, radius: float, material=None, handed: bool = False) -> SolverSettings:
    """Table-3 style parameters → solver settings (SPEC §3); 'moisture' rescales stiffness, friction
    and adhesion by the cooked ``material``'s factors (``CookedMaterial.stiffness_scale``, ``friction_scale``,
    ``adhesion_scale``: computed once, by ``cooked_material``, from its water content; None: the cooked_rice
    defaults, ``moisture_factors(WATER_CONTENT)``). ``radius``: the particles' median radius (mm), the unit of
    the capture radius. ``handed``: the elements come from another run's rest (``HANDOFF_FRAMES``)."""
    p = params
    material = material if material is not None else moisture_factors(WATER_CONTENT)
    moist = "moisture" in effects
    stiffness = p.stiffness * (material.stiffness_scale if moist else 1.0)
    adhesion = p.clumping * (material.adhesion_scale if moist else 1.0) * ADHESION_STIFFNESS
    mu_s = p.static_threshold * p.friction * (material.friction_scale if moist else 1.0)
    return SolverSettings(
        effects=frozenset(effects),
        substeps=p.substeps,
        iterations=p.iterations,
        dt=p.dt,
        gravity=p.gravity,
        compliance=1.0 / (1000.0 * stiffness) if stiffness > 0 else np.inf,  # N/m → s²/g
        linear_deformation=p.linear_deformation,
        quadratic=p.deformation == "quadratic",
        bend_compliance=1.0 / (1000.0 * stiffness * p.bend_stiffness) if stiffness * p.bend_stiffness > 0 else np.inf,
        mu_s=mu_s,
        mu_k=mu_s * p.dynamic_scale,
        friction=FRICTION_MODELS[p.friction_model],
        capture=p.capture_radius * radius,
        adhesion_compliance=1.0 / (1000.0 * adhesion) if adhesion > 0 else np.inf,
        glue=p.glue,
        glue_tear=radius,
        damping=p.damping,
        sleep_speed=p.sleep_speed,
        speed_clamp=p.speed_clamp,
        depenetration_speed=p.depenetration_speed if p.depenetration_speed > 0 else np.inf,
        handoff_until=HANDOFF_FRAMES * p.dt if handed else 0.0,
        squeeze_strain=p.squeeze_strain / 100.0,
        shock_propagation=p.shock_propagation,
        yolk_accel=p.gravity * (p.white_density / p.part_density - 1.0) if "gravity" in effects else 0.0,
    )


def solver_settings_for(effects, radius: float, water_content: float = WATER_CONTENT, **params) -> SolverSettings:
    """The settings the ``xpbd`` node runs with for these ``effects``, median particle ``radius`` (mm) and
    ``water_content`` (%), with ``params`` given in the node's units (``PARAMS``: stiffness in N/m, not
    compliance; static_threshold and dynamic_scale, not μs and μk; friction_model, not a flag) and the rest
    at the node's defaults: the one way tests, benchmarks and scenes get a solver."""
    return solver_settings(xpbd_params(**params), effects, radius, moisture_factors(water_content))
