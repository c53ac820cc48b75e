"""Position-level static and dynamic friction on contacts — Macklin et al. 2014 §6.1.

For a contact with overlap d (its normal load), the relative tangential displacement Δx_t over the
substep is removed entirely when |Δx_t| < μs·d (static: sticking), otherwise scaled by
min(μk·d/|Δx_t|, 1) (dynamic). G Table 3: μs = static threshold, μk = dynamic scale · μs.
``tangential_slip`` is that rule, once, for both kinds of contact: particle pairs (``friction_pair``,
applied per pair inside the contacts' Gauss–Seidel sweep, ``contact_constraints.contact_sweep``,
just before the pair's normal correction: a separate averaged-Jacobi friction sweep cost half as
much as the contacts again and re-read every pair, issue-6 profile) and a particle against a
collider wall (``collider.collider_project``, the wall a partner that never moves).
"""

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def tangential_slip(rx, ry, rz, nx, ny, nz, depth, mu_s, mu_k):
    """(share, tx, ty, tz): the tangential part t of the relative displacement r against the unit
    normal n, and the share of it friction removes — 1 when |t| < μs·depth (static), else
    min(μk·depth/|t|, 1) (dynamic); share −1 when there is no tangential motion (|t| ≤ 1e-12)."""
    dn = rx * nx + ry * ny + rz * nz
    tx = rx - dn * nx
    ty = ry - dn * ny
    tz = rz - dn * nz
    t = np.sqrt(tx * tx + ty * ty + tz * tz)
    if t <= 1e-12:
        return -1.0, tx, ty, tz
    return (1.0 if t < mu_s * depth else min(mu_k * depth / t, 1.0)), tx, ty, tz


@njit(cache=True, inline="always")
def friction_pair(x, x_prev, i, j, nx, ny, nz, depth, share, mu_s, mu_k):
    """Friction on the pair (i, j) with unit normal n (j → i) and overlap ``depth``, in place; i
    takes ``share`` of the correction, j the rest (the contacts' mass scaling)."""
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


@njit(cache=True, inline="always")
def friction_wall(x, x_prev, i, nx, ny, nz, depth, mu_s, mu_k):
    """Friction of particle i against a static wall with unit normal n and penetration ``depth``,
    in place: the pair rule with a partner that does not move and takes no share."""
    scale, tx, ty, tz = tangential_slip(
        x[i, 0] - x_prev[i, 0], x[i, 1] - x_prev[i, 1], x[i, 2] - x_prev[i, 2], nx, ny, nz, depth, mu_s, mu_k
    )
    if scale < 0.0:
        return
    x[i, 0] -= scale * tx
    x[i, 1] -= scale * ty
    x[i, 2] -= scale * tz
