"""Per-element transform and deformation from the particle fit — SPEC §5 (A = A_pq·A_qq).

The element's high-resolution mesh follows its cluster (G: carry the high-res grain on the
low-res simulation): v_world = D·R·v_local + t, with R the cluster rotation and D = R·S·Rᵀ the
symmetric stretch of the least-squares fit, its principal stretches clamped to [0.5, 2] and left
at 1 along axes a collinear/planar cluster cannot observe.
"""

import numpy as np

from .shape_matching import particle_masses


def element_transforms(x, w, start, q_rest, rotations, centres, aqq_pinv, null_proj, local_centre):
    """(positions (m, 3), rotations (m, 3, 3), deformations (m, 3, 3)) of every element."""
    m = len(start) - 1
    deformations = np.tile(np.eye(3), (m, 1, 1))
    for c in range(m):
        s, e = start[c], start[c + 1]
        if e - s < 2:
            continue
        mass = particle_masses(w[s:e])
        apq = ((x[s:e] - centres[c]) * mass[:, None]).T @ q_rest[s:e]
        stretch = rotations[c].T @ (apq @ aqq_pinv[c]) + null_proj[c]
        stretch = 0.5 * (stretch + stretch.T)
        vals, vecs = np.linalg.eigh(stretch)
        vals = np.clip(vals, 0.5, 2.0)
        deformations[c] = rotations[c] @ (vecs * vals) @ vecs.T @ rotations[c].T
    positions = centres - np.einsum("cij,cjk,ck->ci", deformations, rotations, local_centre)
    return positions, rotations, deformations


def _monomial_jacobian_at(o):
    """(6, 3) linear part of m(v − o) in v: m(v − o) = m(v) + J·v + m(o), m = [x², y², z², xy, yz, zx]."""
    ox, oy, oz = o
    return -np.array([[2 * ox, 0, 0], [0, 2 * oy, 0], [0, 0, 2 * oz], [oy, ox, 0], [0, oz, oy], [oz, 0, ox]])


def element_bends(x, w, start, q_rest, rotations, centres, positions, deformations, quadratic, local_centre):
    """(positions, deformations, bends (m, 3, 6)) with the quadratic term of every flagged cluster — SPEC §5.

    The bend B is the least-squares fit of the particles' local-frame residual after the linear map,
    Rᵀ(p_i − D·R·q_i) ≈ B·(m(q_i) − m̄), over the six monomials of the rest offset q_i from the
    cluster's rest centre of mass (``local_centre``; m̄ their mass-weighted mean, so x_cm stays put).
    It follows the particles, which already carry the β-blended goal: no second β. The map is then
    re-expressed about the mesh origin (what ``Aggregate.bends`` states): the linear and constant
    parts of m(v − c₀) move into the deformation and the position. Unflagged clusters (too few or
    degenerate particles, the solver's linear goal) keep a zero bend and their linear map unchanged.
    """
    from ..values import Aggregate

    m = len(start) - 1
    positions, deformations = positions.copy(), deformations.copy()
    bends = np.zeros((m, 3, 6))
    for c in np.flatnonzero(quadratic[:m]):
        s, e = start[c], start[c + 1]
        mass = particle_masses(w[s:e])
        rot, q = rotations[c], q_rest[s:e]
        residual = (x[s:e] - centres[c] - q @ (deformations[c] @ rot).T) @ rot  # rows: Rᵀ·r_i
        mono = Aggregate.monomials(q)
        mono_mean = mass @ mono / mass.sum()
        u = mono - mono_mean
        bend = np.linalg.solve((u * mass[:, None]).T @ u, (u * mass[:, None]).T @ residual).T
        bends[c] = bend
        deformations[c] += rot @ bend @ _monomial_jacobian_at(local_centre[c]) @ rot.T
        positions[c] += rot @ bend @ (Aggregate.monomials(local_centre[c][None])[0] - mono_mean)
    return positions, deformations, bends
