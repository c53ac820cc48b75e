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
A rigid grain touches a wall or another grain at several particles, and the load falls on them unevenly (one
particle of a grain lying on a plane carries ≈ 90 %), while shape matching spreads the grain's drift over them
alike: tested per particle, the lightly loaded ones slid and took the grain along (it slid at 26° on a plane
at μs 0.6). So the test takes each contact's mean load over its touching particles in the last substep
(``group_means`` per pair of elements, ``collider.wall_means`` per element against the walls): Coulomb's
Σ|t| < μs·Σ N for the rigid contact; a grain then holds to 29–30° and slides at 30–31° (docs/validation.md).
G Table 3: μs = static threshold, μk = dynamic scale · μs.

Anchors are NaN where no contact sticks. ``friction_pair`` runs per pair inside the contacts'
Gauss–Seidel sweep (``contact_constraints.contact_sweep``) just before the pair's normal correction;
``friction_wall`` for a particle against a collider wall (a partner that never moves).
"""

import numpy as np
from numba import njit, prange

# a contact whose gap opens beyond this share of the radii sum lets go of its anchor (a resting contact
# the solve leaves just apart, or exactly touching, keeps it)
RELEASE = 0.05


@njit(cache=True, inline="always")
def tangential_slip(rx, ry, rz, nx, ny, nz, depth, mu_s, mu_k):
    """(share, tx, ty, tz): the tangential part t of the drift r against the unit normal n, and the
    share of it friction removes — 1 when |t| < μs·depth (static), else min(μk·depth/|t|, 1)
    (dynamic); share −1 when there is no tangential drift (|t| ≤ 1e-12)."""
    dn = rx * nx + ry * ny + rz * nz
    tx = rx - dn * nx
    ty = ry - dn * ny
    tz = rz - dn * nz
    t = np.sqrt(tx * tx + ty * ty + tz * tz)
    if t <= 1e-12:
        return -1.0, tx, ty, tz
    return (1.0 if t < mu_s * depth else min(mu_k * depth / t, 1.0)), tx, ty, tz


@njit(cache=True, inline="always")
def friction_pair(x, x_prev, anchor, a, i, j, normal, depth, share, rule):
    """Friction on the pair (i, j) of list entry ``a`` with unit normal ``normal`` = (nx, ny, nz)
    (j → i) and overlap ``depth``, in place; i takes ``share`` of the correction, j the rest (the
    contacts' mass scaling). ``rule``: a ``friction_models.FrictionRule`` (μs, μk, anchored); without
    anchors the drift is the substep's (Macklin's rule); with them a pair without an anchor is anchored where
    it stood at the substep's start (its first substep is Macklin's rule) and a sliding pair is re-anchored
    after its step."""
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
    scale, tx, ty, tz = tangential_slip(rx, ry, rz, nx, ny, nz, depth, mu_s, mu_k)
    if scale < 0.0:
        return
    si = scale * share
    sj = scale - si
    x[i, 0] -= si * tx
    x[i, 1] -= si * ty
    x[i, 2] -= si * tz
    x[j, 0] += sj * tx
    x[j, 1] += sj * ty
    x[j, 2] += sj * tz
    if anchored and scale < 1.0:  # sliding: the contact sticks again, if at all, where it now is
        for k in range(3):
            anchor[a, k] = x[i, k] - x[j, k]


@njit(cache=True, inline="always")
def friction_wall(x, x_prev, anchor, i, nx, ny, nz, depth, rule):
    """Friction of particle i against a static wall with unit normal n and penetration ``depth``,
    in place: the pair rule with a partner that does not move and takes no share."""
    mu_s, mu_k, anchored = rule
    ref = anchor if anchored else x_prev
    if anchored and np.isnan(anchor[i, 0]):
        for k in range(3):
            anchor[i, k] = x_prev[i, k]
    scale, tx, ty, tz = tangential_slip(
        x[i, 0] - ref[i, 0], x[i, 1] - ref[i, 1], x[i, 2] - ref[i, 2], nx, ny, nz, depth, mu_s, mu_k
    )
    if scale < 0.0:
        return
    x[i, 0] -= scale * tx
    x[i, 1] -= scale * ty
    x[i, 2] -= scale * tz
    if anchored and scale < 1.0:
        for k in range(3):
            anchor[i, k] = x[i, k]


@njit(cache=True, parallel=True)
def carry_anchors(old, old_anchor, new, new_anchor):
    """Copy each pair's anchor from the old neighbour lists to its entry in the rebuilt ones, found in the
    same particle's row; pairs new to the lists get none (NaN). In half rows a pair sits in the row of the
    partner that comes first in the grid's order, which can change between builds: such a pair is not
    found and is anchored afresh where it stands (friction then holds from there, as for a new contact).
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
            new_anchor[a, 0] = np.nan
            if q < 0:
                continue
            for b in range(old_start[q], old_start[q + 1]):
                if old_nbr[b] == j:
                    for k in range(3):
                        new_anchor[a, k] = old_anchor[b, k]
                    break


def contact_groups(lists, elem) -> tuple[np.ndarray, int]:
    """Per entry of the neighbour lists, the contact it belongs to: the pair of elements it joins (−1 for the
    entries the sweep skips, a pair's second listing in full rows), and how many there are. A grain touches
    another, or a wall, at several particles; ``group_means`` pools their loads."""
    nbr_start, nbr, half, order = lists.rows()
    i = np.repeat(order, np.diff(nbr_start))
    j = nbr
    kept = np.ones(len(j), bool) if half else i < j
    lo, hi = np.minimum(elem[i], elem[j]), np.maximum(elem[i], elem[j])
    key = lo * (int(elem.max(initial=0)) + 1) + hi
    group = np.full(len(j), -1, np.int64)
    ids, inverse = np.unique(key[kept], return_inverse=True)
    group[kept] = inverse
    return group, len(ids)


@njit(cache=True)
def group_means(group, count, load, mean):
    """Each contact's mean load over its touching entries (load > 0) into ``mean`` per entry (0 where none
    touches), from the substep's ``load``. Static friction then tests a rigid grain's contact as a whole:
    shape matching spreads a grain's drift over its particles alike, while the normal load falls unevenly on
    them, so the test per entry let the lightly loaded ones slide and the grain with them (a grain on a 26°
    plane at μs 0.6); with the mean the test is Σ|t| < μs·Σ load, Coulomb's for the rigid contact."""
    total = np.zeros(count)
    touching = np.zeros(count, np.int64)
    for a in range(group.shape[0]):
        g = group[a]
        if g >= 0 and load[a] > 0.0:
            total[g] += load[a]
            touching[g] += 1
    for a in range(group.shape[0]):
        g = group[a]
        mean[a] = total[g] / touching[g] if g >= 0 and touching[g] > 0 else 0.0
