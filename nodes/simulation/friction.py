"""Static and dynamic friction on contacts, anchored where the contact began — Macklin et al. 2014
§6.1's position-level rule, measured from an anchor instead of the substep's start.

Macklin's rule removes the relative tangential displacement of one substep entirely when it is below
μs·d (d the contact's overlap: its normal load as the solve meets it), else scales it by
min(μk·d/|Δx_t|, 1). Alone it holds a lone grain on a slope (measured: a sphere on a 28° plane with
μs = 0.6 does not move, at 35° it slides), but not a heap: whatever the later corrections of the
same substep (other contacts, shape matching, walls) add tangentially is never undone, and 900 rice
grains crept flat for seconds (12° at 2.5 s, 10° at 7 s; μs 1.0 no better than 0.6). Each contact
here keeps an anchor, the relative position (i − j, or a particle's own position against a wall)
where it began sticking: static friction restores the tangential drift since then, not only this
substep's, so slow slip cannot pile up; when the drift exceeds μs·d the contact slides by μk·d
(dynamic) and is re-anchored where it now is — the per-substep rule again while it slides. Drift and
load both scale with h² (gravity's step), so the sticking test does not depend on the substep count.

With anchors the load d of a pair is the normal correction it has received this substep
(pre-stabilisation included, ``contact_constraints.PairEntries.load``) plus the correction it is about to
get: the λ_n of Müller et al. 2020's static-friction test, in position units. The overlap alone
reads nearly 0 at a resting contact once pre-stabilisation has removed it, while shape matching hands
each contact particle back only part of a friction correction, so the drift of a grain (8 particles)
outgrew μs·overlap and heaps of rice-like grains crept (H/R 28.7° → 25.1° from 2.5 s to 7 s); with the
substep's load they rest (docs/validation.md). The tolerated old overlap is no load: counted in, resting
overlaps fed friction that kept them, and poured spheres jammed at φ 0.34. Walls keep the penetration as
their load: summing a wall's pushes too raised the heap 2.6° but kept a sleeping pile of bars from resting
(kinetic energy 0.3–3 g·mm²/s² for ever, against 0 without).
A rigid grain touches a wall or another grain at several particles; the load falls on them unevenly (one
particle of a grain lying on a plane carries ≈ 90 %) while shape matching spreads the grain's drift over them
alike. Whether a contact sticks is therefore decided for the contact as a whole (the pair of elements, or an
element against the walls) and once per substep, from the last (``pool_contacts``, ``collider.wall_means``):
Coulomb's |Σ Δx_t| ≤ μs·Σ Δx_n with the tangential corrections summed as vectors and both summed over the
contact's particles and all of the substep's passes (``contact_mode``). While a contact sticks, every pass
restores its drift since the anchor, each particle against a wall within its own cone (``pooled_load``); while
it slides, the passes remove at most μk times its load over the substep, and once kinetic friction stops it, it
sticks again. A test of each pass's drift against the load, as Macklin's, saw only what the passes before had
left, so static friction grew with the iterations (a grain held on a plane to 24°, 29°, 34° and 37° at 1–4
iterations, μs 0.6); the summed test holds it to 29–30° and lets it slide at 30–31° at 10 × 2, 40 × 2 and
10 × 4, laid on the plane or set down on it (tests/simulation/test_static_friction.py). G Table 3: μs = static
threshold, μk = dynamic scale · μs.

Anchors are NaN where no contact sticks. ``friction_pair`` runs per pair inside the contacts'
Gauss–Seidel sweep (``contact_constraints.contact_sweep``) just before the pair's normal correction;
``friction_wall`` for a particle against a collider wall (a partner that never moves).
"""

from typing import NamedTuple

import numpy as np
from numba import njit, prange

# a contact whose gap opens beyond this share of the radii sum lets go of its anchor (a resting contact
# the solve leaves just apart, or exactly touching, keeps it)
RELEASE = 0.05


# a contact's friction mode in a substep, decided at the end of the last one from what its contact needed
# (``pool_contacts``): TESTED when it touched nothing (each entry tests its drift against its own load),
# STICKING (restore the whole drift since the anchor), SLIDING (remove at most μk·load over the substep)
TESTED, STICKING, SLIDING = 0, 1, 2
ROLLS = 3  # a pair with a one-particle element (``ROLLING``): tested each pass against its own load
# per entry, what friction removed this substep (``rubbed``): the drift vector (3), its length summed over
# the passes, and whether it slid in one
RUBBED = 5
# the share of one substep's tangential and normal corrections in a contact's remembered force (``remember``);
# the rest is what it remembered. A grain tilted on a plane at μs 1 (never sliding) reads |Σ Δx_t|/Σ Δx_n = tan θ
# once at rest, but rings to 1.3 tan θ over the first 4–10 substeps (10 × 2, 40 × 2 and 10 × 4 alike): a test of
# each substep alone let it slide at 28° (μs 0.6: 31°); the running mean at this share stays below tan θ
RESPONSE = 0.25
# a sticking contact restores at most this many times μs·load in one pass (the particle slips beyond, and the
# contact's summed test decides whether the grain slides): a grain tilted on a plane needs up to 1.3 μs·load in a
# pass while it rings (held to 30°, slid at 31° from 1.25 up at 10 × 2, 40 × 2 and 10 × 4); without a bound two
# sticking contacts with other normals lock a particle against its normal
# corrections (a plate pressed on two-layer grains passed through them), and a bar lying on the ground under
# another kept rocking (kinetic energy 1.3e-3 g·mm²/s² at 2: 4.7e-9 at 1.25, 0.17 with sleeping at 1.5)
HOLD = 1.25
# per contact, the remembered force: the tangential corrections' vector (3) and the normal corrections' sum
FORCE = 4
# a one-particle element (a sphere) has no rotation here: where a real sphere would roll off another, a sticking
# contact welds them, and spheres poured on a lattice stood in columns (φ 0.34 against 0.65; so did the per-pass
# test against the pooled load of the substep before). Its pairs are tested each pass against their own load of
# this substep (ROLLS), which lets them slip as rolling would, and its walls each pass (TESTED)
ROLLING = 1  # particles: an element this small rolls


@njit(cache=True, inline="always")
def removed_share(t, mode, held, used, mu_s, mu_k):
    """The share of a tangential drift of length t > 0 that friction removes in this pass: all of it when
    sticking, up to ``HOLD``·μs·held; when sliding, what is left of the substep's budget μk·held after ``used``;
    when tested, all of it below μs·held, else min(μk·held/t, 1) (Macklin et al. 2014 §6.1). Below 1 the
    contact slid."""
    if mode == STICKING:
        return min(HOLD * mu_s * held / t, 1.0)
    if mode == SLIDING:
        return min(max(mu_k * held - used, 0.0) / t, 1.0)
    return 1.0 if t < mu_s * held else min(mu_k * held / t, 1.0)


@njit(cache=True, inline="always")
def pooled_load(mode, mean, own):
    """The normal load a particle against the walls is held against in ``mode``: while it sticks its ``own`` of this
    substep (each particle within its own Coulomb cone; whether the grain slides is the contact's summed test,
    ``contact_mode``), else its grain's mean over the touching particles (``collider.wall_means``). Held against
    the mean, a grain landing tip first on a slab tilted 25° slid (μs 0.6) in the pass where the tip took three
    times the mean, and a lightly loaded particle landing sideways held the whole grain's share. Pairs keep the
    mean: with their own, bars resting on one another kept moving (kinetic energy 0.83 g·mm²/s² after 2 s, where
    it falls below 1e-6)."""
    return own if mode == STICKING else mean


@njit(cache=True, inline="always")
def touched_at(gap, approach):
    """The share of a substep's motion so far that passed before a contact began to touch: it closed ``approach``
    along the normal from ``gap`` (0 when it touched at the substep's start). A fresh anchor sits there, so that
    the tangential drift friction holds is the one made while touching, as the normal load is the push made
    while touching: anchored at the substep's start, a grain landing on a slab tilted 25° counted the tangential
    motion of its fall against the load of its landing alone, needed 0.69 of it where tan 25° = 0.47, and slid
    away at μs 0.6."""
    if gap <= 0.0 or approach <= gap:
        return 0.0 if gap <= 0.0 else 1.0
    return gap / approach


@njit(cache=True, inline="always")
def tangential_part(rx, ry, rz, nx, ny, nz):
    """(t, tx, ty, tz): the tangential part of the drift r against the unit normal n and its length."""
    dn = rx * nx + ry * ny + rz * nz
    tx = rx - dn * nx
    ty = ry - dn * ny
    tz = rz - dn * nz
    return np.sqrt(tx * tx + ty * ty + tz * tz), tx, ty, tz


@njit(cache=True, inline="always")
def _rub(rubbed, a, scale, t, tx, ty, tz):
    """Add what friction removed in this pass to entry ``a`` of ``rubbed`` (``RUBBED`` columns)."""
    rubbed[a, 0] += scale * tx
    rubbed[a, 1] += scale * ty
    rubbed[a, 2] += scale * tz
    rubbed[a, 3] += scale * t
    if scale < 1.0:
        rubbed[a, 4] = 1.0


@njit(cache=True, inline="always")
def friction_pair(x, x_prev, anchor, rubbed, a, i, j, normal, held, share, rule, mode):
    """Friction on the pair (i, j) of list entry ``a`` with unit normal ``normal`` = (nx, ny, nz)
    (j → i) and normal load ``held``, in place; i takes ``share`` of the correction, j the rest (the
    contacts' mass scaling). ``rule``: a ``friction_models.FrictionRule`` (μs, μk, anchored); ``mode``: the
    contact's (``TESTED``, ``STICKING``, ``SLIDING``). Without anchors the drift is the substep's (Macklin's
    rule); with them a pair without an anchor is anchored where it stood at the substep's start (its first
    substep is Macklin's rule) and a sliding pair is re-anchored after its step. What is removed adds to
    ``rubbed[a]``."""
    mu_s, mu_k, anchored = rule
    nx, ny, nz = normal
    if anchored:
        if np.isnan(anchor[a, 0]):
            for k in range(3):
                anchor[a, k] = x_prev[i, k] - x_prev[j, k]
        rx = x[i, 0] - x[j, 0] - anchor[a, 0]
        ry = x[i, 1] - x[j, 1] - anchor[a, 1]
        rz = x[i, 2] - x[j, 2] - anchor[a, 2]
    else:
        rx = (x[i, 0] - x_prev[i, 0]) - (x[j, 0] - x_prev[j, 0])
        ry = (x[i, 1] - x_prev[i, 1]) - (x[j, 1] - x_prev[j, 1])
        rz = (x[i, 2] - x_prev[i, 2]) - (x[j, 2] - x_prev[j, 2])
    t, tx, ty, tz = tangential_part(rx, ry, rz, nx, ny, nz)
    if t <= 1e-12:
        return
    scale = removed_share(t, mode, held, rubbed[a, 3] if anchored else 0.0, mu_s, mu_k)
    if anchored:  # without anchors nothing is kept per pair: ``rubbed`` is empty
        _rub(rubbed, a, scale, t, tx, ty, tz)
    si = scale * share
    sj = scale - si
    x[i, 0] -= si * tx
    x[i, 1] -= si * ty
    x[i, 2] -= si * tz
    x[j, 0] += sj * tx
    x[j, 1] += sj * ty
    x[j, 2] += sj * tz
    if anchored and scale < 1.0:  # it slid: the contact sticks again, if at all, where it now is
        for k in range(3):
            anchor[a, k] = x[i, k] - x[j, k]


@njit(cache=True, inline="always")
def friction_wall(x, x_prev, anchor, rubbed, i, nx, ny, nz, pen, held, rule, mode):
    """Friction of particle i against a static wall with unit normal n and normal load ``held``, just pushed out
    by ``pen`` along n, in place: the pair rule with a partner that does not move and takes no share; ``rubbed``
    per particle."""
    mu_s, mu_k, anchored = rule
    ref = anchor if anchored else x_prev
    if anchored and np.isnan(anchor[i, 0]):
        # the move since the substep's start up to the push (x − pen·n), and how far along n it closed on the wall
        mx = x[i, 0] - pen * nx - x_prev[i, 0]
        my = x[i, 1] - pen * ny - x_prev[i, 1]
        mz = x[i, 2] - pen * nz - x_prev[i, 2]
        approach = -(mx * nx + my * ny + mz * nz)
        f = touched_at(approach - pen, approach)  # the gap at the start was the approach less the penetration
        anchor[i, 0] = x_prev[i, 0] + f * mx
        anchor[i, 1] = x_prev[i, 1] + f * my
        anchor[i, 2] = x_prev[i, 2] + f * mz
    t, tx, ty, tz = tangential_part(x[i, 0] - ref[i, 0], x[i, 1] - ref[i, 1], x[i, 2] - ref[i, 2], nx, ny, nz)
    if t <= 1e-12:
        return
    scale = removed_share(t, mode, held, rubbed[i, 3], mu_s, mu_k)
    _rub(rubbed, i, scale, t, tx, ty, tz)
    x[i, 0] -= scale * tx
    x[i, 1] -= scale * ty
    x[i, 2] -= scale * tz
    if anchored and scale < 1.0:
        for k in range(3):
            anchor[i, k] = x[i, k]


@njit(cache=True, inline="always")
def remember(force, c, normal, tx, ty, tz):
    """Fold one substep's summed corrections into row c of ``force`` (``FORCE`` columns): the running mean with
    weight ``RESPONSE``; cleared when the contact carries no load."""
    if normal <= 0.0:
        for k in range(FORCE):
            force[c, k] = 0.0
        return
    force[c, 0] += RESPONSE * (tx - force[c, 0])
    force[c, 1] += RESPONSE * (ty - force[c, 1])
    force[c, 2] += RESPONSE * (tz - force[c, 2])
    force[c, 3] += RESPONSE * (normal - force[c, 3])


@njit(cache=True, inline="always")
def contact_mode(normal, tx, ty, tz, slid, mu_s, mode):
    """A contact's mode for the next substep from its remembered force (``remember``; Coulomb for the contact as
    a whole: Müller et al. 2020 §3.5's λ_t < μs·λ_n with the multipliers summed over the substep) and ``mode``, this
    substep's; TESTED without load.
    - STICKING (or TESTED, a contact's first substep) slides when holding it took more than μs times its normal
      load, |Σ Δx_t| > μs·Σ Δx_n, both summed over its particles and the substep's passes. Summed over the passes,
      the decision does not depend on how the substep is split into iterations: each pass's own test saw only the
      drift since the pass before, and a grain on a plane held to 24°, 29°, 34°, 37° at 1–4 iterations (31°).
      Where one of its particles slipped (``slid``: a lightly loaded one, ``pooled_load``) the contact still
      sticks: a grain set down tip first on a slab swings about the tip until a second particle lands moving
      sideways, and that particle's slip slid the whole grain away from 24° at 40 substeps (μs 0.6).
    - SLIDING sticks again once kinetic friction stopped it in the substep (Coulomb: static friction holds a
      contact at rest). The remembered force, which still held the slip's, kept a grain that rocked as it was set
      down on a slab sliding away at 28°, where kinetic friction alone (μk 0.42) cannot stop it."""
    if normal <= 0.0:
        return TESTED
    if mode == SLIDING:
        return SLIDING if slid else STICKING
    if tx * tx + ty * ty + tz * tz > (mu_s * normal) ** 2:
        return SLIDING
    return STICKING


@njit(cache=True, inline="always")
def next_mode(force, c, normal, tx, ty, tz, slid, mu_s, mode):
    """Fold a contact's summed corrections of this substep into its remembered force (row c of ``force``,
    ``remember``) and return its mode for the next substep (``contact_mode``) from ``mode``, this substep's: what
    walls and pairs both do."""
    remember(force, c, normal, tx, ty, tz)
    return contact_mode(force[c, 3], force[c, 0], force[c, 1], force[c, 2], slid, mu_s, mode)


@njit(cache=True, parallel=True)
def entry_sources(old, new, source):
    """Per entry of the rebuilt neighbour lists, the entry of the old ones that lists the same pair, found in the
    same particle's row, into ``source`` (−1: none, a pair new to the lists). What a contact keeps (its anchor,
    loads, friction mode and remembered force) follows it through ``source``. In half rows a pair sits in the
    row of the partner that comes first in the grid's order, which can change between builds: such a pair is
    not found and starts afresh where it stands (friction then holds from there, as for a new contact).
    ``old``, ``new``: the lists' (nbr_start, nbr, order), row p being particle order[p]'s."""
    old_start, old_nbr, old_order = old
    new_start, new_nbr, new_order = new
    n = new_start.shape[0] - 1
    old_row = np.full(n, -1, np.int64)  # particle id -> its row in the old lists (-1: none)
    for p in range(min(old_order.shape[0], old_start.shape[0] - 1)):
        if old_order[p] < n:
            old_row[old_order[p]] = p
    for p in prange(n):
        i = new_order[p]
        q = old_row[i]
        for a in range(new_start[p], new_start[p + 1]):
            j = new_nbr[a]
            source[a] = -1
            if q < 0:
                continue
            for b in range(old_start[q], old_start[q + 1]):
                if old_nbr[b] == j:
                    source[a] = b
                    break


def carried(old: np.ndarray, source: np.ndarray, fresh: float) -> np.ndarray:
    """``old``'s rows taken through ``source`` (``entry_sources``); ``fresh`` where an entry has none."""
    width = int(np.prod(old.shape[1:]))
    out = np.empty((len(source), width), old.dtype)
    _carry_rows(old.reshape(len(old), width), source, old.dtype.type(fresh), out)
    return out.reshape((len(source), *old.shape[1:]))


@njit(cache=True)
def _carry_rows(old, source, fresh, out):
    """``carried``'s gather in one pass over the entries (NumPy's mask, take and put made four, ≈ 1 ms a call on
    the main job's ≈ 10⁵ entries, four calls each time the lists are rebuilt)."""
    for a in range(source.shape[0]):
        b = source[a]
        for k in range(out.shape[1]):
            out[a, k] = old[b, k] if b >= 0 else fresh


class ContactGroups(NamedTuple):
    """Which contact each entry of the neighbour lists belongs to (``contact_groups``), as ``pool_contacts``
    takes it."""

    group: np.ndarray  # per entry, its contact (−1: none)
    count: int  # contacts
    sign: np.ndarray  # per entry, +1 when its first particle is in the contact's lower element, else −1
    wsum: np.ndarray  # per entry, w_i + w_j
    rolls: np.ndarray  # per entry, whether one of its elements is a sphere (``ROLLING``): always ROLLS


NO_GROUPS = ContactGroups(
    np.empty(0, np.int64), 0, np.empty(0), np.empty(0), np.empty(0, np.bool_)
)  # lists not built yet


def contact_groups(lists, elem, w) -> ContactGroups:
    """Per entry of the neighbour lists, the contact it belongs to: the pair of elements it joins (−1 for the
    entries the sweep skips, a pair's second listing in full rows), numbered in the order of (lower element,
    higher element), and how many there are; with each entry's orientation in its contact (+1 when its first
    particle is in the lower element: an entry's drift is i − j) and its pair's w_i + w_j (adhesion's load scales
    with it). A grain touches another, or a wall, at several particles; ``pool_contacts`` pools them."""
    nbr_start, nbr, half, order = lists.rows()
    entries = len(nbr)
    group, sign = np.empty(entries, np.int64), np.empty(entries)
    wsum, rolls = np.empty(entries), np.empty(entries, np.bool_)
    count = _group_entries(nbr_start, nbr, bool(half), order, elem, w, group, sign, wsum, rolls)
    return ContactGroups(group, count, sign, wsum, rolls)


@njit(cache=True)
def _group_entries(nbr_start, nbr, half, order, elem, w, group, sign, wsum, rolls):
    """``contact_groups``' arrays in linear passes: the kept entries bucketed by their lower element, each
    bucket's higher elements numbered in ascending order (the ranks of the sorted (lower, higher) keys; a sort
    of all the entries' keys cost ≈ 3 ms a rebuild on the main job). Returns the number of contacts."""
    m = 0
    for e in range(elem.shape[0]):
        m = max(m, elem[e] + 1)
    sizes = np.zeros(m, np.int64)
    for e in range(elem.shape[0]):
        sizes[elem[e]] += 1
    first = np.empty(nbr.shape[0], np.int64)  # per entry, its row's particle
    start = np.zeros(m + 1, np.int64)  # kept entries per lower element, then where its bucket starts
    for p in range(order.shape[0]):
        i = order[p]
        for a in range(nbr_start[p], nbr_start[p + 1]):
            j = nbr[a]
            first[a] = i
            ei, ej = elem[i], elem[j]
            sign[a] = 1.0 if ei <= ej else -1.0
            wsum[a] = w[i] + w[j]
            rolls[a] = sizes[ei] <= ROLLING or sizes[ej] <= ROLLING
            group[a] = -1
            if half or i < j:
                start[min(ei, ej) + 1] += 1
    for e in range(m):
        start[e + 1] += start[e]
    bucket = np.empty(start[m], np.int64)
    fill = start[:m].copy()
    for a in range(nbr.shape[0]):
        i, j = first[a], nbr[a]
        if half or i < j:
            lo = min(elem[i], elem[j])
            bucket[fill[lo]] = a
            fill[lo] += 1
    seen = np.full(m, -1, np.int64)  # the lower element whose bucket last met this higher one
    slot = np.empty(m, np.int64)
    distinct = np.empty(m, np.int64)
    count = 0
    for lo in range(m):
        k = 0
        for b in range(start[lo], start[lo + 1]):
            a = bucket[b]
            hi = max(elem[first[a]], elem[nbr[a]])
            if seen[hi] != lo:
                seen[hi] = lo
                distinct[k] = hi
                k += 1
        for t in range(1, k):  # insertion sort: a grain meets a few others
            v = distinct[t]
            u = t - 1
            while u >= 0 and distinct[u] > v:
                distinct[u + 1] = distinct[u]
                u -= 1
            distinct[u + 1] = v
        for t in range(k):
            slot[distinct[t]] = count + t
        count += k
        for b in range(start[lo], start[lo + 1]):
            a = bucket[b]
            group[a] = slot[max(elem[first[a]], elem[nbr[a]])]
    return count


@njit(cache=True)
def pool_contacts(contacts, cohesion, mu_s, load, rubbed, mean, mode, force):
    """Each contact's mean load over its touching entries (load > 0) into ``mean`` per entry (0 where none
    touches), its remembered force (``remember``) into ``force`` and its mode for the next substep
    (``contact_mode``) into ``mode``, from the substep's ``load`` and ``rubbed`` (then cleared). ``contacts``:
    ``ContactGroups``. A rigid grain's contact is tested as a whole: shape matching
    spreads a grain's drift over its particles alike, while the normal load falls unevenly on them, so the test
    per entry let the lightly loaded ones slide and the grain with them (a grain on a 26° plane at μs 0.6).
    Each entry keeps its contact's force (entries new to the lists have none: the contact's is the entry's
    with the largest remembered load)."""
    group, count, sign, wsum, rolls = contacts
    total = np.zeros(count)
    normal = np.zeros(count)
    touching = np.zeros(count, np.int64)
    drift = np.zeros((count, 3))
    slid = np.zeros(count, np.bool_)
    was = np.zeros(count, np.int8)  # the contact's mode this substep (TESTED: all its entries new or tested)
    held = np.zeros((count, FORCE))
    for a in range(group.shape[0]):
        g = group[a]
        if g < 0:
            continue
        if load[a] > 0.0:
            total[g] += load[a]
            normal[g] += load[a] + cohesion * wsum[a]
            touching[g] += 1
        for k in range(3):
            drift[g, k] += sign[a] * rubbed[a, k]
        slid[g] |= rubbed[a, 4] > 0.0
        if mode[a] == STICKING or mode[a] == SLIDING:
            was[g] = mode[a]
        if force[a, 3] > held[g, 3]:
            for k in range(3):
                held[g, k] = sign[a] * force[a, k]
            held[g, 3] = force[a, 3]
    decided = np.empty(count, np.int8)
    for g in range(count):
        decided[g] = next_mode(held, g, normal[g], drift[g, 0], drift[g, 1], drift[g, 2], slid[g], mu_s, was[g])
    for a in range(group.shape[0]):
        g = group[a]
        if g >= 0 and touching[g] > 0:
            mean[a] = total[g] / touching[g]
            mode[a] = ROLLS if rolls[a] else decided[g]
            for k in range(3):
                force[a, k] = sign[a] * held[g, k]
            force[a, 3] = held[g, 3]
        else:
            mean[a] = 0.0
            mode[a] = ROLLS if g >= 0 and rolls[a] else TESTED
            for k in range(FORCE):
                force[a, k] = 0.0
        for k in range(RUBBED):
            rubbed[a, k] = 0.0
