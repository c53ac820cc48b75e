"""Dense candidate points for Poisson-sphere placement — SPEC §2.1 (S §3.1.1) and G's volume fill (§3.2.2.1).

Surface: the shape is subdivided without smoothing until every edge ≤ the candidate spacing (S
adds face centroids and edge midpoints; trimesh's midpoint subdivision gives the same density on
triangles); its vertices, with vertex normals, are the candidates. Volume: a jittered cubic grid
of the same spacing, kept where the point lies inside the shape (the column winding number of
``nodes.mesh_inside``, shared with the voxeliser and the colliders).
"""

from __future__ import annotations

import numpy as np

from ..kernel_arrays import kernel_array

# Bytes held per candidate while sampling: position, normal, cell key, order, flag and sort scratch.
BYTES_PER_CANDIDATE = 96


def estimate_candidates(mode: str, area: float, volume: float, spacing: float) -> int:
    """Candidates the subdivision (surface) or grid (volume) will make, before making them."""
    if mode == "surface":
        # A triangulated surface with edges ≈ spacing/√2 … spacing has about 2.3·A/spacing² vertices.
        return int(4.0 * area / spacing**2) + 1
    return int(volume / spacing**3) + 1


def surface_candidates(vertices: np.ndarray, faces: np.ndarray, spacing: float, method: str, rng: np.random.Generator):
    """Candidate points on the shape with outward normals, about one per (spacing/2)² of area.

    ``subdivide`` (S): vertices of the shape subdivided until every edge ≤ ``spacing``.
    ``random``: area-weighted uniform samples at the same density, normals interpolated from the
    vertex normals; ~10× faster than subdividing and just as dense (the dart thrower does the rest).
    """
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=False)
    if method == "subdivide":
        sub_v, sub_f = trimesh.remesh.subdivide_to_size(vertices, faces, max_edge=spacing, max_iter=64)
        sub = trimesh.Trimesh(sub_v, sub_f, process=True)  # merges the duplicated edge midpoints
        return np.asarray(sub.vertices), np.asarray(sub.vertex_normals)
    count = estimate_candidates("surface", mesh.area, 0.0, spacing)
    weights = mesh.area_faces / mesh.area
    face = rng.choice(len(faces), size=count, p=weights)
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    bary = np.stack([1.0 - u - v, u, v], axis=1)
    corners = faces[face]
    points = np.einsum("nk,nkd->nd", bary, vertices[corners])
    normals = np.einsum("nk,nkd->nd", bary, np.asarray(mesh.vertex_normals)[corners])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return points, normals


def volume_candidates(vertices: np.ndarray, faces: np.ndarray, spacing: float, rng: np.random.Generator):
    """Points of a jittered cubic grid (jitter ±spacing/4) inside the closed shape, each with local up +z."""
    from ..mesh_inside import inside_columns

    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    # Small irrational shifts, different per axis, keep grid columns off the edges and diagonals of box-like
    # shapes (the inside test is exact there; the shifts keep candidates off the surface itself).
    shift = 1e-4 * np.array([np.pi, np.e, np.sqrt(2.0)])
    axes = [np.arange(lo[d] + (0.5 + shift[d]) * spacing, hi[d], spacing) for d in range(3)]
    if any(len(a) == 0 for a in axes):
        return np.zeros((0, 3)), np.zeros((0, 3))
    inside = inside_columns(kernel_array(vertices), kernel_array(faces, np.int64), axes[0], axes[1], axes[2])
    ix, iy, iz = np.nonzero(inside)
    points = np.stack([axes[0][ix], axes[1][iy], axes[2][iz]], axis=1)
    points += rng.uniform(-0.25 * spacing, 0.25 * spacing, points.shape)
    up = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    return points, up
