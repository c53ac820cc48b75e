"""Medial spheres of an element and the implicit function they define — SPEC §2.5 (S §3.2.2, G eq. 2).

S took the skeleton from the power crust (Voronoi poles). Here: inner Voronoi poles of surface
samples (scipy/qhull) are the candidate spheres; a greedy set cover keeps the few that touch the
surface everywhere within a tolerance, so the refine cost (linear in the sphere count) stays low.
Radii of the kept spheres are the exact distances to the mesh, so every sphere lies inside.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..kernel_arrays import kernel_array
from ..triangle_distance import point_triangle_offset


@njit(cache=True)
def distance_to_surface(points, vertices, faces):
    """Unsigned distance from each point to the triangle mesh (brute force: used on few points)."""
    out = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        best = np.inf
        for f in range(faces.shape[0]):
            ex, ey, ez = point_triangle_offset(
                points[i, 0],
                points[i, 1],
                points[i, 2],
                vertices[faces[f, 0]],
                vertices[faces[f, 1]],
                vertices[faces[f, 2]],
            )
            best = min(best, ex * ex + ey * ey + ez * ez)
        out[i] = np.sqrt(best)
    return out


def surface_samples(vertices: np.ndarray, faces: np.ndarray, count: int, spacing: float = 0.0):
    """Deterministic surface samples with normals: vertices and face centroids, thinned by stride; with
    ``spacing`` > 0 (element lengths) of the mesh subdivided until no edge is longer (a thin element's poles need
    samples closer than its thickness)."""
    import trimesh

    if spacing > 0.0:
        vertices, faces = trimesh.remesh.subdivide_to_size(vertices, faces, max_edge=spacing * element_length(vertices))
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    points = np.vstack([mesh.vertices, mesh.triangles_center])
    normals = np.vstack([mesh.vertex_normals, mesh.face_normals])
    stride = max(1, len(points) // count)
    return points[::stride], normals[::stride]


def inner_poles(points: np.ndarray, normals: np.ndarray):
    """Per sample, the farthest Voronoi vertex of its cell on the inner side (−normal): centre and radius."""
    from scipy.spatial import QhullError, Voronoi

    if len(points) < 5 or np.linalg.matrix_rank(points - points.mean(axis=0), tol=1e-9) < 3:
        raise ValueError("element mesh has no interior (all vertices on a plane or too few)")
    try:
        vor = Voronoi(points)
    except QhullError as exc:
        raise ValueError(
            f"element mesh has no interior (Voronoi of its surface failed: {str(exc).splitlines()[0]})"
        ) from None
    # every (sample, Voronoi vertex of its cell) pair at once; per sample the first deepest inward vertex
    regions = [vor.regions[k] for k in vor.point_region]
    lengths = np.fromiter((len(r) for r in regions), np.int64, len(regions))
    owner = np.repeat(np.arange(len(points)), lengths)
    vertex = np.fromiter((v for r in regions for v in r), np.int64, int(lengths.sum()))
    owner, vertex = owner[vertex >= 0], vertex[vertex >= 0]  # −1: the vertex at infinity
    offsets = vor.vertices[vertex] - points[owner]
    inward = np.einsum("ij,ij->i", offsets, -normals[owner])
    depth = np.where(inward > 0, np.linalg.norm(offsets, axis=1), -1.0)
    order = np.lexsort((-depth, owner))  # by sample, deepest first, ties in the cell's own order (stable)
    first = order[np.r_[True, owner[order][1:] != owner[order][:-1]]] if len(order) else order
    centers = np.full((len(points), 3), np.nan)
    best = first[depth[first] > 0]
    centers[owner[best]] = vor.vertices[vertex[best]]
    ok = np.isfinite(centers[:, 0])
    radii = np.linalg.norm(centers[ok] - points[ok], axis=1)
    return centers[ok], radii


def element_length(vertices: np.ndarray) -> float:
    """The element's length: its longest bounding-box extent."""
    return float(np.ptp(vertices, axis=0).max())


def medial_spheres(
    vertices: np.ndarray,
    faces: np.ndarray,
    tolerance: float,
    max_spheres: int,
    samples: int = 2000,
    spacing: float = 0.0,
):
    """Spheres (centres, radii) whose union matches the mesh within ``tolerance``·length (surface samples at most
    ``spacing`` element lengths apart where > 0, ``surface_samples``).

    Raises ValueError for an element without interior (flat or open): no inner pole survives.
    """
    from ..mesh_inside import inside_points

    vertices, faces = kernel_array(vertices), kernel_array(faces, np.int64)
    length = element_length(vertices)
    points, normals = surface_samples(vertices, faces, samples, spacing)
    centers, radii = inner_poles(points, normals)
    keep = inside_points(vertices, faces, centers) & (radii > 1e-6 * length)
    centers, radii = centers[keep], radii[keep]
    if len(centers) == 0:
        raise ValueError("element mesh has no interior: no medial sphere fits inside (flat or open mesh)")
    chosen = _greedy_cover(points, centers, radii, tolerance * length, max_spheres)
    centers = centers[chosen]
    radii = distance_to_surface(centers, vertices, faces)
    return centers, radii


def _greedy_cover(points, centers, radii, epsilon, max_spheres):
    """Set cover: repeatedly keep the sphere touching (within epsilon) most still-uncovered samples
    (``_cover``; the first such sphere on ties)."""
    reach = np.ascontiguousarray(radii + epsilon, np.float64)
    return _cover(kernel_array(points), kernel_array(centers), reach, max_spheres)


@njit(cache=True)
def _cover(points, centers, reach, max_spheres):
    """``_greedy_cover``'s loop: a sample is touched by a sphere when their distance (√ of x² + y² + z², the
    floats ``np.linalg.norm`` gives) is at most the sphere's reach; each sphere's gain is the count of uncovered
    samples it touches, lowered as samples get covered. Compiled: the array version copied the touch matrix's
    columns at every step (0.4 s of a 1,800-face grain)."""
    n_points, n_centers = points.shape[0], centers.shape[0]
    touched_by = np.zeros((n_points, n_centers), np.bool_)  # per sample: the spheres touching it
    gain = np.zeros(n_centers, np.int64)
    for p in range(n_points):
        for c in range(n_centers):
            dx = centers[c, 0] - points[p, 0]
            dy = centers[c, 1] - points[p, 1]
            dz = centers[c, 2] - points[p, 2]
            if np.sqrt(dx * dx + dy * dy + dz * dz) <= reach[c]:
                touched_by[p, c] = True
                gain[c] += 1
    covered = np.zeros(n_points, np.bool_)
    chosen = np.empty(max(max_spheres, 0), np.int64)
    count = 0
    while count < max_spheres:
        best = 0
        for c in range(1, n_centers):
            if gain[c] > gain[best]:
                best = c
        if gain[best] == 0:
            break
        chosen[count] = best
        count += 1
        for p in range(n_points):
            if touched_by[p, best] and not covered[p]:
                covered[p] = True
                for c in range(n_centers):
                    if touched_by[p, c]:
                        gain[c] -= 1
    return chosen[:count]


def largest_inscribed_radius(vertices: np.ndarray, faces: np.ndarray, samples: int = 2000) -> float:
    """Radius of the largest sphere inside the element (S: r is half of it) — best of the inner poles."""
    from ..mesh_inside import inside_points

    vertices = np.ascontiguousarray(vertices, np.float64)
    faces = np.ascontiguousarray(faces, np.int64)
    points, normals = surface_samples(vertices, faces, samples)
    centers, radii = inner_poles(points, normals)
    centers = centers[inside_points(vertices, faces, centers)]
    if len(centers) == 0:
        raise ValueError("element mesh has no interior: no sphere fits inside (flat or open mesh)")
    top = np.argsort(np.linalg.norm(centers - centers.mean(axis=0), axis=1))[:50]  # deepest poles sit central
    return float(distance_to_surface(centers[top], vertices, faces).max())


def union_fit(
    vertices: np.ndarray, faces: np.ndarray, centers: np.ndarray, radii: np.ndarray, grid: int = 24
) -> dict[str, float]:
    """How well the union of spheres matches the mesh, in element lengths and volume shares.

    ``gap_mean``/``gap_max``: distance from surface samples to the union's surface; ``volume``:
    share of the element's interior grid points inside some sphere.
    """
    from ..mesh_inside import inside_columns

    length = element_length(vertices)
    points, _ = surface_samples(vertices, faces, 4000)
    gap = (np.linalg.norm(points[:, None, :] - centers[None, :, :], axis=2) - radii).min(axis=1)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    axes = [np.linspace(lo[d], hi[d], grid + 2)[1:-1] for d in range(3)]
    inside = inside_columns(kernel_array(vertices), kernel_array(faces, np.int64), *axes)
    ix, iy, iz = np.nonzero(inside)
    interior = np.stack([axes[0][ix], axes[1][iy], axes[2][iz]], axis=1)
    covered = (np.linalg.norm(interior[:, None, :] - centers[None, :, :], axis=2) <= radii).any(axis=1)
    return {
        "gap_mean": float(np.abs(gap).mean() / length),
        "gap_max": float(np.abs(gap).max() / length),
        "volume": float(covered.mean()) if len(covered) else 0.0,
        "spheres": float(len(radii)),
    }
