"""Particle–particle non-penetration between different elements — SPEC §3 (XPBD contact).

Gauss–Seidel by graph colouring: the neighbour grid is cut into slabs one cell thick along x and
coloured by the slab index modulo 3; slabs of one colour share no particle (neighbours lie at most
one cell away), so they run in parallel while each slab projects its pairs one after another,
updating both particles at once. Three colours, not 27 cells' worth: a parallel launch costs
≈ 0.1 ms on this machine, more than a whole sweep of a few thousand particles. Averaged Jacobi (each
particle moves by the mean of its contacts' corrections) was stable but weak: in a dense pile a
particle with n contacts moved by 1/n of what it needed per sweep, and 50k-sphere piles sank into
themselves (penetration ≈ 2 radii). Gauss–Seidel has no such division and stays race-free and
deterministic (the order within a cell is fixed, colours run in a fixed order).
Contacts have zero compliance and produce no restitution: velocities come from positions.

Tall piles: shock propagation by mass scaling (Macklin et al. 2014 §5.2, after Guendelman et al.
2003). Within the contact solve a particle's inverse mass is scaled by exp(k·z): the lower of two
touching particles acts heavier, so the upper one takes the correction. Averaged Jacobi without it
spreads a column's weight like diffusion (≈ layers² sweeps to carry it to the floor), and piles a
few dozen particles high sink into each other; with it each layer rests on the one below within a
few sweeps. The split uses the height difference of the pair only, w_i / (w_i + w_j·e^{k(z_j − z_i)}),
so no exponent overflows however tall the pile. Rest positions do not depend on masses.
Overlap left over at the start of a substep is removed mostly by pre-stabilisation (moves that add
no velocity, Macklin et al. 2014 §4.2); within the substep each pair may keep that overlap less a
``decay`` share of the smaller radius (``allowance``). Deep initial overlaps therefore separate
without a burst of kinetic energy (at most decay·r/h of separation speed; the solver passes decay = rate·h, a fixed speed), while old overlaps still
shrink every substep: an allowance that never decays ratchets, since each impact adds overlap
that is then tolerated for good, and falling columns ended with coincident particles.
"""

import numpy as np
from numba import njit, prange


@njit(cache=True, inline="always")
def pair_normal(x, i, j):
    """Unit vector from j to i and the distance; coincident particles get a fixed pseudo-random
    direction, antisymmetric in (i, j), so deep overlaps separate deterministically."""
    nx = x[i, 0] - x[j, 0]
    ny = x[i, 1] - x[j, 1]
    nz = x[i, 2] - x[j, 2]
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
def lifted_share(w, x, i, j, lift):
    """Share of a pair correction taken by i: w_i / (w_i + w_j·e^{lift·(z_j − z_i)}) (mass scaling by
    height; lift = 0 is the plain w_i / (w_i + w_j)). Returns −1 when both are immovable; a static
    partner (w_j = 0) stays infinitely heavy at any height (no 0·exp overflow)."""
    wj = w[j] * np.exp(lift * (x[j, 2] - x[i, 2])) if lift != 0.0 and w[j] > 0.0 else w[j]
    wsum = w[i] + wj
    return w[i] / wsum if wsum > 0.0 else -1.0


@njit(cache=True, inline="always")
def _project_cell(x, w, r, nbr_start, nbr, allowance, lift, order, p0, p1):
    """Project, in order, every pair (i, j > i) whose i lies in the sorted range p0:p1 (a slab)."""
    for p in range(p0, p1):
        i = order[p]
        for a in range(nbr_start[i], nbr_start[i + 1]):
            j = nbr[a]
            if j < i:
                continue  # each pair once, from its lower index
            nx, ny, nz, d = pair_normal(x, i, j)
            pen = r[i] + r[j] - d - allowance[a]
            if pen <= 0.0:
                continue
            share = lifted_share(w, x, i, j, lift)
            if share < 0.0:
                continue
            si = pen * share
            sj = pen - si
            x[i, 0] += si * nx
            x[i, 1] += si * ny
            x[i, 2] += si * nz
            x[j, 0] -= sj * nx
            x[j, 1] -= sj * ny
            x[j, 2] -= sj * nz


@njit(cache=True, parallel=True, fastmath=True)
def contact_gauss_seidel(x, w, r, nbr_start, nbr, allowance, lift, cell_start, order, dims):
    """One Gauss–Seidel sweep of C = |x_i − x_j| − r_i − r_j + allowance ≥ 0 (allowance per list
    entry) in place, with shock propagation ``lift`` (1/length, 0 = off). ``cell_start, order,
    dims`` are the grid the neighbour lists were built on (``spatial_hash.neighbour_lists``):
    slabs of cells with the same x index modulo 3 share no particle and run in parallel."""
    slab = dims[1] * dims[2]
    for colour in range(3):
        for k in prange((dims[0] - colour + 2) // 3):
            ix = colour + 3 * k
            _project_cell(x, w, r, nbr_start, nbr, allowance, lift, order, cell_start[ix * slab],
                          cell_start[(ix + 1) * slab])


@njit(cache=True, fastmath=True)
def contact_gauss_seidel_serial(x, w, r, nbr_start, nbr, allowance, lift, cell_start, order, dims):
    """``contact_gauss_seidel`` on one thread, same order, same result: for small scenes, where the
    parallel launches cost more than the sweep itself."""
    slab = dims[1] * dims[2]
    for colour in range(3):
        for k in range((dims[0] - colour + 2) // 3):
            ix = colour + 3 * k
            _project_cell(x, w, r, nbr_start, nbr, allowance, lift, order, cell_start[ix * slab],
                          cell_start[(ix + 1) * slab])


@njit(cache=True, parallel=True, fastmath=True)
def overlap_allowance(x, r, nbr_start, nbr, decay, out):
    """Per list entry, the overlap r_i + r_j − d that remains less decay·min(r_i, r_j) (≥ 0):
    tolerated until the next pre-stabilisation."""
    n = x.shape[0]
    for i in prange(n):
        for a in range(nbr_start[i], nbr_start[i + 1]):
            j = nbr[a]
            _, _, _, d = pair_normal(x, i, j)
            out[a] = max(0.0, r[i] + r[j] - d - decay * min(r[i], r[j]))


@njit(cache=True, parallel=True, fastmath=True)
def max_penetration_ratio(x, r, nbr_start, nbr):
    """max over contacts of (r_i + r_j − d) / min(r_i, r_j): the residual overlap, in radii."""
    n = x.shape[0]
    worst = np.zeros(n)
    for i in prange(n):
        m = 0.0
        for a in range(nbr_start[i], nbr_start[i + 1]):
            j = nbr[a]
            _, _, _, d = pair_normal(x, i, j)
            pen = (r[i] + r[j] - d) / min(r[i], r[j])
            if pen > m:
                m = pen
        worst[i] = m
    return worst.max() if n > 0 else 0.0
