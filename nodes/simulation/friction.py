"""Position-level static and dynamic friction on particle contacts — Macklin et al. 2014 §6.1.

For a penetrating pair with depth d, the relative tangential displacement Δx_t over the substep is
removed entirely when |Δx_t| < μs·d (static: sticking), otherwise scaled by min(μk·d/|Δx_t|, 1)
(dynamic). G Table 3: μs = static threshold, μk = dynamic scale · μs. Jacobi with averaging.
"""

from numba import njit, prange

from .contact_constraints import lifted_share, pair_normal


@njit(cache=True, parallel=True, fastmath=True)
def friction_project(x, x_prev, w, r, nbr_start, nbr, mu_s, mu_k, lift, out):
    """One Jacobi sweep of contact friction, with the contacts' mass scaling ``lift``; writes the
    averaged result to ``out`` (no aliasing)."""
    n = x.shape[0]
    for i in prange(n):
        ax = 0.0
        ay = 0.0
        az = 0.0
        count = 0
        for a in range(nbr_start[i], nbr_start[i + 1]):
            j = nbr[a]
            share = lifted_share(w, x, i, j, lift)
            if share < 0.0:
                continue
            nx, ny, nz, d = pair_normal(x, i, j)
            pen = r[i] + r[j] - d
            if pen <= 0.0:
                continue
            rx = (x[i, 0] - x_prev[i, 0]) - (x[j, 0] - x_prev[j, 0])
            ry = (x[i, 1] - x_prev[i, 1]) - (x[j, 1] - x_prev[j, 1])
            rz = (x[i, 2] - x_prev[i, 2]) - (x[j, 2] - x_prev[j, 2])
            dn = rx * nx + ry * ny + rz * nz
            tx = rx - dn * nx
            ty = ry - dn * ny
            tz = rz - dn * nz
            t = (tx * tx + ty * ty + tz * tz) ** 0.5
            if t <= 1e-12:
                continue
            scale = 1.0 if t < mu_s * pen else min(mu_k * pen / t, 1.0)
            s = -scale * share
            ax += s * tx
            ay += s * ty
            az += s * tz
            count += 1
        if count > 0:
            out[i, 0] = x[i, 0] + ax / count
            out[i, 1] = x[i, 1] + ay / count
            out[i, 2] = x[i, 2] + az / count
        else:
            out[i, 0] = x[i, 0]
            out[i, 1] = x[i, 1]
            out[i, 2] = x[i, 2]
