"""Local uvw frames and random rotations keyed by P_num — SPEC §2.3 (G §3.2.2.2)."""

from __future__ import annotations

import numpy as np


def local_frames(normals: np.ndarray, directions: np.ndarray | None) -> np.ndarray:
    """Columns (u, v, w): w = unit normal, u = ``directions`` projected on the tangent plane (any tangent if
    none/parallel)."""
    w = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    fallback = np.eye(3)[np.argmin(np.abs(w), axis=1)]  # the axis least aligned with w
    guide = fallback if directions is None else np.asarray(directions, float)
    u = guide - (guide * w).sum(axis=1, keepdims=True) * w
    length = np.linalg.norm(u, axis=1)
    degenerate = length < 1e-9
    u[degenerate] = (
        fallback[degenerate] - (fallback[degenerate] * w[degenerate]).sum(axis=1, keepdims=True) * w[degenerate]
    )
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(w, u)
    return np.stack([u, v, w], axis=2)


def random_rotations(rng: np.random.Generator, p_num: np.ndarray, max_angles: np.ndarray) -> np.ndarray:
    """Rotation per element from angles uniform in ±max_angles about (u, v, w), drawn per P_num.

    Drawing one row per P_num (not per array index) keeps an element's rotation when others are
    culled or re-ordered.
    """
    from scipy.spatial.transform import Rotation

    if len(p_num) == 0:
        return np.zeros((0, 3, 3))
    draws = rng.uniform(-1.0, 1.0, (int(p_num.max()) + 1, 3))[p_num] * max_angles
    return Rotation.from_euler("ZYX", draws[:, ::-1]).as_matrix()
