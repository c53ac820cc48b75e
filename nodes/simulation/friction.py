"""Position-level static and dynamic friction on particle contacts — Macklin et al. 2014 §6.1.

For a touching pair with overlap d (its normal load), the relative tangential displacement Δx_t
over the substep is removed entirely when |Δx_t| < μs·d (static: sticking), otherwise scaled by
min(μk·d/|Δx_t|, 1) (dynamic). G Table 3: μs = static threshold, μk = dynamic scale · μs.
Applied per pair inside the contacts' Gauss–Seidel sweep (``contact_constraints.contact_sweep``),
just before the pair's normal correction: a separate averaged-Jacobi friction sweep cost half as
much as the contacts again and re-read every pair (issue-6 profile).
"""

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def friction_pair(x, x_prev, i, j, nx, ny, nz, depth, share, mu_s, mu_k):
    """Friction on the pair (i, j) with unit normal n (j → i) and overlap ``depth``, in place; i
    takes ``share`` of the correction, j the rest (the contacts' mass scaling)."""
    rx = (x[i, 0] - x_prev[i, 0]) - (x[j, 0] - x_prev[j, 0])
    ry = (x[i, 1] - x_prev[i, 1]) - (x[j, 1] - x_prev[j, 1])
    rz = (x[i, 2] - x_prev[i, 2]) - (x[j, 2] - x_prev[j, 2])
    dn = rx * nx + ry * ny + rz * nz
    tx = rx - dn * nx
    ty = ry - dn * ny
    tz = rz - dn * nz
    t = np.sqrt(tx * tx + ty * ty + tz * tz)
    if t <= 1e-12:
        return
    scale = 1.0 if t < mu_s * depth else min(mu_k * depth / t, 1.0)
    si = scale * share
    sj = scale - si
    x[i, 0] -= si * tx
    x[i, 1] -= si * ty
    x[i, 2] -= si * tz
    x[j, 0] += sj * tx
    x[j, 1] += sj * ty
    x[j, 2] += sj * tz
