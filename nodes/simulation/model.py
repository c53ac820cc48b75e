"""What a simulation run does not change — SPEC §3 (particles in clusters, colliders, yolks) and §5
(rest shapes and their moments): the ``Model``, in the shape of Newton's Model / State split.

Particles are struct-of-arrays, one cluster per element (CSR ``start``); static obstacle particles
(other aggregates at rest) come last, with inverse mass 0, outside ``start``. The optional parts
are each their own value or None — built only when the settings ask for what uses them: the rest
moments with shape matching, the quadratic fit with the quadratic goal, the bend triples with bend
constraints, the collider field with effect 'collider', the yolks with effect 'buoyancy'.
``Model.state()`` gives the initial ``State`` (``state``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from . import bending, collider, glue, shape_matching
from .friction import FORCE, RUBBED
from .settings import SolverSettings
from .state import State, YolkState


class ModelArrays(NamedTuple):
    """The ``Model``'s per-particle and per-cluster arrays as the kernels take them: one named bundle, built once
    per run (``Model.arrays()``; numba takes it as one argument, a kernel reads the fields it uses)."""

    w: np.ndarray  # (n,) inverse masses; 0 = static
    r: np.ndarray  # (n,) radii
    elem: np.ndarray  # (n,) element of each particle
    start: np.ndarray  # (m + 1,) CSR of the clusters
    q_rest: np.ndarray  # (n_moving, 3) rest offsets


@dataclass(frozen=True, eq=False)
class RestMoments:
    """Per cluster A_qq⁺ and the projector on its null space (SPEC §5, ``shape_matching.rest_moments``)."""

    aqq_pinv: np.ndarray  # (m, 3, 3)
    null_proj: np.ndarray  # (m, 3, 3)

    def args(self):
        """The kernels' argument: one ``shape_matching.LinearMoments``."""
        return (shape_matching.LinearMoments(self.aqq_pinv, self.null_proj),)


@dataclass(frozen=True, eq=False)
class QuadraticFit:
    """The quadratic goal's rest data (SPEC §5, ``shape_matching.quadratic_moments``); clusters whose
    flag is unset keep the linear goal."""

    qt: np.ndarray  # (n, 9) q̃ per particle
    qpinv: np.ndarray  # (m, 9, 9) Ã_qq⁻¹ per cluster
    flags: np.ndarray  # (m,) bool

    def args(self):
        """The kernels' argument: one ``shape_matching.QuadraticMoments``."""
        return (shape_matching.QuadraticMoments(self.qt, self.qpinv, self.flags),)


@dataclass(frozen=True, eq=False)
class BendTriples:
    """Long-axis bend constraints (``bending.bend_triples``): chain triples (end a, interior b, end c),
    chord fractions, rest offsets, per-cluster CSR."""

    triples: np.ndarray  # (t, 3)
    frac: np.ndarray  # (t,)
    rest: np.ndarray  # (t, 3)
    tstart: np.ndarray  # (m + 1,)

    def args(self):
        """The kernels' argument: one ``bending.BendRows``."""
        return bending.BendRows(self.triples, self.frac, self.rest, self.tstart)


@dataclass(frozen=True, eq=False)
class ColliderField:
    """φ of the free space on a grid (``collider.free_space_field``) and its ``block_minimum``."""

    phi: np.ndarray  # (nx, ny, nz)
    origin: np.ndarray  # (3,)
    pitch: float
    blocks: np.ndarray  # min φ per block of COARSE³ cells

    @classmethod
    def from_grid(cls, grid) -> ColliderField:
        """From (phi, origin, pitch) as ``collider.signed_distance_grid`` returns it."""
        phi, origin, pitch = grid
        return cls(phi, origin, pitch, collider.block_minimum(phi))

    def grid(self):
        return self.phi, self.origin, self.pitch

    def args(self):
        """The kernels' argument: one ``collider.ColliderGrid``."""
        return collider.ColliderGrid(self.phi, self.origin, self.pitch, self.blocks)


@dataclass(frozen=True, eq=False)
class GlueRegions:
    """The regions of the grains glued at the start of the run (``glue.glued_regions``)."""

    region_start: np.ndarray  # (m + 1,) CSR of each region's links
    link_grain: np.ndarray  # (L,)
    link_own: np.ndarray  # (L,) bool: the region's own grain
    link_start: np.ndarray  # (L + 1,) CSR of each link's memberships
    member: np.ndarray  # (M,) particle of each membership
    rest: np.ndarray  # (M, 3) its position at the start
    pstart: np.ndarray  # (n + 1,) CSR of each particle's memberships
    pslot: np.ndarray  # (M,)
    floor_start: np.ndarray  # (n + 1,) CSR of each particle's pressed glued partners
    floor_partner: np.ndarray
    floor_depth: np.ndarray  # their overlap at the start (mm)

    def rows(self):
        """The regions as ``glue.glue_match`` takes them."""
        return glue.RegionRows(self.region_start, self.link_own, self.link_start, self.member, self.rest)

    def floors(self):
        """The pressed partners as ``glue.glued_floors`` takes them."""
        return glue.GlueFloors(
            self.floor_start, self.floor_partner, self.floor_depth, self.region_start, self.link_grain
        )

    def members(self):
        """Each particle's memberships as ``glue.glue_pull`` takes them."""
        return glue.GlueMembers(self.pstart, self.pslot)


class YolkRoom(NamedTuple):
    """Where the yolks may be, as the buoyancy kernels take it (``Yolks.arrays()``, once per run)."""

    owner: np.ndarray  # (k,) int64
    centre: np.ndarray  # (k, 3)
    room: np.ndarray  # (k,)


@dataclass(frozen=True, eq=False)
class Yolks:
    """Buoyant yolks (SPEC §1, ``buoyancy``): yolk k sits in element ``owner[k]``, free within ``room[k]``
    of the membrane centre ``centre[k]`` (element frame, relative to the cluster's centre of mass)."""

    x0: np.ndarray  # (k, 3) initial positions
    owner: np.ndarray  # (k,) int64
    centre: np.ndarray  # (k, 3)
    room: np.ndarray  # (k,)

    def arrays(self) -> YolkRoom:
        return YolkRoom(self.owner, self.centre, self.room)


@dataclass(frozen=True, eq=False)
class Model:
    """Particles in clusters, one per element, then the static obstacle particles; what never changes
    in a run (the initial positions and rotations included, as Newton's Model holds them)."""

    x0: np.ndarray  # (n, 3) initial positions, obstacles last
    quats0: np.ndarray  # (m, 4) initial cluster rotations, w-x-y-z
    r: np.ndarray  # (n,) radii
    w: np.ndarray  # (n,) inverse masses; 0 = static
    elem: np.ndarray  # (n,) element of each particle; the obstacles share id m (no pair of them is listed)
    start: np.ndarray  # (m + 1,) CSR of the clusters (moving particles only)
    q_rest: np.ndarray  # (n_moving, 3) rest offsets from the cluster's centre of mass
    n_moving: int  # particles before the obstacles
    moments: RestMoments | None  # None: no shape matching (compliance inf, or no cluster of ≥ 2)
    quadratic: QuadraticFit | None
    bend: BendTriples | None
    collider: ColliderField | None
    yolks: Yolks | None
    glue: GlueRegions | None = None  # effect 'adhesion' with glue on (``SolverSettings.glue``)

    def arrays(self) -> ModelArrays:
        """The kernels' bundle of the model's arrays (``ModelArrays``)."""
        return ModelArrays(self.w, self.r, self.elem, self.start, self.q_rest)

    @property
    def elements(self) -> int:
        return len(self.start) - 1

    def state(self) -> State:
        """The state at the start of a run: at rest in the initial positions, every element awake."""
        n = len(self.x0)
        awake = np.zeros(n, np.bool_)  # per particle: solved this substep; static obstacles never are
        awake[: self.n_moving] = True
        yolks = None
        if self.yolks is not None:
            yx = self.yolks.x0.copy()
            yolks = YolkState(yx, np.zeros_like(yx), np.zeros_like(yx))
        return State(
            x=self.x0.copy(),
            v=np.zeros_like(self.x0),
            x_prev=self.x0.copy(),
            quats=self.quats0.copy(),
            x_start=np.zeros_like(self.x0),
            asleep=np.zeros(self.elements, np.bool_),
            awake=awake,
            pushed=np.zeros(n, np.bool_),
            wall_anchor=np.full((n, 3), np.nan),
            wall_load=np.zeros(n),
            wall_mean=np.zeros(self.elements),
            wall_mode=np.zeros(self.elements, np.int8),
            wall_rubbed=np.zeros((n, RUBBED)),
            wall_force=np.zeros((self.elements, FORCE)),
            slow_steps=np.zeros(self.elements, np.int64),
            yolks=yolks,
            glued=np.ones(len(self.glue.link_grain), np.bool_) if self.glue is not None else None,
            glue_quats=np.tile([1.0, 0.0, 0.0, 0.0], (self.elements, 1)) if self.glue is not None else None,
        )

    def centres(self, x: np.ndarray) -> np.ndarray:
        """Mass-weighted cluster centres (m, 3) of positions ``x``."""
        x, w = x[: self.n_moving], self.w[: self.n_moving]
        m = shape_matching.particle_masses(w)
        sums = np.add.reduceat(x * m[:, None], self.start[:-1], axis=0)
        return sums / np.add.reduceat(m, self.start[:-1])[:, None]


def build_model(
    x, r, w, start, q_rest, quats, settings: SolverSettings, sdf=None, yolks: Yolks | None = None, obstacles=None
) -> Model:
    """The model of particles ``x, r, w`` in clusters ``start`` with rest offsets ``q_rest`` and
    rotations ``quats``, holding what ``settings`` use. ``sdf`` = (phi, origin, pitch) of the free
    space, kept with effect 'collider'; ``yolks`` kept with effect 'buoyancy'.

    ``obstacles`` = (positions, radii) of static particles (other aggregates at rest), or None.
    They are appended after the moving particles with inverse mass 0 and one shared element id
    (so no pair of them is ever listed), take part in contact and friction only (adhesion skips
    them, see ``adhesion``), and lie outside ``start``: shape matching, sleeping and the outputs
    never see them. The pair kernels treat w = 0 as infinitely heavy (``lifted_share``: the moving
    partner takes the whole correction, whatever the height scaling). Unwired: nothing is appended
    or allocated."""
    s = settings
    n_moving = len(x)
    start = np.ascontiguousarray(start, np.int64)
    elem = np.repeat(np.arange(len(start) - 1, dtype=np.int64), np.diff(start))
    if obstacles is not None and len(obstacles[0]):
        x = np.concatenate([x, obstacles[0]])
        r = np.concatenate([r, obstacles[1]])
        w = np.concatenate([w, np.zeros(len(obstacles[0]))])
        elem = np.concatenate([elem, np.full(len(obstacles[0]), len(start) - 1, np.int64)])
    x = np.ascontiguousarray(x, np.float64).copy()
    r = np.ascontiguousarray(r, np.float64)
    w = np.ascontiguousarray(w, np.float64)
    q_rest = np.ascontiguousarray(q_rest, np.float64)
    quats = np.ascontiguousarray(quats, np.float64).copy()
    # shape matching is the element's own elasticity, not an effect: always on for clusters of ≥ 2
    moments = quadratic = bend = None
    if np.isfinite(s.compliance) and bool(np.any(np.diff(start) > 1)):
        moments = RestMoments(*shape_matching.rest_moments(q_rest, w, start))
        if s.quadratic:
            quadratic = QuadraticFit(*shape_matching.quadratic_moments(q_rest, w, start))
        if np.isfinite(s.bend_compliance):
            triples = BendTriples(*bending.bend_triples(q_rest, start))
            bend = triples if len(triples.triples) else None
    field = ColliderField.from_grid(sdf) if sdf is not None and "collider" in s.effects else None
    if yolks is not None and not ("buoyancy" in s.effects and len(yolks.x0)):
        yolks = None
    regions = None
    if "adhesion" in s.effects and s.glue > 0:
        found = glue.glued_regions(x, r, elem, start, n_moving, s.capture)
        regions = GlueRegions(**found) if found is not None else None
    return Model(x, quats, r, w, elem, start, q_rest, n_moving, moments, quadratic, bend, field, yolks, regions)
