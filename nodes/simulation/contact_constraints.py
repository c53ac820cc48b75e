"""Particle–particle non-penetration between different elements — SPEC §3 (XPBD contact).

Jacobi with averaging: each particle gathers the corrections of all its contacts and applies their
mean (divided by the contact count), which stays stable where summed Jacobi updates explode in
dense piles. Per-particle gathering (not per-pair scattering) keeps the parallel loop race-free.
Contacts have zero compliance and produce no restitution: velocities come from positions.
Overlap left over at the start of a substep is removed by pre-stabilisation only (moves that add
no velocity, Macklin et al. 2014 §4.2); within the substep each pair may keep that much overlap
(``allowance``), so deep initial overlaps separate without a burst of kinetic energy.
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


@njit(cache=True, parallel=True, fastmath=True)
def contact_project(x, w, r, nbr_start, nbr, allowance, out):
    """One Jacobi sweep of C = |x_i − x_j| − r_i − r_j + allowance ≥ 0 (allowance per list entry);
    writes the averaged result to ``out``, which must not alias ``x``."""
    n = x.shape[0]
    for i in prange(n):
        ax = 0.0
        ay = 0.0
        az = 0.0
        count = 0
        wi = w[i]
        for a in range(nbr_start[i], nbr_start[i + 1]):
            j = nbr[a]
            wsum = wi + w[j]
            if wsum <= 0.0:
                continue
            nx, ny, nz, d = pair_normal(x, i, j)
            pen = r[i] + r[j] - d - allowance[a]
            if pen > 0.0:
                s = pen * wi / wsum
                ax += s * nx
                ay += s * ny
                az += s * nz
                count += 1
        if count > 0:
            out[i, 0] = x[i, 0] + ax / count
            out[i, 1] = x[i, 1] + ay / count
            out[i, 2] = x[i, 2] + az / count
        else:
            out[i, 0] = x[i, 0]
            out[i, 1] = x[i, 1]
            out[i, 2] = x[i, 2]


@njit(cache=True, parallel=True, fastmath=True)
def overlap_allowance(x, r, nbr_start, nbr, out):
    """Per list entry, the overlap r_i + r_j − d that remains (≥ 0): tolerated until the next
    pre-stabilisation."""
    n = x.shape[0]
    for i in prange(n):
        for a in range(nbr_start[i], nbr_start[i + 1]):
            _, _, _, d = pair_normal(x, i, nbr[a])
            out[a] = max(0.0, r[i] + r[nbr[a]] - d)


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
