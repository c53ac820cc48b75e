"""Grain skin: how lumpy an element's surface is, read from its exported mesh (issue 26, SPEC §1.6).

The skin score is the concave share of the surface's edge curvature: over all interior edges, the sum of
edge length × dihedral angle on the concave edges divided by the same sum on every edge. A convex surface
scores 0; porosity spheres bulging through the skin (SPEC §1.2) leave concave creases around each bump and
raise it (an ellipsoid with 4 % sinusoidal bumps scores ≈ 0.17; cooked rice is plump and smooth: ≤ 0.10).
"""

from __future__ import annotations

import numpy as np


def skin_score(vertices: np.ndarray, faces: np.ndarray, edges: np.ndarray | None = None) -> float:
    """Σ_concave ℓ·θ / Σ_all ℓ·θ over the edges shared by two faces (θ = angle between their normals).

    An edge is concave when the far vertex of one face lies above the plane of the other (outward
    normals). A mesh with no bent edge (a flat sheet) scores 0. Refuses a non-manifold edge.
    ``edges``: ``interior_edges(faces, len(vertices))``, the same for every mesh with these faces (computed when
    not given).
    """
    vertices = np.asarray(vertices, np.float64)
    faces = np.asarray(faces, np.int64)
    f1, f2, start, end, opposite = interior_edges(faces, len(vertices)) if edges is None else edges
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    normals = np.cross(b - a, c - a)
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
    length = np.linalg.norm(vertices[end] - vertices[start], axis=1)
    cosine = np.clip(np.einsum("ij,ij->i", normals[f1], normals[f2]), -1.0, 1.0)
    angle = np.arccos(cosine)
    rise = np.einsum("ij,ij->i", vertices[opposite] - vertices[start], normals[f1])
    weight = length * angle
    total = weight.sum()
    return float(weight[rise > 0.0].sum() / total) if total > 0.0 else 0.0


def interior_edges(faces: np.ndarray, vertex_count: int) -> np.ndarray:
    """The edges shared by two faces: a (5, edges) array of each one's first face, second face, start and end
    vertex, and the second face's vertex opposite it — the mesh's topology alone, which ``measure`` computes once
    per library mesh. Refuses an edge shared by more than two faces."""
    faces = np.asarray(faces, np.int64)
    # each face's three directed edges (v_i → v_{i+1}) with the vertex opposite them
    start = faces.ravel()
    end = np.roll(faces, -1, axis=1).ravel()
    opposite = np.roll(faces, -2, axis=1).ravel()
    owner = np.repeat(np.arange(len(faces)), 3)
    lo, hi = np.minimum(start, end), np.maximum(start, end)
    key = lo * vertex_count + hi
    order = np.argsort(key, kind="stable")
    key = key[order]
    counts = np.bincount(np.unique(key, return_inverse=True)[1])
    if (counts > 2).any():
        raise ValueError(f"skin_score: {int((counts > 2).sum())} edges are shared by more than two faces")
    pair = np.flatnonzero(key[1:] == key[:-1])  # sorted: the two faces of an interior edge are adjacent
    first, second = order[pair], order[pair + 1]
    return np.stack([owner[first], owner[second], start[first], end[first], opposite[second]])
