"""The XPBD substep loop — SPEC §3 (G §3.3; Macklin et al. 2016): predict, iterate constraint
families, update velocities; only the requested effects allocate buffers and run kernels.

Every kernel call goes through ``KernelDispatch``, which counts calls per constraint family: the
effects-gating test and the effects-cost benchmark read those counters.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numba
import numpy as np

from . import adhesion, bending, buoyancy, collider, contact_constraints, integrate, shape_matching, spatial_hash
from .threads import FreeCores, thread_count

# below this many particles the kernels run on one thread: threads gain nothing there (ikura don,
# 2,480 particles: equal times); above, on the cores other processes leave free (``threads``)
PARALLEL_PARTICLES = 4096
EFFECTS = ("gravity", "contact", "friction", "adhesion", "collider", "buoyancy", "moisture", "damping")


class KernelDispatch:
    """Calls kernels by family name and counts the calls (what ran, and how often)."""

    def __init__(self):
        self.calls: Counter[str] = Counter()

    def __call__(self, family: str | tuple[str, ...], kernel, *args):
        for name in (family,) if isinstance(family, str) else family:  # a fused kernel counts for each
            self.calls[name] += 1
        return kernel(*args)


@dataclass
class SolverSettings:
    """Physical and numerical settings in the solver's units (mm, g, s); see the ``xpbd`` node."""

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
    capture: float = 0.2  # mm
    adhesion_compliance: float = 1e-3  # s²/g
    damping: float = 0.0  # fraction of velocity removed per 1/60 s
    sleep_speed: float = 0.0  # mm/s
    # every this many frames one substep solves the asleep elements too (under gravity), so an
    # element whose support went away falls and wakes; between probes only a push wakes it
    sleep_probe: int = 1
    speed_clamp: float = 1.0  # particle radii per substep
    yolk_accel: float = 0.0  # mm/s², upward buoyant acceleration of the yolk
    yolk_drag: float = 40.0  # 1/s
    rotation_iterations: int = 8
    # tolerated old overlap shrinks by this many radii per second (0.05 r per substep at 10 × 1/60 s);
    # a rate, not a share per substep, so the separation speed it allows (≤ rate·r) does not grow
    # with the substep count (a per-substep share gave 64-substep runs 6× the speed, and energy)
    overlap_decay_rate: float = 30.0
    shock_propagation: float = 1.0  # mass ratio of a contact particle to one a diameter above it (1 = off)


@dataclass
class Diagnostics:
    """Per-frame scalars (SPEC §3 log): max penetration / radius, residual, kinetic energy, sleeping
    share; and ``solved``, the share of the moving particles solved per substep (awake, 1 without
    sleeping): the work sleeping leaves."""

    penetration: list[float] = field(default_factory=list)
    residual: list[float] = field(default_factory=list)
    kinetic_energy: list[float] = field(default_factory=list)
    sleeping: list[float] = field(default_factory=list)
    solved: list[float] = field(default_factory=list)


class XpbdSolver:
    """Particles in clusters (CSR ``start``), one per element; yolks optional; colliders optional.

    ``obstacles`` = (positions, radii) of static particles (other aggregates at rest), or None.
    They are appended after the moving particles with inverse mass 0 and one shared element id
    (so no pair of them is ever listed), take part in contact and friction only (adhesion skips
    them, see ``adhesion``), and lie outside ``start``: shape matching, sleeping and the outputs
    never see them. The pair kernels treat w = 0 as infinitely heavy (``lifted_share``: the moving partner takes the whole
    correction, whatever the height scaling). Unwired: nothing is appended or allocated.
    ``threads``: a fixed thread count for the kernels, or None to use the cores other processes
    leave free (``threads.FreeCores``); the results are the same either way.
    """

    def __init__(self, x, r, w, start, q_rest, quats, settings: SolverSettings,
                 sdf=None, yolks=None, dispatch: KernelDispatch | None = None, obstacles=None,
                 threads: int | None = None):
        s = settings
        unknown = set(s.effects) - set(EFFECTS)
        if unknown:
            raise ValueError(f"unknown effects {sorted(unknown)}; allowed: {', '.join(EFFECTS)}")
        if s.substeps < 1 or s.iterations < 1 or not s.dt > 0:
            raise ValueError("substeps and iterations must be ≥ 1 and dt > 0")
        self.s = s
        self.dispatch = dispatch or KernelDispatch()
        self.n_moving = len(x)
        self.start = np.ascontiguousarray(start, np.int64)
        self.elem = np.repeat(np.arange(len(start) - 1, dtype=np.int64), np.diff(self.start))
        if obstacles is not None and len(obstacles[0]):
            x = np.concatenate([x, obstacles[0]])
            r = np.concatenate([r, obstacles[1]])
            w = np.concatenate([w, np.zeros(len(obstacles[0]))])
            self.elem = np.concatenate([self.elem, np.full(len(obstacles[0]), len(start) - 1, np.int64)])
        self.x = np.ascontiguousarray(x, np.float64).copy()
        self.v = np.zeros_like(self.x)
        self.x_prev = self.x.copy()
        self.x_mark = self.x.copy()  # positions at the start of a frame's last substep (diagnostics)
        self.r = np.ascontiguousarray(r, np.float64)
        self.w = np.ascontiguousarray(w, np.float64)
        self.q_rest = np.ascontiguousarray(q_rest, np.float64)
        self.quats = np.ascontiguousarray(quats, np.float64).copy()
        self.h = s.dt / s.substeps
        self.time = 0.0
        self.diagnostics = Diagnostics()
        self.asleep = np.zeros(len(start) - 1, np.bool_)
        # per particle: solved this substep (integrate.wake_flags); static obstacles never are
        self.awake = np.zeros(len(self.x), np.bool_)
        self.awake[:self.n_moving] = True
        self.pushed = np.zeros(len(self.x), np.bool_)  # asleep particles a fast awake partner ran into
        # an awake particle that moves more than this in a substep wakes the sleepers it touches:
        # the sleep threshold plus the step gravity adds to one resting on them
        self.wake_step = self.h * s.sleep_speed + (s.gravity if "gravity" in s.effects else 0.0) * self.h ** 2
        self.substeps_done = 0
        self.solved = 0  # particles solved over the substeps of the current frame
        self.buffers: dict[str, np.ndarray] = {}
        if s.sleep_speed > 0:  # positions at the substep start (asleep: when it fell asleep), for the sleep test
            self.buffers["x_start"] = np.zeros_like(self.x)
        # shape matching is the element's own elasticity, not an effect: always on for clusters of ≥ 2
        self.matching = np.isfinite(s.compliance) and bool(np.any(np.diff(self.start) > 1))
        if self.matching:
            self.buffers["lambda"] = np.zeros_like(self.x)
            self.aqq_pinv, self.null_proj = shape_matching.rest_moments(self.q_rest, self.w, self.start)
            # (qt, qpinv, flags) for the quadratic goal; Nones: the linear goal for every cluster
            self.quadratic_fit = (shape_matching.quadratic_moments(self.q_rest, self.w, self.start)
                                  if s.quadratic else (None, None, None))
        self.bend = None
        if self.matching and np.isfinite(s.bend_compliance):
            triples, frac, rest, tstart = bending.bend_triples(self.q_rest, self.start)
            if len(triples):
                self.bend = (triples, frac, rest, tstart)
                self.buffers["bend_lambda"] = np.zeros((len(triples), 3))
        g = np.array([[0.0, 0.0, -s.gravity]]) if "gravity" in s.effects else np.zeros((1, 3))
        self.accel = g
        self.pairs = bool({"contact", "friction", "adhesion"} & s.effects)
        if "adhesion" in s.effects:
            self.buffers["scratch"] = np.zeros_like(self.x)
        if self.pairs:
            # Verlet skin: lists hold pairs within contact (+ capture) + skin and are rebuilt only
            # once some particle has moved half the skin since the last build
            self.skin = 0.5 * float(self.r[:self.n_moving].max())
            self.reach = (s.capture if "adhesion" in s.effects else 0.0) + self.skin
            self.cell = 2.0 * float(self.r.max()) + self.reach
            self.buffers["x_built"] = np.full_like(self.x, np.inf)
            self.buffers["moved"] = np.zeros(len(self.x))
        # max displacement since the last neighbour build, from predict / update_velocity
        self.moved = np.inf
        self.no_lists = np.empty((0, 3))
        self.no_allowance = np.empty(0)
        # threads: fixed, or None = one below PARALLEL_PARTICLES, else the free cores, re-measured per frame
        most = min(threads, numba.config.NUMBA_NUM_THREADS) if threads else \
            (numba.get_num_threads() if len(self.x) >= PARALLEL_PARTICLES else 1)
        self.cores = FreeCores(most) if threads is None else None
        self.threads = most
        self.sdf = sdf if "collider" in s.effects else None
        self.sdf_blocks = collider.block_minimum(sdf[0]) if self.sdf is not None else None
        self.yolks = yolks if ("buoyancy" in s.effects and yolks is not None and len(yolks["x"])) else None
        if self.yolks is not None:
            self.buffers["yolk_v"] = np.zeros_like(self.yolks["x"])
            self.buffers["yolk_prev"] = np.zeros_like(self.yolks["x"])
            self.yolk_accel = np.array([0.0, 0.0, s.yolk_accel])
        # mass scaling by height (contact_constraints): only where gravity says which way is up
        self.lift = (np.log(s.shock_propagation) / (2.0 * float(np.median(self.r[:self.n_moving])))
                     if "gravity" in s.effects and s.shock_propagation > 1.0 else 0.0)
        self.mu_s = s.mu_s if "friction" in s.effects else 0.0
        self.mu_k = s.mu_k if "friction" in s.effects else 0.0
        self.damping_factor = (1.0 - s.damping) ** (self.h * 60.0) if "damping" in s.effects else 1.0
        self.half = "adhesion" not in s.effects  # each pair listed once; the Jacobi adhesion needs full rows
        self.nbr_start = np.zeros(len(self.x) + 1, np.int64)
        self.nbr = np.zeros(0, np.int64)
        self.grid = ()  # (cell_start, order, dims) of the last neighbour build: the contacts' colouring

    # -- one substep ------------------------------------------------------------------------
    def substep(self) -> float:
        """Advance by h = dt/substeps; returns the largest constraint residual of the last iteration.

        Asleep elements are frozen: not predicted, not shape-matched, pairs of two asleep particles
        skipped, and an asleep particle holds still against an awake one like a static obstacle, so
        grains resting on sleepers load nothing onto them (a first design let pushes move sleepers:
        each awake grain then woke the column under it, and piles hardly slept). An awake partner
        moving faster than ``wake_step`` wakes the sleeper at the end of the substep (the impact is
        taken by the awake one alone for that substep). With every element asleep the substep
        solves nothing; every ``sleep_probe`` frames one substep solves all, under gravity, and
        re-tests them: a sleeper whose support went away falls and wakes."""
        with thread_count(self.threads):
            return self._substep()

    def _substep(self) -> float:
        s, d, h = self.s, self.dispatch, self.h
        awake = self.n_moving
        if s.sleep_speed > 0:
            probe = self.substeps_done % (s.substeps * s.sleep_probe) == 0
            awake = d("sleep", integrate.wake_flags, self.x, self.buffers["x_start"], self.start, self.asleep, probe,
                      self.awake, self.pushed)
        self.substeps_done += 1
        self.solved += awake
        if awake:
            self._prestabilise()
        if self.yolks is not None:  # drag towards the egg velocity of the last substep
            y = self.yolks
            d("buoyancy", buoyancy.yolk_predict, y["x"], self.buffers["yolk_v"], self.buffers["yolk_prev"],
              self.x, self.v, self.w, self.start, y["owner"], self.yolk_accel, h, s.yolk_drag)
        residual = self._solve() if awake else 0.0
        if self.yolks is not None:
            y = self.yolks
            d("buoyancy", buoyancy.yolk_contain, y["x"], self.buffers["yolk_v"], self.buffers["yolk_prev"], self.x,
              self.w, self.start, self.quats, y["owner"], y["centre"], y["room"], h)
        if s.sleep_speed > 0:
            d("sleep", integrate.sleep_clusters, self.v, self.x, self.buffers["x_start"], h, self.start,
              s.sleep_speed, self.asleep, self.pushed)
        self.time += h
        return residual

    def _solve(self) -> float:
        """Predict, the constraint iterations, velocities from positions; returns the residual."""
        s, d, h = self.s, self.dispatch, self.h
        self.moved = d("integrate", integrate.predict, self.x, self.v, self.w, self.r, self.accel, h, s.speed_clamp,
                       self.x_prev, *self._tracking(), self.awake)
        if self._refresh_neighbours() and "contact" in s.effects:  # overlap tolerated: as at the substep start
            d("contact", contact_constraints.overlap_allowance, self.x_prev, self.r, self.nbr_start, self.nbr, self.half, self.awake,
              s.overlap_decay_rate * h, self.buffers["allowance"])
        if self.matching:
            self.buffers["lambda"][:] = 0.0
        if self.bend is not None:
            self.buffers["bend_lambda"][:] = 0.0
        alpha = s.compliance / (h * h) if self.matching else 0.0
        adhesion_alpha = s.adhesion_compliance / (h * h)
        residual = 0.0
        if "adhesion" in s.effects:
            # once per substep, not per iteration: bonds accumulate no λ, so repeating them per
            # iteration made them rigid as iterations grew, and at 32 × 8 they fought the contacts
            # and pumped energy into the pile (accuracy benchmark)
            self._jacobi("adhesion", adhesion.adhesion_project, self.x, self.w, self.r, self.nbr_start,
                         self.nbr, self.awake, s.capture, adhesion_alpha, self.lift)
        for _ in range(s.iterations):
            residual = 0.0
            if {"contact", "friction"} & s.effects:  # one sweep: friction on each pair after its contact
                self._contacts(self.buffers.get("allowance", self.no_allowance), friction=True)
            # the element's shape is restored after the contacts, the walls have the last word
            if self.matching:
                residual = d("shape_matching", shape_matching.shape_match_project, self.x, self.w, self.q_rest,
                             self.start, self.quats, self.aqq_pinv, self.null_proj, self.buffers["lambda"],
                             alpha, s.linear_deformation, s.rotation_iterations, *self.quadratic_fit, self.awake)
            if self.bend is not None:
                residual = max(residual, d("bending", bending.bend_project, self.x, self.w, *self.bend, self.quats,
                                           self.buffers["bend_lambda"], s.bend_compliance / (h * h), self.awake))
            if self.sdf is not None:
                d("collider", collider.collider_project, self.x, self.x_prev, self.r, self.w, *self.sdf,
                  self.sdf_blocks, self.mu_s, self.mu_k)
        self.moved = d("integrate", integrate.update_velocity, self.x, self.x_prev, self.v, self.r, h, s.speed_clamp,
                       self.damping_factor, *self._tracking())
        return residual

    def _tracking(self):
        """(x_built, moved) for the displacement check folded into predict / update_velocity."""
        return (self.buffers["x_built"], self.buffers["moved"]) if self.pairs else (self.no_lists, self.no_allowance)

    def _refresh_neighbours(self) -> bool:
        """Rebuild the Verlet lists once a particle has moved half the skin since the last build
        (``self.moved``: measured by the last predict / update_velocity, or inf before the first)."""
        if self.pairs and self.moved > 0.5 * self.skin:
            self.nbr_start, self.nbr, *self.grid = self.dispatch("neighbours", spatial_hash.neighbour_lists, self.x,
                                                                 self.r, self.elem, self.reach, self.cell,
                                                                 self.n_moving, self.half)
            self.buffers["x_built"][:] = self.x
            self.moved = 0.0
            if "contact" in self.s.effects:
                self.buffers["allowance"] = np.zeros(len(self.nbr))
            return True
        return False

    def _prestabilise(self):
        """Resolve the overlaps left at the start of the substep before predicting (Macklin et al.
        2014 §4.2 pre-stabilisation): moved before x_prev is taken, they add no velocity, so deep
        initial overlaps separate instead of bursting."""
        self._refresh_neighbours()
        if "contact" in self.s.effects:
            none = self.buffers["allowance"]
            none[:] = 0.0
            self._contacts(none, wake_step=np.inf)
            self.dispatch("contact", contact_constraints.overlap_allowance, self.x, self.r, self.nbr_start, self.nbr, self.half,
                          self.awake, self.s.overlap_decay_rate * self.h, self.buffers["allowance"])
        if self.sdf is not None:
            self.dispatch("collider", collider.collider_project, self.x, self.x, self.r, self.w, *self.sdf,
                          self.sdf_blocks, 0.0, 0.0)

    def _contacts(self, allowance, friction=False, wake_step=None):
        """One Gauss–Seidel sweep of the contacts (if asked) and, with ``friction`` and the effect,
        friction on each pair just before its normal correction; one run of slabs per thread. ``wake_step``: see
        ``__init__`` (pre-stabilisation passes inf: the overlaps it undoes are no impact)."""
        s = self.s
        normal = "contact" in s.effects
        rub = friction and "friction" in s.effects
        family = ("contact",) * normal + ("friction",) * rub
        wake_step = self.wake_step if wake_step is None else wake_step
        self.dispatch(family, contact_constraints.contact_sweep, self.x, self.x_prev, self.w, self.r, self.nbr_start, self.nbr, self.half, self.awake,
                      self.pushed, wake_step, allowance, self.lift, self.mu_s if rub else 0.0, self.mu_k, normal,
                      self.threads, *self.grid)

    def _jacobi(self, family, kernel, *args):
        out = self.buffers["scratch"]
        self.dispatch(family, kernel, *args, out)
        self.x, self.buffers["scratch"] = out, self.x

    # -- one frame --------------------------------------------------------------------------
    def frame(self) -> None:
        """``substeps`` substeps, then the per-frame diagnostics."""
        if self.cores is not None:
            self.threads = self.cores.threads()
        residual = 0.0
        for k in range(self.s.substeps):
            if k == self.s.substeps - 1:
                self.x_mark[:] = self.x
            residual = self.substep()
        with thread_count(self.threads):
            self._diagnose(residual)

    def _diagnose(self, residual):
        pen = 0.0
        if "contact" in self.s.effects:
            pen = contact_constraints.max_penetration_ratio(self.x, self.r, self.nbr_start, self.nbr)
        if self.sdf is not None:
            pen = max(pen, collider.collider_penetration(self.x, self.r, *self.sdf))
        dg = self.diagnostics
        dg.penetration.append(float(pen))
        dg.residual.append(float(residual))
        # from the motion over the last substep, not from v: a resting particle that pre-stabilisation
        # lifts out of its tolerated overlap and the solve lets sink back has v = −Δ/h but stands still
        dg.kinetic_energy.append(float(integrate.kinetic_energy((self.x - self.x_mark) / self.h, self.w)))
        dg.sleeping.append(float(self.asleep.mean()) if self.s.sleep_speed > 0 else 0.0)
        dg.solved.append(self.solved / (self.s.substeps * self.n_moving))
        self.solved = 0

    def rotations(self) -> np.ndarray:
        """Current cluster rotations (m, 3, 3) from the warm-started quaternions."""
        out = np.empty((len(self.quats), 3, 3))
        for c in range(len(self.quats)):
            shape_matching.quat_to_matrix(self.quats[c], out[c])
        return out

    def centres(self) -> np.ndarray:
        """Mass-weighted cluster centres (m, 3)."""
        x, w = self.x[:self.n_moving], self.w[:self.n_moving]
        m = shape_matching.particle_masses(w)
        sums = np.add.reduceat(x * m[:, None], self.start[:-1], axis=0)
        return sums / np.add.reduceat(m, self.start[:-1])[:, None]
