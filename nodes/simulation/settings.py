"""The xpbd node's parameters and the solver's settings — SPEC §3 (G Table 3) and §5.

``XpbdParams`` is the node's declared parameters as one typed value (user units: N/m, mg, radii, %,
g/cm³), built once by the node; ``solver_settings`` turns it into ``SolverSettings``, the solver's
units (mm, g, s). ``EFFECTS`` is the one list of the physical effects the solver implements: the
node declares it and the solver checks requests against it. numpy only, no numba: the node's module
imports this at registry time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .moisture import WATER_CONTENT, moisture_scales

EFFECTS = ("gravity", "contact", "friction", "adhesion", "collider", "buoyancy", "moisture", "damping")
PAIR_EFFECTS = frozenset({"contact", "friction", "adhesion"})  # the effects that need neighbour lists
ADHESION_STIFFNESS = 10.0  # N/m at clumping 1: pulls a 25 mg grain with ≈ 40× its weight per mm of gap


@dataclass(frozen=True)
class SolverSettings:
    """Physical and numerical settings in the solver's units (mm, g, s); see the ``xpbd`` node.
    Raises ValueError for an effect outside ``EFFECTS`` or a step that cannot run."""

    effects: frozenset[str]
    substeps: int = 10
    iterations: int = 2
    dt: float = 1.0 / 60.0
    gravity: float = 9810.0
    compliance: float = 1e-6  # s²/g; 0 = infinitely stiff clusters, inf = no shape matching
    linear_deformation: float = 0.0  # β of SPEC §5
    quadratic: bool = False  # quadratic deformation (SPEC §5) for clusters that can support it
    bend_compliance: float = np.inf  # s²/g of the long-axis bend constraints (``bending``); inf = none
    mu_s: float = 0.6
    mu_k: float = 0.4
    # friction measured from where each contact began sticking, against the normal load the contact carried
    # this substep (``friction``); False: Macklin et al. 2014's per-substep rule, under which heaps creep flat
    # (issue 24, docs/validation.md)
    anchored_friction: bool = True
    capture: float = 0.2  # mm
    adhesion_compliance: float = 1e-3  # s²/g
    glue: float = 0.0  # share of the way to the glued regions' goal per iteration (``glue``); 0 = no glue
    # a glued grain further than this (mm) from its place in a neighbour's region tears off: one particle radius
    # (0.2 r tore most of a glued onigiri's paste as it settled onto its plate, 1 r none; docs/validation.md)
    glue_tear: float = 1.0
    damping: float = 0.0  # fraction of velocity removed per 1/60 s
    sleep_speed: float = 0.0  # mm/s
    # every this many frames one substep solves the asleep elements too (under gravity), so an
    # element whose support went away falls and wakes; between probes only a push wakes it
    sleep_probe: int = 1
    speed_clamp: float = 1.0  # particle radii per substep
    yolk_accel: float = 0.0  # mm/s², upward buoyant acceleration of the yolk
    yolk_drag: float = 40.0  # 1/s
    rotation_iterations: int = 8
    shock_propagation: float = 1.0  # mass ratio of a contact particle to one a diameter above it (1 = off)
    # mm/s: the solve leaves a particle no faster than max(its predicted speed, this) (``integrate.update_velocity``)
    depenetration_speed: float = np.inf

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


@dataclass(frozen=True)
class XpbdParams:
    """The ``xpbd`` node's parameters, validated and with defaults filled in (``NodeSpec.resolve_params``);
    their meanings, units and ranges are declared with the node."""

    mode: str
    frames: int
    dt: float
    substeps: int
    iterations: int
    particles_per_element: int
    slender: bool
    rigid_start: bool
    contact_offset: float  # median particle radii
    mass: float  # mg
    stiffness: float  # N/m
    linear_deformation: float
    deformation: str
    bend_stiffness: float  # × stiffness
    damping: float
    friction: float
    static_threshold: float
    dynamic_scale: float
    friction_model: str  # substep | anchored
    capture_radius: float  # particle radii
    clumping: float
    glue: float
    sleep_speed: float  # mm/s
    shock_propagation: float
    speed_clamp: float  # radii per substep
    depenetration_speed: float  # mm/s, 0 = unbounded
    gravity: float  # mm/s²
    white_density: float  # g/cm³
    part_density: float  # g/cm³
    log_every: int
    log_meshes_every: int


def solver_settings(params: XpbdParams, effects, radius: float, water_content: float = WATER_CONTENT) -> SolverSettings:
    """Table-3 style parameters → solver settings (SPEC §3); 'moisture' rescales stiffness, friction
    and adhesion (``moisture_scales``) at ``water_content`` % (the cooked material's: the node's input
    'material'). ``radius``: the particles' median radius (mm), the unit of the capture radius."""
    p = params
    scale = (
        moisture_scales(water_content)
        if "moisture" in effects
        else {"stiffness": 1.0, "friction": 1.0, "adhesion": 1.0}
    )
    stiffness = p.stiffness * scale["stiffness"]
    adhesion = p.clumping * scale["adhesion"] * ADHESION_STIFFNESS
    mu_s = p.static_threshold * p.friction * scale["friction"]
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
        anchored_friction=p.friction_model == "anchored",
        capture=p.capture_radius * radius,
        adhesion_compliance=1.0 / (1000.0 * adhesion) if adhesion > 0 else np.inf,
        glue=p.glue,
        glue_tear=radius,
        damping=p.damping,
        sleep_speed=p.sleep_speed,
        speed_clamp=p.speed_clamp,
        depenetration_speed=p.depenetration_speed if p.depenetration_speed > 0 else np.inf,
        shock_propagation=p.shock_propagation,
        yolk_accel=p.gravity * (p.white_density / p.part_density - 1.0) if "gravity" in effects else 0.0,
    )
