"""Per-vertex mean curvature and normals of a triangle mesh — the κ of SPEC §4 (eq. 9).

The cotangent Laplacian and the mixed Voronoi mass (Meyer et al. 2003, libigl's ``cotmatrix`` and
``massmatrix(VORONOI)``) give the mean-curvature normal ``H·n = −½ M⁻¹ L x``; the sign comes from the
area-weighted vertex normal, so a convex bump is positive (a sphere of radius r gives 1/r). One numba pass over
the faces accumulates L x, M and the normals (libigl built a sparse L first: 1.2 s of the main job's shade-only
re-run, 0.64 M vertices, against ≈ 0.05 s here; ``tests/shading/test_cdrf.py`` checks both agree).
"""

from __future__ import annotations

import numpy as np
from numba import njit

MIN_AREA = 1e-12  # mm² — Voronoi area floor for vertices only on degenerate faces (κ → 0 there, not inf)


@njit(cache=True)
def _face_sums(vertices, faces):  # pragma: no cover - numba
    """Per vertex: Σ area-weighted face normals (×2), the cotangent Laplacian times x, the mixed Voronoi area.
    Scalar code (no per-face arrays); degenerate faces (zero area) add nothing."""
    n = vertices.shape[0]
    normal_sum = np.zeros((n, 3))
    laplacian_x = np.zeros((n, 3))
    mass = np.zeros(n)
    edge = np.empty((3, 3))  # edge k: from corner k+1 to corner k+2 (opposite corner k)
    squared = np.empty(3)  # |edge k|²
    cot = np.empty(3)  # cotangent of the angle at corner k
    for f in range(faces.shape[0]):
        for k in range(3):
            i, j = faces[f, (k + 1) % 3], faces[f, (k + 2) % 3]
            for c in range(3):
                edge[k, c] = vertices[j, c] - vertices[i, c]
            squared[k] = edge[k, 0] ** 2 + edge[k, 1] ** 2 + edge[k, 2] ** 2
        # 2·area·unit normal = e2 × (−e1): (p1 − p0) × (p2 − p0)
        nx = -(edge[2, 1] * edge[1, 2] - edge[2, 2] * edge[1, 1])
        ny = -(edge[2, 2] * edge[1, 0] - edge[2, 0] * edge[1, 2])
        nz = -(edge[2, 0] * edge[1, 1] - edge[2, 1] * edge[1, 0])
        double_area = np.sqrt(nx * nx + ny * ny + nz * nz)
        if double_area == 0.0:
            continue
        obtuse = -1
        for k in range(3):  # angle at corner k between edges k+2 (towards k+1, reversed) and k+1
            dot = -(
                edge[(k + 1) % 3, 0] * edge[(k + 2) % 3, 0]
                + edge[(k + 1) % 3, 1] * edge[(k + 2) % 3, 1]
                + edge[(k + 1) % 3, 2] * edge[(k + 2) % 3, 2]
            )
            cot[k] = dot / double_area
            if cot[k] < 0.0:
                obtuse = k
        area = 0.5 * double_area
        for k in range(3):
            o, i, j = faces[f, k], faces[f, (k + 1) % 3], faces[f, (k + 2) % 3]
            normal_sum[o, 0] += nx
            normal_sum[o, 1] += ny
            normal_sum[o, 2] += nz
            w = 0.5 * cot[k]  # L_ij += ½ cot of the angle opposite edge ij
            for c in range(3):
                laplacian_x[i, c] += w * edge[k, c]
                laplacian_x[j, c] -= w * edge[k, c]
            if obtuse >= 0:  # Meyer's mixed area: half the face to the obtuse corner, a quarter to the others
                mass[o] += area * (0.5 if k == obtuse else 0.25)
            else:  # Voronoi region: ⅛ Σ |e|² cot over the two edges at the corner
                mass[o] += 0.125 * (squared[(k + 1) % 3] * cot[(k + 1) % 3] + squared[(k + 2) % 3] * cot[(k + 2) % 3])
    return normal_sum, laplacian_x, mass


def _sums(vertices: np.ndarray, faces: np.ndarray):
    v = np.ascontiguousarray(vertices, np.float64)
    f = np.ascontiguousarray(faces, np.int64).reshape(-1, 3)
    return _face_sums(v, f)


def row_lengths(rows: np.ndarray) -> np.ndarray:
    """(n, 1) lengths of (n, 3) rows: ``np.linalg.norm(rows, axis=1, keepdims=True)`` to the bit (x² + y², then
    + z², in the rows' precision) without its copies and strided reduction (half the time; tests/export)."""
    squares = rows[:, 0] * rows[:, 0]
    squares += rows[:, 1] * rows[:, 1]
    squares += rows[:, 2] * rows[:, 2]
    return np.sqrt(squares)[:, None]


def _unit(rows: np.ndarray) -> np.ndarray:
    length = row_lengths(rows)
    return np.divide(rows, length, out=np.zeros_like(rows), where=length > 0)


def vertex_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (zero for isolated vertices)."""
    return _unit(_sums(vertices, faces)[0])


def normals_and_curvature(
    vertices: np.ndarray, faces: np.ndarray, sign_normals: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(area-weighted unit vertex normals, signed mean curvature per vertex) in one pass over the faces; the
    curvature's sign follows ``sign_normals`` (default: those vertex normals)."""
    normal_sum, laplacian_x, mass = _sums(vertices, faces)
    normals = _unit(normal_sum)
    hn = -0.5 * laplacian_x / np.maximum(mass, MIN_AREA)[:, None]
    side = normals if sign_normals is None else sign_normals
    return normals, np.nan_to_num(np.einsum("ij,ij->i", hn, side))


def mean_curvature(vertices: np.ndarray, faces: np.ndarray, normals: np.ndarray | None = None) -> np.ndarray:
    """Signed discrete mean curvature per vertex (1/length units), the cotangent formula; signed by ``normals``
    (default: the area-weighted vertex normals)."""
    return normals_and_curvature(vertices, faces, normals)[1]
