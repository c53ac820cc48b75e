"""Clumping: breakable adhesion between particles of different elements — SPEC §3, issue 6.

Houdini has no grain "clumping"; we define it as an attractive distance constraint C = gap
(gap = |x_i − x_j| − r_i − r_j) for 0 < gap ≤ capture radius, with compliance from the adhesion
strength. A bond breaks (exerts nothing) once the gap exceeds the capture radius, so bonds hold no
state and λ is not accumulated across iterations. Jacobi with averaging. Pairs use the contacts'
mass scaling by height (``lift``): with plain masses adhesion pulled back what the scaled contacts
pushed, and the two pumped energy into piles at many substeps × iterations (32 × 8 exploded).
Static obstacle particles (w = 0) hold no bonds: with an immovable partner nothing recoils, and the
pull towards near-touching bed particles, undone by the contacts only along their normals, drove
eggs sideways across a static bed (measured: a lone egg reached the speed clamp, > 500 mm/s, and
left the bed; with moving partners the recoil cancels it). Contact and friction do act on them.
"""

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .contact_constraints import pair_normal


class AdhesionRule(NamedTuple):
    """What ``adhesion_project`` takes of the settings (once per run, ``solver.XpbdSolver``)."""

    capture: float  # mm: bonds break beyond this gap
    alpha_tilde: float  # compliance / h²
    lift: float  # the contacts' mass scaling by height, 1/mm


@njit(cache=True, parallel=True)
def adhesion_project(state, model, rows, rule, out):
    """One Jacobi sweep pulling near-touching pairs together; ``capture`` in length units,
    ``alpha_tilde`` = compliance / h² (larger is weaker), ``lift`` the contacts' mass scaling.
    Asleep particles (``awake``, ``integrate.wake_flags``) are not moved (an awake partner still
    takes its own share of their bond). Writes to ``out`` (no aliasing). ``state``: ``StateArrays`` (x, x_prev,
    awake), ``model``: ``ModelArrays`` (w, r), ``rows``: the neighbour lists' ``buffers.ListRows``, ``rule``:
    ``AdhesionRule``. Per pair, XPBD with constraint damping (Macklin et al. 2016, eq. 26):
    Δx_i = −(gap + γ·n·(Δx_i − Δx_j))·w_i / ((1 + γ)·w + α̃)·n, averaged, with w = w_i + w_j·e^{lift·(z_j − z_i)},
    Δx the substep's motion so far, and γ = 2·√(α̃ / w) the critical damping (ζ = 1) of the bond's spring on
    the pair's mass. Undamped, the bond and the contacts traded energy every substep: at 40 substeps a resting
    sticky clump heated up and crept flat (``tests/simulation/test_adhesion_energy.py``); cooked rice's starch
    paste is viscous, so a bond pulls without ringing."""
    x, x_prev, awake = state.x, state.x_prev, state.awake
    w, r = model.w, model.r
    nbr_start, nbr, order = rows.nbr_start, rows.nbr, rows.order
    capture, alpha_tilde, lift = rule.capture, rule.alpha_tilde, rule.lift
    n = x.shape[0]
    for p in prange(n):
        i = order[p]  # row p lists the partners of order[p] (``spatial_hash.neighbour_lists``)
        ax = 0.0
        ay = 0.0
        az = 0.0
        count = 0
        wi = w[i]
        stop = nbr_start[p + 1] if awake[i] else nbr_start[p]  # an asleep particle stays put
        for a in range(nbr_start[p], stop):
            j = nbr[a]
            if wi <= 0.0 or w[j] <= 0.0:
                continue  # no bonds with static obstacles (module docstring)
            nx, ny, nz, d = pair_normal(x, i, j)
            gap = d - r[i] - r[j]
            if gap <= 0.0 or gap > capture:
                continue
            wsum = wi + (w[j] * np.exp(lift * (x[j, 2] - x[i, 2])) if lift != 0.0 else w[j])
            rel = (
                nx * (x[i, 0] - x_prev[i, 0] - x[j, 0] + x_prev[j, 0])
                + ny * (x[i, 1] - x_prev[i, 1] - x[j, 1] + x_prev[j, 1])
                + nz * (x[i, 2] - x_prev[i, 2] - x[j, 2] + x_prev[j, 2])
            )
            gamma = 2.0 * np.sqrt(alpha_tilde / wsum) if alpha_tilde < np.inf else 0.0  # ζ = 1 (docstring)
            s = -(gap + gamma * rel) * wi / ((1.0 + gamma) * wsum + alpha_tilde)
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
