"""Per-element transform and deformation from the particle fit — SPEC §5 (A = A_pq·A_qq).

The element's high-resolution mesh follows its cluster (G: carry the high-res grain on the
low-res simulation): v_world = D·R·v_local + t, with R the cluster rotation and D = R·S·Rᵀ the
symmetric stretch of the least-squares fit, its principal stretches clamped to [0.5, 2] and left
at 1 along axes a collinear/planar cluster cannot observe.
"""

import numpy as np


def element_transforms(x, w, start, q_rest, rotations, centres, aqq_pinv, null_proj, local_centre):
    """(positions (m, 3), rotations (m, 3, 3), deformations (m, 3, 3)) of every element."""
    m = len(start) - 1
    deformations = np.tile(np.eye(3), (m, 1, 1))
    for c in range(m):
        s, e = start[c], start[c + 1]
        if e - s < 2:
            continue
        mass = np.where(w[s:e] > 0, 1.0 / np.maximum(w[s:e], 1e-300), 1e12)
        apq = ((x[s:e] - centres[c]) * mass[:, None]).T @ q_rest[s:e]
        stretch = rotations[c].T @ (apq @ aqq_pinv[c]) + null_proj[c]
        stretch = 0.5 * (stretch + stretch.T)
        vals, vecs = np.linalg.eigh(stretch)
        vals = np.clip(vals, 0.5, 2.0)
        deformations[c] = rotations[c] @ (vecs * vals) @ vecs.T @ rotations[c].T
    positions = centres - np.einsum("cij,cjk,ck->ci", deformations, rotations, local_centre)
    return positions, rotations, deformations
