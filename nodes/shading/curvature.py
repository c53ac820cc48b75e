"""Per-vertex mean curvature and normals of a triangle mesh — the κ of SPEC §4 (eq. 9).

libigl's cotangent Laplacian and Voronoi mass matrix give the mean-curvature normal
``H·n = −½ M⁻¹ L x`` (Meyer et al. 2003); the sign comes from the area-weighted vertex normal, so a
convex bump is positive (a sphere of radius r gives 1/r).
"""

from __future__ import annotations

import numpy as np

MIN_AREA = 1e-12  # mm² — Voronoi area floor for vertices only on degenerate faces (κ → 0 there, not inf)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (zero for isolated vertices)."""
    import igl

    v = np.ascontiguousarray(vertices, np.float64)
    f = np.ascontiguousarray(faces, np.int64)
    normals = igl.per_vertex_normals(v, f, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)
    return np.nan_to_num(normals)


def mean_curvature(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None = None) -> np.ndarray:
    """Signed discrete mean curvature per vertex (1/length units), libigl cotangent formula."""
    import igl

    v = np.ascontiguousarray(vertices, np.float64)
    f = np.ascontiguousarray(faces, np.int64)
    if len(f) == 0:
        return np.zeros(len(v))
    laplacian = igl.cotmatrix(v, f)
    mass = igl.massmatrix(v, f, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    hn = -0.5 * (laplacian @ v) / np.maximum(mass, MIN_AREA)[:, None]
    if normals is None:
        normals = vertex_normals(v, f)
    return np.nan_to_num(np.einsum("ij,ij->i", hn, normals))
