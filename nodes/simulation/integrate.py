"""Substep prediction and velocity update — SPEC §3 (XPBD: predict x̃, solve, v = (xⁿ⁺¹ − xⁿ)/Δt).

The speed clamp (|v| ≤ clamp·r/h) is what keeps a particle from crossing a wall or another
particle between two projections; it is always on (stability, not an effect). The solver runs
clamps above one radius per substep as several solves of ≤ 1 r each (``step_limits.MAX_TRAVEL``): φ is
a distance (|∇φ| ≤ 1), so a particle that starts a solve clear of a wall (φ ≥ r) and travels ≤ r
ends with its centre in free space (φ ≥ 0) and is pushed back out on its own side, however thin
the wall. Damping acts on velocities only; sleeping (``wake_flags``, ``sleep_clusters``)
freezes resting elements: an asleep particle is not predicted and the contacts hold it like a
static obstacle, so it stays where it fell asleep until a fast neighbour runs into it or a probe
substep finds it unsupported (``solver.XpbdSolver.substep``).
"""

from typing import NamedTuple

import numpy as np
from numba import njit, prange


class Motion(NamedTuple):
    """What ``predict`` and ``update_velocity`` take of one solve (``solver.Coefficients.motion``, with the
    ``Control``'s acceleration): a named bundle, one numba argument."""

    accel: np.ndarray  # (1, 3) or (n, 3) mm/s²
    h: float  # the solve, s
    clamp: float  # speed clamp, radii per solve
    damping: float  # velocity factor per solve (1 = none)
    gain: float  # mm/s, the depenetration speed bound (inf = none)


@njit(cache=True, inline="always")
def _clamp(v, i, vmax):
    s = np.sqrt(v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] + v[i, 2] * v[i, 2])
    if s > vmax:
        f = vmax / s
        v[i, 0] *= f
        v[i, 1] *= f
        v[i, 2] *= f


@njit(cache=True, inline="always")
def _moved(x, x_built, i, moved):
    """Squared distance of particle i from where the neighbour lists were last built."""
    dx = x[i, 0] - x_built[i, 0]
    dy = x[i, 1] - x_built[i, 1]
    dz = x[i, 2] - x_built[i, 2]
    moved[i] = dx * dx + dy * dy + dz * dz


@njit(cache=True, inline="always")
def _predict_one(x, v, w, r, accel, h, clamp, x_prev, x_built, moved, awake, i):
    """``predict`` for particle i: its row of ``accel`` (one row for all, or one per particle), and the
    Verlet-list tracking when ``x_built`` holds a row per particle."""
    stride = 1 if accel.shape[0] == x.shape[0] else 0
    row = i * stride  # not ``i if … else 0``: numba unifies prange's index with 0 as a float
    for k in range(3):
        x_prev[i, k] = x[i, k]
    if w[i] > 0.0 and awake[i]:
        for k in range(3):
            v[i, k] += h * accel[row, k]
        _clamp(v, i, clamp * r[i] / h)
        for k in range(3):
            x[i, k] += h * v[i, k]
    if x_built.shape[0] == x.shape[0]:
        _moved(x, x_built, i, moved)


@njit(cache=True, parallel=True)
def predict(state, model, tracking, motion):
    """x_prev ← x; v += h·a (a per particle, (n, 3), or one row for all); clamp; x ← x + h·v —
    for the ``awake`` particles; asleep ones only get x_prev ← x (no gravity: they stay put).
    ``state``: ``StateArrays``, ``model``: ``ModelArrays`` (w, r), ``motion``: ``Motion`` (accel, h, clamp).

    Returns max_i |x_i − x_built_i| (the Verlet-list check, folded in to save a launch; 0 when
    ``tracking.x_built`` is empty, i.e. no neighbour lists). ``tracking.moved`` (n,) is scratch."""
    x, v, x_prev, awake = state.x, state.v, state.x_prev, state.awake
    w, r = model.w, model.r
    x_built, moved = tracking.x_built, tracking.moved
    accel, h, clamp = motion.accel, motion.h, motion.clamp
    n = x.shape[0]
    track = x_built.shape[0] == n
    for i in prange(n):
        _predict_one(x, v, w, r, accel, h, clamp, x_prev, x_built, moved, awake, i)
    return np.sqrt(moved.max()) if track and n > 0 else 0.0


@njit(cache=True, inline="always")
def _velocity_one(x, x_prev, x_begin, v, r, h, clamp, damping_factor, gain, x_built, moved, i):
    predicted = np.sqrt(v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] + v[i, 2] * v[i, 2])  # ``predict``'s v
    a = 0.0  # |x − x_prev|², the motion of the solve
    b = 0.0  # |x − x_begin|², the motion over the whole substep, pre-stabilisation included
    for k in range(3):
        a += (x[i, k] - x_prev[i, k]) ** 2
        b += (x[i, k] - x_begin[i, k]) ** 2
    ref = x_prev if a <= b else x_begin
    for k in range(3):
        v[i, k] = (x[i, k] - ref[i, k]) / h * damping_factor
    _clamp(v, i, min(clamp * r[i] / h, max(predicted, gain)))
    if x_built.shape[0] == x.shape[0]:  # Verlet-list tracking on
        _moved(x, x_built, i, moved)


@njit(cache=True, parallel=True)
def update_velocity(state, model, x_begin, tracking, motion):
    """v = (x − x_prev)/h or (x − x_begin)/h, whichever is shorter, clamped, times the damping factor
    (1 = none); zero restitution. ``gain`` (mm/s; inf = none): the solve leaves a particle no faster than
    max(its predicted speed, gain) — the constraints may slow it or turn it, but speed it up beyond
    ``gain`` only by carrying it (the positions keep their corrections): a maximum depenetration speed
    (PhysX's maxDepenetrationVelocity, Macklin et al. 2014 §4.2's bounded separation), so deep overlaps
    between jammed clusters come apart without launching them. ``x_begin``: the positions before
    pre-stabilisation. Its moves add
    no velocity (x_prev is taken after them), and they take none away when the solve undoes them: a
    resting particle that pre-stabilisation lifts and the solve lets sink back has not moved, and
    (x − x_prev)/h would give it a velocity the next prediction turns into real motion (jitter that
    never settles without sleeping: 7 mm/s at rest in the long-rest test).
    ``state``: ``StateArrays`` (x, v, x_prev), ``model``: ``ModelArrays`` (r), ``motion``: ``Motion`` (h, clamp,
    damping, gain), ``tracking``: ``buffers.Tracking``.
    Returns max_i |x_i − x_built_i| like ``predict``: the next substep's Verlet-list check."""
    x, v, x_prev = state.x, state.v, state.x_prev
    r = model.r
    x_built, moved = tracking.x_built, tracking.moved
    h, clamp, damping_factor, gain = motion.h, motion.clamp, motion.damping, motion.gain
    n = x.shape[0]
    track = x_built.shape[0] == n
    for i in prange(n):
        _velocity_one(x, x_prev, x_begin, v, r, h, clamp, damping_factor, gain, x_built, moved, i)
    return np.sqrt(moved.max()) if track and n > 0 else 0.0


@njit(cache=True, parallel=True)
def wake_flags(state, model, probe):
    """Per particle ``awake`` ← its element is awake (or ``probe``: every element is solved this
    substep), and for those particles x_start ← x, the sleep test's reference; ``pushed`` cleared;
    returns how many particles are awake. An asleep particle keeps the x_start of the substep it
    fell asleep in, so the test measures its drift since then. Particles outside ``start`` (static
    obstacles) are never touched: they stay asleep. ``state``: ``StateArrays``, ``model``: ``ModelArrays``."""
    x, x_start, asleep, awake, pushed = state.x, state.x_start, state.asleep, state.awake, state.pushed
    start = model.start
    m = start.shape[0] - 1
    count = 0
    for c in prange(m):
        on = probe or not asleep[c]
        for i in range(start[c], start[c + 1]):
            awake[i] = on
            pushed[i] = False
            if on:
                x_start[i, 0] = x[i, 0]
                x_start[i, 1] = x[i, 1]
                x_start[i, 2] = x[i, 2]
        if on:
            count += start[c + 1] - start[c]
    return count


@njit(cache=True, inline="always")
def _moved_sq(x, x_start, i):
    return (x[i, 0] - x_start[i, 0]) ** 2 + (x[i, 1] - x_start[i, 1]) ** 2 + (x[i, 2] - x_start[i, 2]) ** 2


@njit(cache=True, inline="always")
def _touching(x, r, i, j):
    """Particles i and j in contact, within 5 % of their radii sum (a resting contact the solve left
    just apart still counts)."""
    reach = 1.05 * (r[i] + r[j])
    return (x[i, 0] - x[j, 0]) ** 2 + (x[i, 1] - x[j, 1]) ** 2 + (x[i, 2] - x[j, 2]) ** 2 < reach * reach


class SleepRule(NamedTuple):
    """When an element falls asleep (``sleep_clusters``): what the solver reads of the settings once per run."""

    still: float  # mm: sleep_speed·h, the drift a resting particle may make in one substep
    still_probed: float  # mm: a·h² for the net acceleration a that wakes a sleeper (``settings.WAKE_ACCEL``)
    settle_steps: int  # substeps in a row an awake element must stay within ``still`` (``settings.SETTLE_TIME``)


@njit(cache=True, parallel=True)
def sleep_clusters(state, model, contact_rows, slow_steps, rule):
    """Put to sleep (and zero the velocities of) every element whose particles have all lain within
    ``rule.still`` (sleep_speed·h) of x_start for ``rule.settle_steps`` substeps in a row
    (``settings.SETTLE_TIME``, counted in ``slow_steps``, so the test spans the same time at any substep count),
    measured from before pre-stabilisation (an element asleep before this substep, solved by the probe from
    rest: within ``rule.still_probed``, a·h² for the net acceleration a that wakes it, so whether a sleeper on a
    slope wakes does not depend on the substep count), none of which was ``pushed``
    (``contact_constraints.sleeper_share``) and none of which touches a particle of another awake
    element that moved farther (``contact_rows``: the contact lists' (nbr_start, nbr, order), half or
    full, row p being particle order[p]'s: ``buffers.ListRows``; none without them). ``state``:
    ``StateArrays``, ``model``: ``ModelArrays`` (r, elem, start). An element pinned in an overlap that
    pre-stabilisation and the solve undo in turn has a velocity but no motion, and sleeps. Every other
    element is awake: an asleep one that a fast neighbour ran into wakes here.

    The touching rule keeps the supports of a moving element awake until it has settled on them:
    supports that fell asleep under it held still as obstacles, it bounced on them at up to 11 mm/s
    and woke them (``pushed``) every few substeps, for seconds (issue 11, long-rest test).

    Sleeping removes jitter (no kinetic energy creeps into resting piles) and work: the solver
    skips asleep elements in prediction, shape matching, bending and adhesion, and pairs of two
    asleep particles in the contacts (``solver.XpbdSolver.substep``).
    """
    x, v, x_start, asleep, awake, pushed = state.x, state.v, state.x_start, state.asleep, state.awake, state.pushed
    r, elem, start = model.r, model.elem, model.start
    m = start.shape[0] - 1
    limit = rule.still * rule.still
    limit_probed = rule.still_probed * rule.still_probed
    slow = np.empty(m, np.bool_)
    falling = 0  # awake elements that would fall asleep now: without any, the touching rule has nothing to do
    for c in prange(m):
        fastest = 0.0
        hit = False
        for i in range(start[c], start[c + 1]):
            hit = hit or pushed[i]
            fastest = max(fastest, _moved_sq(x, x_start, i))
        if asleep[c]:
            slow[c] = fastest < limit_probed
            if not slow[c] or hit:
                slow_steps[c] = 0  # woken: it settles again for a whole frame before it sleeps
        else:
            still = fastest < limit
            slow_steps[c] = slow_steps[c] + 1 if still else 0
            slow[c] = still and slow_steps[c] >= rule.settle_steps
        asleep[c] = slow[c] and not hit
        if asleep[c] and start[c + 1] > start[c] and awake[start[c]]:
            falling += 1
    nbr_start, nbr, order = contact_rows
    rows = nbr_start.shape[0] - 1 if falling else 0
    for p in prange(rows):  # the touching rule: both awake, one fast (each side written alone)
        i = order[p]
        if not awake[i] or elem[i] >= m:
            continue
        for a in range(nbr_start[p], nbr_start[p + 1]):
            j = nbr[a]
            if not awake[j] or elem[j] >= m or elem[j] == elem[i] or slow[elem[i]] == slow[elem[j]]:
                continue
            if _touching(x, r, i, j):
                asleep[elem[i] if slow[elem[i]] else elem[j]] = False
    for c in prange(m):
        if asleep[c]:
            for i in range(start[c], start[c + 1]):
                v[i, 0] = 0.0
                v[i, 1] = 0.0
                v[i, 2] = 0.0


@njit(cache=True)
def kinetic_energy(v, w):
    """½ Σ m |v|² over particles with finite mass."""
    e = 0.0
    for i in range(v.shape[0]):
        if w[i] > 0.0:
            e += 0.5 * (v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2) / w[i]
    return e
