"""Particle–particle non-penetration between different elements — SPEC §3 (XPBD contact).

Gauss–Seidel by graph colouring: the neighbour grid is cut into slabs one cell thick along x and
coloured by the slab index modulo 3; slabs of one colour share no particle (neighbours lie at most
one cell away), so they run in parallel while each slab projects its pairs one after another,
updating both particles at once. Three colours, not 27 cells' worth: each colour is a
parallel launch and a barrier. Averaged Jacobi (each
particle moves by the mean of its contacts' corrections) was stable but weak: in a dense pile a
particle with n contacts moved by 1/n of what it needed per sweep, and 50k-sphere piles sank into
themselves (penetration ≈ 2 radii). Gauss–Seidel has no such division and stays race-free and
deterministic (the order within a cell is fixed, colours run in a fixed order).
Contacts are rigid, or with ``squeeze_strain`` compliant (``compliant_push``): an element then gives at its
contacts as a squeezed grain does, and pre-stabilisation leaves each pair the elastic overlap its load holds.

Tall piles: shock propagation by mass scaling (Macklin et al. 2014 §5.2, after Guendelman et al.
2003). Within the contact solve a particle's inverse mass is scaled by exp(k·z): the lower of two
touching particles acts heavier, so the upper one takes the correction. Averaged Jacobi without it
spreads a column's weight like diffusion (≈ layers² sweeps to carry it to the floor), and piles a
few dozen particles high sink into each other; with it each layer rests on the one below within a
few sweeps. The split uses the height difference of the pair only, w_i / (w_i + w_j·e^{k(z_j − z_i)}),
so no exponent overflows however tall the pile. Rest positions do not depend on masses.
Overlap left over at the start of a substep is removed mostly by pre-stabilisation (moves that add
no velocity, Macklin et al. 2014 §4.2); within the substep each pair may keep what that sweep left
(``allowance``, less a ``decay`` share of the smaller radius: the solver passes 0, since a decay left the
tolerated overlaps of long grains in place, docs/look.md). What bounds the separation speed instead is
``SolverSettings.depenetration_speed`` in ``integrate.update_velocity``.
"""

from collections import namedtuple

import numpy as np
from numba import njit, prange

from .friction import RELEASE, ROLLS, TESTED, friction_pair

# the sweep's arguments in bundles (a kernel takes at most 12): the neighbour lists' rows, the grid
# that colours them, the per-entry arrays, and the scalars of one sweep
PairRows = namedtuple(
    "PairRows", "nbr_start nbr half order at"
)  # row p lists the partners (ids nbr, rows at) of order[p]
Colouring = namedtuple("Colouring", "cell_start order dims")
# per list entry: tolerated overlap, friction anchor, normal correction so far this substep (anchored friction's
# load), its contact's mean load over the last substep and its friction mode (``friction.pool_contacts``), what
# friction removed this substep (``friction.RUBBED`` columns), and ``glued``: its grains are glued (``glue``), so
# its friction takes the true masses and tests each entry alone (``_project_slab``); empty: none is
# and ``spring``: the elastic overlap its compliance holds so far this substep (``compliant_push``; empty: rigid);
# ``parting``: its elements were placed inside one another and part without friction (``parting``; empty: none)
PairEntries = namedtuple("PairEntries", "allowance anchor load held mode rubbed glued spring parting")
# compliant contacts' ``alpha`` (α̃ of one element's face, ``face_compliance`` / h², 1/g; 0 = rigid contacts),
# ``crush`` (the overlap in mm one face gives before it turns rigid) and ``zeta`` (damping ratio of their unloading,
# ``compliant_push``); flat fields: numba's parallel loop takes no tuple inside the bundle
ContactRule = namedtuple("ContactRule", "wake_step lift upright mu_s mu_k anchored normal cohesion alpha crush zeta")


@njit(cache=True, inline="always")
def pair_normal(x, i, j):
    """Unit vector from j to i and the distance; coincident particles get a fixed pseudo-random
    direction, antisymmetric in (i, j), so deep overlaps separate deterministically."""
    return pair_normal_at(x, i, j, i, j)


@njit(cache=True, inline="always")
def pair_normal_at(x, p, q, i, j):
    """``pair_normal`` of particles i and j held in rows p and q of ``x`` (the sweep's sorted copies)."""
    nx = x[p, 0] - x[q, 0]
    ny = x[p, 1] - x[q, 1]
    nz = x[p, 2] - x[q, 2]
    d = np.sqrt(nx * nx + ny * ny + nz * nz)
    if d > 1e-9:
        return nx / d, ny / d, nz / d, d
    lo, hi, sign = (i, j, 1.0) if i < j else (j, i, -1.0)
    h = (lo * 2654435761 + hi * 40503) % 1000003
    theta = 6.283185307179586 * (h % 1009) / 1009.0
    z = -1.0 + 2.0 * ((h // 1009) % 991) / 990.0
    s = np.sqrt(max(0.0, 1.0 - z * z))
    return sign * s * np.cos(theta), sign * s * np.sin(theta), sign * z, d


@njit(cache=True, inline="always")
def lifted_share(w, x, i, j, nz, lift, upright):
    """Share of a pair correction taken by i: w_i / (w_i + w_j·e^{lift·(z_j − z_i)}) (mass scaling by
    height; lift = 0 is the plain w_i / (w_i + w_j)). Returns −1 when both are immovable; a static
    partner (w_j = 0) stays infinitely heavy at any height (no 0·exp overflow).

    ``upright`` (gravity on): a lower particle never acts lighter than the one resting on it. When
    the lower one would take more than the equal-mass share e (the share both would take at equal
    masses, height scaling included), its share s becomes s + (e − s)·nz², nz the vertical component
    of the pair normal: a heavy element on a light one stacks like equal masses (nz = ±1), a
    side-by-side contact (nz = 0) keeps the true masses. The blend is of shares, so the upper one
    takes at least nz²·e whatever the ratio (a blend of inverse masses left it 1/(1 + ratio·(1 − nz²)):
    at a 45° contact and 1:1000 it took 0.2 %, and a heavy element fell through a light pyramid,
    shooting it out at 421 mm/s). Gauss–Seidel against the ground converges like (1 − m_l/m_u) per
    iteration without it (mass scaling, Macklin et al. 2014 §5.2; it does not conserve momentum in
    such contacts, by design)."""
    wi = w[i]
    wj = w[j]
    scale = np.exp(lift * (x[j, 2] - x[i, 2])) if lift != 0.0 and wj > 0.0 else 1.0
    wsum = wi + wj * scale
    if wsum <= 0.0:
        return -1.0
    share = wi / wsum
    if upright and wi > 0.0 and wj > 0.0 and nz != 0.0:
        even = 1.0 / (1.0 + scale)
        if (nz < 0.0 and share > even) or (nz > 0.0 and share < even):  # the lower one acts lighter
            share += (even - share) * nz * nz
    return share


@njit(cache=True, inline="always")
def sleeper_share(x, x_prev, w, awake, pushed, i, j, wake_step):
    """Share of i in a pair with one asleep particle: the asleep one is held like a static obstacle
    (the awake one takes the whole correction, so a grain resting on sleepers loads nothing onto
    them) and is marked ``pushed`` when the awake one moved more than ``wake_step`` this substep (it
    runs or slides into the sleeper faster than the sleep threshold plus one step of gravity)."""
    a, b = (i, j) if awake[i] else (j, i)
    dx = x[a, 0] - x_prev[a, 0]
    dy = x[a, 1] - x_prev[a, 1]
    dz = x[a, 2] - x_prev[a, 2]
    if dx * dx + dy * dy + dz * dz > wake_step * wake_step:
        pushed[b] = True
    if w[a] <= 0.0:
        return -1.0
    return 1.0 if a == i else 0.0


def face_compliance(r, q_rest, start, strain: float, load: float, crush: float, sample: int = 64):
    """The XPBD compliance (mm/N) of one face of an element and the overlap (mm) it gives before it turns rigid,
    such that the element squeezed flat between two rigid plates under ``load`` (N) strains by ``strain``: its
    thickness t along its thinnest axis (the smallest principal axis of its particles) shortens by strain·t, half at
    each face, and a face's particles carry the load in parallel, each by its own overlap (the particles a plate
    reaches first carry more, so the element stiffens as it flattens): α = Σ_k max(0, δ − (top − s_k)) / load,
    δ = strain·t/2, s_k the top of particle k's sphere. Averaged over both faces and the median over up to
    ``sample`` elements (``start``: CSR of the clusters, ``q_rest``: rest offsets, ``r``: radii). The crush overlap
    is crush·t/2 (a face rigid past that strain). Overlap = α·F at rest whatever the iterations (Macklin, Müller &
    Chentanez 2016, XPBD eq. 18)."""
    m = len(start) - 1
    alphas, limits = [], []
    for e in np.unique(np.linspace(0, m - 1, min(m, sample)).astype(np.int64)):
        q, radius = q_rest[start[e] : start[e + 1]], r[start[e] : start[e + 1]]
        q = q - q.mean(axis=0)
        axis = np.linalg.eigh(q.T @ q)[1][:, 0] if len(q) > 1 else np.array([0.0, 0.0, 1.0])
        s = q @ axis
        t = float((s + radius).max() - (s - radius).min())
        delta = strain * t / 2.0
        given = [np.maximum(0.0, delta - (top.max() - top)).sum() for top in (s + radius, radius - s)]
        alphas.append(0.5 * sum(given) / load)
        limits.append(crush * t / 2.0)
    return float(np.median(alphas)), float(np.median(limits))


@njit(cache=True, inline="always")
def compliant_push(x, x_prev, w, p, q, normal, pen, share, spring, a, soft):
    """The normal correction of a pair overlapping by ``pen`` beyond what it tolerates, with compliance: damped XPBD
    Δλ = (pen − α̃λ − γ·Δs)/((1 + γ)W + α̃) (Macklin, Müller & Chentanez 2016, eqs. 18 and 26) in correction units
    c = W·λ, never negative within a substep; Δs the pair's separation over the solve so far (x − x_prev along
    ``normal``, from q to p), γ = 2ζ·√(α̃/W) (a spring of damping ratio ζ), so a landing grain does not bounce on
    the overlap it compressed. ``soft`` = (α̃ per face of a moving element, a static obstacle being rigid; the crush
    overlap per face; ζ). W is the inverse mass the correction's split (``share`` to p, mass scaling included) gives
    the heavier side, min(w_p/share, w_q/(1 − share)): then λ/h² is the force on that side, and a pair at rest
    keeps the overlap α·F however many iterations run (a heavy plate on light grains carries its weight). Past
    ``crush`` per face it is rigid (the rest is corrected in full). ``spring[a]`` keeps the elastic overlap α̃·λ."""
    alpha, crush, zeta = soft
    faces = (1.0 if w[p] > 0.0 else 0.0) + (1.0 if w[q] > 0.0 else 0.0)
    at = alpha * faces
    wsum = np.inf
    if share > 0.0 and w[p] > 0.0:
        wsum = w[p] / share
    if share < 1.0 and w[q] > 0.0:
        wsum = min(wsum, w[q] / (1.0 - share))
    if at <= 0.0 or wsum == np.inf:
        return pen
    c = spring[a] * wsum / at
    nx, ny, nz = normal
    sep = (
        (x[p, 0] - x_prev[p, 0] - x[q, 0] + x_prev[q, 0]) * nx
        + (x[p, 1] - x_prev[p, 1] - x[q, 1] + x_prev[q, 1]) * ny
        + (x[p, 2] - x_prev[p, 2] - x[q, 2] + x_prev[q, 2]) * nz
    )
    gamma = 2.0 * zeta * np.sqrt(at / wsum)
    push = max(wsum * (pen - at * c / wsum - gamma * sep) / ((1.0 + gamma) * wsum + at), 0.0)
    held = at * (c + push) / wsum
    limit = crush * faces
    if held > limit:  # crushed: the face turns rigid
        held = limit
    spring[a] = held
    rest = pen - push - limit
    return push + rest if rest > 0.0 else push


@njit(cache=True)
def _project_slab(x, x_prev, awake, pushed, w, r, rows, entries, rule, p0, p1):
    """Project, in order, every pair listed in the rows of the sorted range p0:p1 (a slab; full
    rows, ``half`` false: each pair from its lower id) but pairs of two asleep particles
    (``awake``, ``integrate.wake_flags``: at rest, nothing to do; with one asleep, ``sleeper_share``):
    friction when μs > 0 (``friction.friction_pair``; normal load: the pair's overlap as the sweep
    meets it, the d of Macklin et al. 2014 §6.1, plus with anchors the normal correction the pair has
    received this substep, ``entries.load``, and the pull of a moist contact's adhesion, ``rule.cohesion``
    × (w_i + w_j): sticky grains hold against μs·(weight + adhesion), as cohesive granular matter does), then
    the normal correction (``rule.normal``).
    Friction after the correction let the tangential moves re-open overlaps: the tall-pile test's max
    penetration rose from 0.14 r to 0.20 r; before it, 0.15 r. The load was once the overlap the
    correction would leave (the tolerated ``allowance``), ≈ 0 at a resting contact once
    pre-stabilisation removes old overlap: pair friction held nothing and a bar resting on another
    crept at 0.13 mm/s for ever (issue 11). A pair whose gap opens past ``friction.RELEASE`` of the
    radii sum lets go of its anchor.
    The friction of pairs whose grains the glue still holds (``entries.glued``) takes the true masses, not the
    mass scaling: split like the normal correction (the upper grain taking more), their anchored friction's
    tangential pushes inside one glued body did not cancel and rocked a glued onigiri on its plate (bulk speed
    ±170 mm/s at ≈ 40 Hz, growing 1.3–1.7× a frame until it slid: nothing ever slept; docs/validation.md).
    Without their friction a tall glued block toppled (it is part of the glue's shear stiffness), without the
    mass scaling of their normal corrections the onigiri slumped to 93 % of its height.
    Pairs of elements placed inside one another (``entries.parting``) rub not at all until they part (``parting``).
    The particle arrays are the sweep's sorted copies (``_sorted_copies``: row p holds particle order[p], a
    partner's row is ``rows.at``)."""
    nbr_start, nbr, half, order, at = rows
    allowance, anchor, load, held_mean, modes, rubbed, glued, spring, parting = entries
    wake_step, lift, upright, mu_s, mu_k, anchored, normal, cohesion, alpha, crush, zeta = rule
    any_glued = glued.shape[0] > 0
    any_parting = parting.shape[0] > 0
    for p in range(p0, p1):
        i = order[p]
        for a in range(nbr_start[p], nbr_start[p + 1]):
            j = nbr[a]
            if not half and j < i:
                continue  # each pair once, from its lower index
            q = at[a]
            if not (awake[p] or awake[q]):
                continue
            nx, ny, nz, d = pair_normal_at(x, p, q, i, j)
            depth = r[p] + r[q] - d
            if depth <= 0.0:
                if anchored and mu_s > 0.0 and depth < -RELEASE * (r[p] + r[q]):
                    anchor[a, 0] = np.nan
                continue
            if awake[p] and awake[q]:
                share = lifted_share(w, x, p, q, nz, lift, upright)
            else:
                share = sleeper_share(x, x_prev, w, awake, pushed, p, q, wake_step)
            if share < 0.0:
                continue
            pen = depth - allowance[a] if normal else 0.0
            if alpha > 0.0 and pen > 0.0:  # the correction a compliant contact takes (before friction reads it)
                soft = (alpha, crush, zeta)
                pen = compliant_push(x, x_prev, w, p, q, (nx, ny, nz), pen, share, spring, a, soft)
            if mu_s > 0.0 and not (any_parting and parting[a]):  # friction first, the normal correction last
                mode = TESTED
                if anchored:  # the contact's pooled load and mode, else (none touched last substep, glued, or a
                    # sphere's: ``friction.ROLLS``) its own
                    pooled = held_mean[a] > 0.0 and not (any_glued and glued[a]) and modes[a] != ROLLS
                    own = held_mean[a] if pooled else load[a] + max(pen, 0.0)
                    held = own + cohesion * (w[p] + w[q])
                    if pooled:
                        mode = modes[a]
                else:
                    held = depth
                # glued grains rub with their true masses: their tangential pushes cancel
                rub = w[p] / (w[p] + w[q]) if any_glued and glued[a] else share
                friction_pair(x, x_prev, anchor, rubbed, a, p, q, (nx, ny, nz), held, rub, (mu_s, mu_k, anchored), mode)
            if pen > 0.0:
                if anchored and mu_s > 0.0:
                    load[a] += pen
                si = pen * share
                sj = pen - si
                x[p, 0] += si * nx
                x[p, 1] += si * ny
                x[p, 2] += si * nz
                x[q, 0] -= sj * nx
                x[q, 1] -= sj * ny
                x[q, 2] -= sj * nz


@njit(cache=True)
def _colour_chunks(cell_start, dims, colour, chunks, out):
    """Split the slabs of one colour (x index ≡ colour mod 3) into ``chunks`` consecutive runs of
    about equal particle count (``out`` gets the run bounds in slab-of-colour units): a split by
    slab count left one thread with the whole pile when a few escaped particles stretched the grid."""
    slab = dims[1] * dims[2]
    m = (dims[0] - colour + 2) // 3
    total = 0
    for k in range(m):
        ix = colour + 3 * k
        total += cell_start[(ix + 1) * slab] - cell_start[ix * slab]
    out[0] = 0
    t = 1
    seen = 0
    for k in range(m):
        ix = colour + 3 * k
        seen += cell_start[(ix + 1) * slab] - cell_start[ix * slab]
        while t < chunks and seen * chunks >= t * total:
            out[t] = k + 1
            t += 1
    while t <= chunks:
        out[t] = m
        t += 1


@njit(cache=True, parallel=True)
def contact_sweep(state, model, rows, colouring, entries, rule, chunks):
    """One Gauss–Seidel sweep over the touching pairs, in place: the non-penetration constraint
    C = |x_i − x_j| − r_i − r_j + allowance ≥ 0 (``entries.allowance`` per list entry;
    ``rule.normal``) with shock propagation ``rule.lift`` (1/length, 0 = off), and in the same pass
    anchored friction (``rule.mu_s`` > 0; ``entries.anchor`` per list entry, ``friction``) on each
    pair just before its normal correction — one sweep instead of a contact sweep plus a Jacobi
    friction sweep (which cost ≈ 0.5× the contacts again, issue-6 profile). ``rows``: the
    ``PairRows`` of the neighbour lists; ``colouring``: the grid they were built on
    (``spatial_hash.neighbour_lists``); slabs of cells with the same x index modulo 3 share no
    particle, so each colour runs as ``chunks`` parallel runs of slabs balanced by particle count.
    The result does not depend on ``chunks``. Sleeping: pairs of two asleep particles are skipped, an
    asleep one is held still and marked ``pushed`` by a fast awake partner (``sleeper_share``;
    ``rule.wake_step`` = inf marks none). ``state``: ``StateArrays`` (x, x_prev, awake, pushed), ``model``:
    ``ModelArrays`` (w, r)."""
    x, x_prev, awake, pushed = state.x, state.x_prev, state.awake, state.pushed
    w, r = model.w, model.r
    cell_start, order, dims = colouring
    xs, xps, aw, pu, ws, rs = _sorted_copies(x, x_prev, awake, pushed, w, r, order)
    slab = dims[1] * dims[2]
    bounds = np.empty(chunks + 1, np.int64)
    for colour in range(3):
        _colour_chunks(cell_start, dims, colour, chunks, bounds)
        for t in prange(chunks):
            for k in range(bounds[t], bounds[t + 1]):
                ix = colour + 3 * k
                p0 = cell_start[ix * slab]
                p1 = cell_start[(ix + 1) * slab]
                _project_slab(xs, xps, aw, pu, ws, rs, rows, entries, rule, p0, p1)
    for p in prange(order.shape[0]):
        i = order[p]
        x[i, 0] = xs[p, 0]
        x[i, 1] = xs[p, 1]
        x[i, 2] = xs[p, 2]
        pushed[i] = pu[p]


@njit(cache=True, parallel=True)
def _sorted_copies(x, x_prev, awake, pushed, w, r, order):
    """The particles' arrays in the grid's sorted order (row p = particle order[p]): the sweep walks
    that order and a pair's partners lie in nearby cells, so it reads neighbouring memory instead of
    jumping by particle id (at 50k particles on a 1 MiB-L2 core the sweep took 1.9× as long)."""
    n = order.shape[0]
    xs = np.empty((n, 3))
    xps = np.empty((n, 3))
    aw = np.empty(n, np.bool_)
    pu = np.empty(n, np.bool_)
    ws = np.empty(n)
    rs = np.empty(n)
    for p in prange(n):
        i = order[p]
        for k in range(3):
            xs[p, k] = x[i, k]
            xps[p, k] = x_prev[i, k]
        aw[p] = awake[i]
        pu[p] = pushed[i]
        ws[p] = w[i]
        rs[p] = r[i]
    return xs, xps, aw, pu, ws, rs


@njit(cache=True, inline="always")
def _allowance_row(x, awake, r, nbr_start, nbr, half, decay, out, p, i):
    for a in range(nbr_start[p], nbr_start[p + 1]):
        j = nbr[a]
        if (not half and j < i) or not (awake[i] or awake[j]):
            continue  # the sweep reads each pair's entry from its lower index only, and skips asleep pairs
        _, _, _, d = pair_normal(x, i, j)
        out[a] = max(0.0, r[i] + r[j] - d - decay * min(r[i], r[j]))


@njit(cache=True, parallel=True)
def overlap_allowance(state, model, rows, decay, out):
    """Per list entry, the overlap r_i + r_j − d that remains less decay·min(r_i, r_j) (≥ 0):
    tolerated until the next pre-stabilisation. Entries the sweep skips (j < i in full rows, ``half``
    false; pairs of two asleep particles, ``awake``) are not written. ``state``: ``StateArrays`` (x, the
    positions measured, and awake), ``model``: ``ModelArrays`` (r), ``rows``: ``PairRows``."""
    x, awake = state.x, state.awake
    r = model.r
    nbr_start, nbr, half, order = rows.nbr_start, rows.nbr, rows.half, rows.order
    for p in prange(x.shape[0]):
        _allowance_row(x, awake, r, nbr_start, nbr, half, decay, out, p, order[p])


@njit(cache=True, parallel=True)
def max_penetration_ratio(x, r, nbr_start, nbr, order):
    """max over contacts of (r_i + r_j − d) / min(r_i, r_j): the residual overlap, in radii."""
    n = x.shape[0]
    worst = np.zeros(n)
    for p in prange(n):
        i = order[p]
        m = 0.0
        for a in range(nbr_start[p], nbr_start[p + 1]):
            j = nbr[a]
            _, _, _, d = pair_normal(x, i, j)
            pen = (r[i] + r[j] - d) / min(r[i], r[j])
            if pen > m:
                m = pen
        worst[i] = m
    return worst.max() if n > 0 else 0.0
