"""The XPBD substep loop — SPEC §3 (G §3.3; Macklin et al. 2016): predict, iterate constraint
families, update velocities; only the requested effects allocate buffers and run kernels.

In Newton's shape: a ``Model`` (what a run does not change, ``model``), a ``State`` (what each
substep changes, ``state``), a ``Control`` (what a caller may change between steps, ``state``),
``Contacts`` (the neighbour lists and what each pair keeps across substeps, ``buffers``) and
``XpbdSolver.step(state_in, state_out, control, contacts, dt)``; ``SolverSettings`` (``settings``) are
fixed per solver, which holds the kernels' scratch and the settings in the form the kernels take
(``Coefficients``). Kernel arguments come in that order too, each a named bundle (issue 45 §1; a NamedTuple
numba takes as one argument): the state's arrays (``state.StateArrays``, built once per solve: the adhesion
swaps the positions), the model's (``model.ModelArrays``, once per run), the family's own data and buffers,
then its rule (``integrate.Motion``, ``shape_matching.MatchRule``, ``adhesion.AdhesionRule``, ``glue.GlueRule``,
the contacts' ``ContactRule``, ``friction_models.FrictionRule``).

Every kernel call goes through ``KernelDispatch``, which counts calls per constraint family: the
effects-gating test and the effects-cost benchmark read those counters.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numba
import numpy as np

from . import (
    adhesion,
    bending,
    buoyancy,
    collider,
    contact_constraints,
    glue,
    integrate,
    parting,
    shape_matching,
    spatial_hash,
)
from .buffers import NO_TRACKING, ClusterBuffers, Contacts, ListRows, NeighbourLists, Tracking
from .friction_models import NO_FRICTION, FrictionRule
from .model import Model
from .settings import (
    CONTACT_DAMPING,
    CRUSH_STRAIN,
    HANDOFF_DEPENETRATION,
    ROTATION_ITERATIONS,
    SETTLE_TIME,
    SLEEP_PROBE,
    SQUEEZE_LOAD,
    WAKE_ACCEL,
    YOLK_DRAG,
    SolverSettings,
)
from .state import Control, State
from .step_limits import MAX_TRAVEL, check_gravity_step, most_pieces, solve_pieces
from .threads import FreeCores, thread_count

# below this many particles the kernels run on one thread: threads gain nothing there (ikura don,
# 2,480 particles: equal times); above, on the cores other processes leave free (``threads``)
PARALLEL_PARTICLES = 4096
NO_GLUED = np.zeros(0, np.bool_)  # no list entry glued: every pair's friction mass-scaled (``XpbdSolver._stuck``)


class KernelDispatch:
    """Calls kernels by family name and counts the calls (what ran, and how often)."""

    def __init__(self):
        self.calls: Counter[str] = Counter()

    def __call__(self, family: str | tuple[str, ...], kernel, *args):
        for name in (family,) if isinstance(family, str) else family:  # a fused kernel counts for each
            self.calls[name] += 1
        return kernel(*args)


@dataclass(frozen=True, eq=False)
class Coefficients:
    """The settings as the kernels take them, derived once per run; effects that are off give the
    neutral value (no gravity, μ = 0, damping factor 1, no height scaling)."""

    h: float  # one solve, s: the substep, or its share when a fast particle splits it (``pieces``)
    pieces: int  # solves per substep (``solve_pieces``)
    clamp: float  # speed clamp per solve, radii (≤ MAX_TRAVEL)
    accel: np.ndarray  # (1, 3) gravity, mm/s²: the default ``Control``'s
    friction: FrictionRule  # μs, μk (0 without 'friction') and where the slip is measured from
    damping: float  # velocity factor per substep
    # mass scaling by height (``contact_constraints``), 1/mm: only where gravity says which way is up
    lift: float
    upright: bool  # gravity on: a lower particle acts at least as heavy as one resting on it (``contact_constraints``)
    # an awake particle that moves more than this in a substep wakes the sleepers it touches: the
    # sleep threshold plus the step gravity adds to one resting on them
    wake_step: float
    alpha: float  # XPBD α̃ = compliance / h² of shape matching, bending, adhesion
    bend_alpha: float
    adhesion_alpha: float
    yolk_accel: np.ndarray  # (3,) buoyant acceleration of the yolks: the default ``Control``'s
    # adhesion's pull at the capture distance as a friction load per unit of the pair's inverse mass (mm·g): F·h²,
    # F = capture / adhesion compliance; 0 without 'adhesion' or anchors (``contact_constraints._project_slab``)
    cohesion: float
    # α̃ of one element's face at its contacts (1/g; 0 = rigid contacts) and the overlap (mm) a face gives before it
    # turns rigid (``contact_constraints.face_compliance``, from ``squeeze_strain``)
    contact_alpha: float
    crush: float

    @classmethod
    def of(cls, model: Model, settings: SolverSettings, pieces: int = 1) -> Coefficients:
        """The coefficients of a substep run as ``pieces`` solves."""
        s, effects = settings, settings.effects
        h = settings.h / pieces
        gravity = "gravity" in effects
        radii = model.r[: model.n_moving]
        face, crush = (
            contact_constraints.face_compliance(
                model.r, model.q_rest, model.start, s.squeeze_strain, SQUEEZE_LOAD, CRUSH_STRAIN
            )
            if s.squeeze_strain > 0 and "contact" in effects and model.elements > 0
            else (0.0, 0.0)
        )
        lift = (
            np.log(s.shock_propagation) / (2.0 * float(np.median(radii)))
            if gravity and s.shock_propagation > 1.0
            else 0.0
        )
        return cls(
            h=h,
            pieces=pieces,
            clamp=min(MAX_TRAVEL, s.speed_clamp / pieces),
            accel=np.array([[0.0, 0.0, -s.gravity]]) if gravity else np.zeros((1, 3)),
            friction=s.friction.rule(
                s.mu_s if "friction" in effects else 0.0, s.mu_k if "friction" in effects else 0.0
            ),
            damping=(1.0 - s.damping) ** (h * 60.0) if "damping" in effects else 1.0,
            lift=lift,
            upright=gravity,
            wake_step=h * s.sleep_speed + (s.gravity if gravity else 0.0) * h**2,
            alpha=s.compliance / (h * h) if model.moments is not None else 0.0,
            bend_alpha=s.bend_compliance / (h * h),
            adhesion_alpha=s.adhesion_compliance / (h * h),
            yolk_accel=np.array([0.0, 0.0, s.yolk_accel]),
            cohesion=s.friction.cohesion(s.capture, h, s.adhesion_compliance) if "adhesion" in effects else 0.0,
            contact_alpha=face * 1e-6 / (h * h),  # mm/N → s²/g, over h²
            crush=crush,
        )


@dataclass(frozen=True)
class SolveRules:
    """What the kernels take of a substep run as ``pieces`` solves: the ``Coefficients`` and the rules derived
    from them (shape matching, adhesion, sleeping)."""

    coefficients: Coefficients
    match: shape_matching.MatchRule
    adhesion: adhesion.AdhesionRule
    sleep: integrate.SleepRule

    @classmethod
    def of(cls, model: Model, settings: SolverSettings, pieces: int) -> SolveRules:
        k = Coefficients.of(model, settings, pieces)
        steps = max(1, round(SETTLE_TIME / k.h))
        return cls(
            k,
            shape_matching.MatchRule(k.alpha, settings.linear_deformation, ROTATION_ITERATIONS),
            adhesion.AdhesionRule(settings.capture, k.adhesion_alpha, k.lift),
            integrate.SleepRule(settings.sleep_speed * k.h, WAKE_ACCEL * k.h * k.h, steps),
        )


@dataclass
class Diagnostics:
    """Per-frame scalars (SPEC §3 log): max penetration / radius, residual, kinetic energy, sleeping
    share; ``solved``, the share of the moving particles solved per solve (awake, 1 without sleeping): the
    work sleeping leaves; and ``solves``, the solves the frame took (substeps, more where a fast particle
    split one: ``XpbdSolver._pieces``)."""

    penetration: list[float] = field(default_factory=list)
    residual: list[float] = field(default_factory=list)
    kinetic_energy: list[float] = field(default_factory=list)
    sleeping: list[float] = field(default_factory=list)
    solved: list[float] = field(default_factory=list)
    solves: list[int] = field(default_factory=list)


class XpbdSolver:
    """Steps a ``State`` of ``model`` under ``settings``, substep by substep (``substep``) or frame by
    frame (``frame``, which also logs ``diagnostics``); one state per solver (its neighbour lists
    follow that state).

    ``threads``: a fixed thread count for the kernels, or None to use the cores other processes
    leave free (``threads.FreeCores``); the results are the same either way.
    """

    def __init__(
        self, model: Model, settings: SolverSettings, dispatch: KernelDispatch | None = None, threads: int | None = None
    ):
        self.model = model
        self.settings = settings
        self.dispatch = dispatch or KernelDispatch()
        radii = model.r[: model.n_moving]
        self.most = most_pieces(settings)
        if "gravity" in settings.effects and len(radii):  # at the solves a resting particle gets
            r_min = float(radii.min())
            rest = solve_pieces(settings.gravity * settings.h**2 / r_min, self.most)
            check_gravity_step(settings, rest, r_min, float(np.median(radii)))
        self._rules: dict[int, SolveRules] = {}  # per solves per substep, derived when first needed
        self._use(1)  # one solve per substep, until a frame finds a particle too fast for it
        self.steps = settings.substeps  # substeps per frame
        self.clusters = ClusterBuffers.allocate(model)
        self.model_arrays = model.arrays()  # the kernels' bundle of the model's arrays, once per run
        self.yolk_room = model.yolks.arrays() if model.yolks is not None else None
        self.moments = model.moments.args() if model.moments is not None else ()
        self.quadratic = model.quadratic.args() if model.quadratic is not None else ()
        self.bend_rows = model.bend.args() if model.bend is not None else None
        self.collider_grid = model.collider.args() if model.collider is not None else None
        g = model.glue
        self.glue_bundles = (g.rows(), g.members(), g.floors()) if g is not None else None
        self.glue_rule = glue.GlueRule(ROTATION_ITERATIONS, settings.glue_tear, settings.glue)
        self.contacts = Contacts.allocate(model, settings)  # the contacts ``frame`` steps with
        self.default_control = self.control()  # the control ``frame`` steps with
        self.diagnostics = Diagnostics()
        # the glued regions' goals per membership, NaN until matched (``glue``)
        self.glue_goal = np.full((len(model.glue.member), 3), np.nan) if model.glue is not None else None
        # the lists the glued floors were found for, each entry's link, pressed overlap and whether its grains are
        # still glued (``_pressed``)
        self.glue_floors = (None, None, None, NO_GLUED)
        self.x_mark = model.x0.copy()  # positions at the start of a frame's last solve (diagnostics)
        self.x_begin = model.x0.copy()  # positions at the start of the current solve
        self.kept = 0.0  # mm: the overlap pre-stabilisation leaves compliant contacts (``_kept``)
        self.solved = 0  # particles solved over the substeps of the current frame
        # threads: fixed, or None = one below PARALLEL_PARTICLES, else the free cores, re-measured per frame
        most = (
            min(threads, numba.config.NUMBA_NUM_THREADS)
            if threads
            else (numba.get_num_threads() if len(model.x0) >= PARALLEL_PARTICLES else 1)
        )
        self.cores = FreeCores(most) if threads is None else None
        self.threads = most

    def _use(self, pieces: int) -> None:
        """Make the rules of a substep run as ``pieces`` solves the current ones (``coefficients``, the shape
        matching's, adhesion's and sleeping's rules), deriving them the first time."""
        rules = self._rules.get(pieces)
        if rules is None:
            rules = self._rules[pieces] = SolveRules.of(self.model, self.settings, pieces)
        self.coefficients = rules.coefficients
        self.match_rule, self.adhesion_rule, self.sleep_rule = rules.match, rules.adhesion, rules.sleep

    def _pieces(self, st: State) -> int:
        """Solves for the next substep: by the furthest an awake particle would travel in it, in its own
        radii, |v|·h + g·h² (``solve_pieces``)."""
        if self.most == 1:
            return 1
        h, n = self.settings.h, self.model.n_moving
        speed = np.sqrt(np.einsum("ij,ij->i", st.v[:n], st.v[:n]))
        step = float(np.linalg.norm(self.default_control.accel[0])) * h * h
        travel = (speed * h + step) / self.model.r[:n]
        awake = st.awake[:n]
        return solve_pieces(float(travel[awake].max()) if awake.any() else 0.0, self.most)

    def control(self) -> Control:
        """A ``Control`` with the settings' accelerations (fresh arrays a caller may change between steps)."""
        k = self.coefficients
        return Control(accel=k.accel.copy(), yolk_accel=k.yolk_accel.copy())

    # -- one step ---------------------------------------------------------------------------
    def step(self, state_in: State, state_out: State, control: Control, contacts: Contacts | None, dt: float) -> float:
        """Advance ``state_in`` by one solve into ``state_out`` (they may be the same state), under ``control``,
        with ``contacts`` (``Contacts.allocate``; they follow the particles they were built for); returns the
        largest constraint residual of the last iteration. ``dt`` must be the solve the settings fix,
        h = dt / substeps / ``Coefficients.pieces`` (``Coefficients.h``): the coefficients are derived for it.

        Asleep elements are frozen: not predicted, not shape-matched, pairs of two asleep particles
        skipped, and an asleep particle holds still against an awake one like a static obstacle, so
        grains resting on sleepers load nothing onto them (a first design let pushes move sleepers:
        each awake grain then woke the column under it, and piles hardly slept). An awake partner
        moving faster than ``Coefficients.wake_step`` wakes the sleeper at the end of the substep
        (the impact is taken by the awake one alone for that substep). With every element asleep the
        substep solves nothing; every ``SLEEP_PROBE`` frames one substep solves all, under gravity,
        and re-tests them: a sleeper whose support went away falls and wakes."""
        h = self.settings.h
        if not abs(dt - h) <= 1e-12 * h:
            raise ValueError(f"dt: this solver steps by h = {h:.6g} s (dt / substeps of its settings), not {dt:.6g} s")
        if state_out is not state_in:
            state_out.assign(state_in)
        with thread_count(self.threads):
            return self._substep(state_out, control, contacts)

    def _substep(self, st: State, control: Control, contacts: Contacts | None, first: bool = True) -> float:
        """One solve under the current rules (``_use``); ``first``: the substep's first solve."""
        s, d, k, m = self.settings, self.dispatch, self.coefficients, self.model
        awake = m.n_moving
        if s.sleep_speed > 0:
            probe = first and st.substeps_done % (self.steps * SLEEP_PROBE) == 0
            awake = d("sleep", integrate.wake_flags, st.arrays(), self.model_arrays, probe)
        st.substeps_done += first
        self.solved += awake
        if awake:
            if m.collider is not None:
                d("friction", collider.wall_means, m.start, st.arrays(), k.friction)
            self.x_begin[:] = st.x  # before pre-stabilisation (``integrate.update_velocity``)
            self._prestabilise(st, contacts)
        y = st.yolks
        if y is not None:  # drag towards the egg velocity of the last substep
            yolks, motion = y.arrays(), buoyancy.YolkMotion(control.yolk_accel, k.h, YOLK_DRAG)
            d("buoyancy", buoyancy.yolk_predict, yolks, st.arrays(), self.model_arrays, self.yolk_room, motion)
        residual = self._solve(st, control, contacts) if awake else 0.0
        if y is not None:  # after the solve: the adhesion may have swapped the positions
            d("buoyancy", buoyancy.yolk_contain, yolks, st.arrays(), self.model_arrays, self.yolk_room, motion)
        if s.sleep_speed > 0:
            d(
                "sleep",
                integrate.sleep_clusters,
                st.arrays(),  # after the solve: the adhesion may have swapped the positions
                self.model_arrays,
                self._contact_rows(contacts),
                st.slow_steps,
                self.sleep_rule,
            )
        st.time += k.h
        return residual

    def _solve(self, st: State, control: Control, contacts: Contacts | None) -> float:
        """Predict, the constraint iterations, velocities from positions; returns the residual."""
        s, d, k, m = self.settings, self.dispatch, self.coefficients, self.model
        pairs, clusters = contacts, self.clusters
        gain = s.depenetration_speed
        if st.time < s.handoff_until:  # a handed-on state's overlaps come apart without a launch (settings)
            gain = min(gain, HANDOFF_DEPENETRATION)
        motion = integrate.Motion(control.accel, k.h, k.clamp, k.damping, gain)
        moved = d("integrate", integrate.predict, st.arrays(), self.model_arrays, self._tracking(pairs), motion)
        self._track(pairs, moved)
        refreshed = self._refresh_neighbours(st, pairs)
        if refreshed and "contact" in s.effects:  # overlap tolerated: as after pre-stabilisation
            a = st.arrays()
            rows = contact_constraints.PairRows(*pairs.lists.sweep_rows())
            # the overlaps at x_prev, the positions before the prediction
            d(
                "contact",
                contact_constraints.overlap_allowance,
                a._replace(x=a.x_prev),
                self.model_arrays,
                rows,
                0.0,
                pairs.allowance,
            )
            self._kept(pairs)
            self._pressed(st, pairs)
        if clusters is not None:
            clusters.clear()
        residual = 0.0
        if "adhesion" in s.effects:
            # once per substep, not per iteration: bonds accumulate no λ, so repeating them per
            # iteration made them rigid as iterations grew, and at 32 × 8 they fought the contacts
            # and pumped energy into the pile (accuracy benchmark)
            self._adhesion(st, pairs)
        a = st.arrays()  # after the adhesion, which swaps the positions: the iterations swap none
        first = True
        for _ in range(s.iterations):
            residual = 0.0
            if {"contact", "friction"} & s.effects:  # one sweep: friction on each pair after its contact
                self._contacts(st, pairs, friction=True)
            if m.glue is not None:  # glued grains keep their places, then each grain its shape
                self._glue(st, tear=first)
            # the element's shape is restored after the contacts, the walls have the last word
            if m.moments is not None:
                residual = d(
                    "shape_matching",
                    shape_matching.shape_match_project,
                    a,
                    self.model_arrays,
                    *self.moments,
                    clusters.lam,
                    self.match_rule,
                    *self.quadratic,
                )
            if m.bend is not None:
                bends = self.bend_rows
                residual = max(
                    residual,
                    d("bending", bending.bend_project, a, self.model_arrays, bends, clusters.bend_lam, k.bend_alpha),
                )
            first = False
            if m.collider is not None:
                d("collider", collider.collider_project, a, self.model_arrays, self.collider_grid, k.friction)
        moved = d(
            "integrate",
            integrate.update_velocity,
            a,
            self.model_arrays,
            self.x_begin,
            self._tracking(pairs),
            motion,
        )
        self._track(pairs, moved)
        return residual

    @staticmethod
    def _contact_rows(contacts: Contacts | None) -> ListRows:
        """(nbr_start, nbr, order) of the neighbour lists, or empty lists (no pair effects)."""
        if contacts is None:
            return ListRows(np.zeros(1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64))
        return contacts.lists.csr()

    @staticmethod
    def _tracking(contacts: Contacts | None) -> Tracking:
        """(x_built, moved) for the displacement check folded into predict / update_velocity."""
        return contacts.tracking() if contacts is not None else NO_TRACKING

    @staticmethod
    def _track(contacts: Contacts | None, moved: float) -> None:
        if contacts is not None:
            contacts.displacement = moved

    def _refresh_neighbours(self, st: State, pairs: Contacts | None) -> bool:
        """Rebuild the Verlet lists once a particle has moved half the skin since the last build."""
        m = self.model
        if pairs is None or not pairs.stale():
            return False
        nbr_start, nbr, at, *grid = self.dispatch(
            "neighbours",
            spatial_hash.neighbour_lists,
            st.x,
            m.r,
            m.elem,
            pairs.reach,
            pairs.cell,
            m.n_moving,
            pairs.lists.half,
        )
        old = pairs.lists
        pairs.lists = NeighbourLists(nbr_start, nbr, at, old.half, *grid)
        if "friction" in self.settings.effects:  # the model's per-pair data follows the pairs
            self.settings.friction.lists_rebuilt(self.dispatch, old, pairs, m)
        pairs.x_built[:] = st.x
        pairs.displacement = 0.0
        pairs.parting = parting.entry_flags(nbr_start, nbr, pairs.lists.order, m.elem, pairs.deep)
        if "contact" in self.settings.effects:
            pairs.allowance = np.zeros(len(nbr))
            if self.coefficients.contact_alpha > 0:  # this substep's elastic overlaps start afresh
                pairs.spring = np.zeros(len(nbr))
        return True

    def _prestabilise(self, st: State, pairs: Contacts | None) -> None:
        """Resolve the overlaps left at the start of the substep before predicting (Macklin et al.
        2014 §4.2 pre-stabilisation): moved before x_prev is taken, they add no velocity. Each overlap is resolved
        in full; what the sweep leaves is tolerated by the substep's solve (``allowance``, decay 0). A decay (giving up
        at most decay·min(r) of an old overlap per substep) left the tolerated overlaps in place on the reduced indica
        bowl (skin after the contact step 0.211 instead of 0.180; docs/look.md).
        Shape matching then pulls a cluster back part of the way, and the solve turns that into speed, h times more
        at more substeps; ``SolverSettings.depenetration_speed`` bounds it (``integrate.update_velocity``)."""
        d, m = self.dispatch, self.model
        self._refresh_neighbours(st, pairs)
        if "contact" in self.settings.effects:
            allowance = contact_constraints.overlap_allowance
            if self.coefficients.contact_alpha > 0:  # overlaps up to the crush depth are the compliance's (``_kept``)
                pairs.spring[:] = 0.0
                fresh = st.substeps_done <= 1 or st.time < self.settings.handoff_until  # a start, or one handed on
                self.kept = 0.0 if fresh else 2.0 * self.coefficients.crush
            pairs.allowance[:] = self.kept
            if "friction" in self.settings.effects:
                k = self.coefficients
                self.settings.friction.pool_loads(self.dispatch, pairs, k.friction, k.cohesion)
            pairs.load[:] = 0.0
            self._pressed(st, pairs)
            self._contacts(
                st, pairs, friction=self.settings.friction.rubs_in_prestabilisation, wake_step=np.inf, soft=False
            )
            rows = contact_constraints.PairRows(*pairs.lists.sweep_rows())
            d("contact", allowance, st.arrays(), self.model_arrays, rows, 0.0, pairs.allowance)
            self._kept(pairs)
            self._pressed(st, pairs)
        if m.collider is not None:  # x_prev = x: no swept test, no friction
            a = st.arrays()
            d(
                "collider",
                collider.collider_project,
                a._replace(x_prev=a.x),
                self.model_arrays,
                self.collider_grid,
                NO_FRICTION,
            )

    def _kept(self, pairs: Contacts) -> None:
        """Compliant contacts: after a run's first substep, or a handed-on state's first frames (``HANDOFF_FRAMES``),
        whose pre-stabilisation separates the overlaps they start with as rigid contacts do (a settled
        bed handed from 10 to 40 substeps with compliant ones moved at 22.6 mm/s mean in the first frame, against the
        14 mm/s test_handoff.py allows), pre-stabilisation leaves every overlap up to
        the crush depth of two faces (``kept``), and
        the solve holds all of it by the compliance (the allowance is what lies beyond). A rigid lift by
        pre-stabilisation of an overlap that grew after the pair's last correction (shape matching, the walls) carries
        part of a load without a λ: kept only where a pair had carried a load, a plate rested on 1/3 of the overlap
        its weight gives."""
        if self.kept > 0:
            np.maximum(pairs.allowance - self.kept, 0.0, out=pairs.allowance)

    def _contacts(self, st: State, pairs: Contacts, friction=False, wake_step=None, soft=True) -> None:
        """One Gauss–Seidel sweep of the contacts (if asked) and, with ``friction`` and the effect,
        friction on each pair just before its normal correction; one run of slabs per thread.
        ``wake_step``: ``Coefficients.wake_step`` unless given (pre-stabilisation passes inf: the
        overlaps it undoes are no impact). ``soft``: compliant contacts where the settings have them
        (pre-stabilisation's are rigid: it moves each pair to the overlap its compliance kept)."""
        s, k = self.settings, self.coefficients
        lists = pairs.lists
        normal = "contact" in s.effects
        rub = friction and "friction" in s.effects
        family = ("contact",) * normal + ("friction",) * rub
        wake_step = k.wake_step if wake_step is None else wake_step
        cc = contact_constraints
        self.dispatch(
            family,
            cc.contact_sweep,
            st.arrays(),
            self.model_arrays,
            cc.PairRows(*lists.sweep_rows()),
            cc.Colouring(*lists.grid()),
            cc.PairEntries(
                pairs.allowance,
                pairs.anchor,
                pairs.load,
                pairs.held,
                pairs.mode,
                pairs.rubbed,
                self._stuck(lists),
                pairs.spring,
                pairs.parting,
            ),
            cc.ContactRule(
                float(wake_step),
                k.lift,
                k.upright,
                k.friction.mu_s if rub else 0.0,
                k.friction.mu_k,
                k.friction.anchored,
                normal,
                k.cohesion,
                k.contact_alpha if soft else 0.0,
                k.crush,
                CONTACT_DAMPING,
            ),
            self.threads,
        )

    def _adhesion(self, st: State, pairs: Contacts) -> None:
        """One Jacobi sweep of the adhesion bonds into the scratch copy, which becomes the positions."""
        out = pairs.scratch
        self.dispatch(
            "adhesion",
            adhesion.adhesion_project,
            st.arrays(),
            self.model_arrays,
            pairs.lists.csr(),
            self.adhesion_rule,
            out,
        )
        st.x, pairs.scratch = out, st.x

    def _pressed(self, st: State, pairs: Contacts) -> None:
        """Glued grains' contacts tolerate the overlap the press left them (``glue.glued_allowance``); the
        entries' links and pressed overlaps are found once per build of the lists (``glue.glued_floors``)."""
        m, lists = self.model, pairs.lists
        if m.glue is None:
            return
        if self.glue_floors[0] is not lists:
            n = len(lists.nbr)
            entries = glue.GluedEntries(np.empty(n, np.int64), np.empty(n), np.zeros(n, np.bool_))
            rows = contact_constraints.PairRows(*lists.sweep_rows())
            self.dispatch("glue", glue.glued_floors, self.model_arrays, rows, self.glue_bundles[2], entries)
            self.glue_floors = (lists, *entries)
        entries = glue.GluedEntries(*self.glue_floors[1:])
        self.dispatch("glue", glue.glued_allowance, entries, self._glue_arrays(st), pairs.allowance)

    def _stuck(self, lists) -> np.ndarray:
        """Per entry of ``lists``, whether its grains are still glued (``_pressed``): the sweep splits those pairs'
        friction by the true masses (``contact_constraints.PairEntries``); empty without glue."""
        return self.glue_floors[3] if self.glue_floors[0] is lists else NO_GLUED

    def _glue(self, st: State, tear: bool) -> None:
        """Match the glued regions and pull each particle towards its regions' goals (``glue``); with
        ``tear`` (once per substep) the links left further than ``glue_tear`` from their goals tear."""
        a, regions, members, arrays = st.arrays(), self.glue_bundles[0], self.glue_bundles[1], self._glue_arrays(st)
        self.dispatch("glue", glue.glue_match, a, self.model_arrays, regions, arrays, self.glue_rule, tear)
        self.dispatch("glue", glue.glue_pull, a, members, arrays, self.glue_rule)

    def _glue_arrays(self, st: State):
        """The glue's changing arrays of ``st`` (``glue.GlueArrays``)."""
        return glue.GlueArrays(st.glued, st.glue_quats, self.glue_goal)

    # -- one frame --------------------------------------------------------------------------
    def frame(self, state: State) -> None:
        """``substeps`` substeps of ``state`` in place, with the solver's own ``contacts`` and ``default_control``,
        each as the solves its fastest particle needs (``_pieces``), then the per-frame diagnostics."""
        if self.cores is not None:
            self.threads = self.cores.threads()
        residual = 0.0
        solves = 0
        with thread_count(self.threads):
            for i in range(self.steps):
                pieces = self._pieces(state)
                self._use(pieces)
                for j in range(pieces):
                    if i == self.steps - 1 and j == pieces - 1:
                        self.x_mark[:] = state.x
                    residual = self._substep(state, self.default_control, self.contacts, first=j == 0)
                solves += pieces
            self._diagnose(state, residual, solves)
        self._part(state)
        self._use(1)

    def _part(self, st: State) -> None:
        """Give the pairs placed inside one another that have parted their friction back (``parting``)."""
        pairs, m = self.contacts, self.model
        if pairs is None or not len(pairs.deep):
            return
        pairs.deep = parting.still_deep(st.x, m.r, m.start, pairs.deep)
        lists = pairs.lists
        pairs.parting = parting.entry_flags(lists.nbr_start, lists.nbr, lists.order, m.elem, pairs.deep)

    def _diagnose(self, st: State, residual: float, solves: int) -> None:
        s, m = self.settings, self.model
        pen = 0.0
        if "contact" in s.effects:
            pen = contact_constraints.max_penetration_ratio(st.x, m.r, *self.contacts.lists.csr())
        if m.collider is not None:
            pen = max(pen, collider.collider_penetration(st.x, m.r, *m.collider.grid()))
        dg = self.diagnostics
        dg.penetration.append(float(pen))
        dg.residual.append(float(residual))
        # from the motion over the last substep, not from v: a resting particle that pre-stabilisation
        # lifts out of its tolerated overlap and the solve lets sink back has v = −Δ/h but stands still
        dg.kinetic_energy.append(float(integrate.kinetic_energy((st.x - self.x_mark) / self.coefficients.h, m.w)))
        dg.sleeping.append(float(st.asleep.mean()) if s.sleep_speed > 0 else 0.0)
        dg.solved.append(self.solved / (solves * m.n_moving))
        dg.solves.append(solves)
        self.solved = 0
