"""Grain skin: how lumpy an element's surface is, read from its exported mesh (issue 26, SPEC §1.6).

The skin score is the concave share of the surface's edge curvature: over all interior edges, the sum of
edge length × dihedral angle on the concave edges divided by the same sum on every edge. A convex surface
scores 0; porosity spheres bulging through the skin (SPEC §1.2) leave concave creases around each bump and
raise it (an ellipsoid with 4 % sinusoidal bumps scores ≈ 0.17; cooked rice is plump and smooth: ≤ 0.10).
"""

from __future__ import annotations

import numpy as np


def skin_score(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Σ_concave ℓ·θ / Σ_all ℓ·θ over the edges shared by two faces (θ = angle between their normals).

    An edge is concave when the far vertex of one face lies above the plane of the other (outward
    normals). A mesh with no bent edge (a flat sheet) scores 0. Refuses a non-manifold edge.
    """
    vertices = np.asarray(vertices, np.float64)
    faces = np.asarray(faces, np.int64)
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    normals = np.cross(b - a, c - a)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    # each face's three directed edges (v_i → v_{i+1}) with the vertex opposite them
    start = faces.ravel()
    end = np.roll(faces, -1, axis=1).ravel()
    opposite = np.roll(faces, -2, axis=1).ravel()
    owner = np.repeat(np.arange(len(faces)), 3)
    lo, hi = np.minimum(start, end), np.maximum(start, end)
    key = lo * len(vertices) + hi
    order = np.argsort(key, kind="stable")
    key = key[order]
    counts = np.bincount(np.unique(key, return_inverse=True)[1])
    if (counts > 2).any():
        raise ValueError(f"skin_score: {int((counts > 2).sum())} edges are shared by more than two faces")
    pair = np.flatnonzero(key[1:] == key[:-1])  # sorted: the two faces of an interior edge are adjacent
    first, second = order[pair], order[pair + 1]
    f1, f2 = owner[first], owner[second]
    length = np.linalg.norm(vertices[end[first]] - vertices[start[first]], axis=1)
    cosine = np.clip(np.einsum("ij,ij->i", normals[f1], normals[f2]), -1.0, 1.0)
    angle = np.arccos(cosine)
    rise = np.einsum("ij,ij->i", vertices[opposite[second]] - vertices[start[first]], normals[f1])
    weight = length * angle
    total = weight.sum()
    return float(weight[rise > 0.0].sum() / total) if total > 0.0 else 0.0
