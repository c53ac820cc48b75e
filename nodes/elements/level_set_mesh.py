"""Expansion and level-set remeshing of a grain's field — SPEC §1.5–1.6 (G eq. 6, G §3.1.1).

Marching cubes (scikit-image, Lewiner) on the signed field, then optional Taubin smoothing
(trimesh; it barely shrinks the volume, unlike plain Laplacian) and optional quadric decimation to a
triangle budget (trimesh → fast-simplification). Every output is checked watertight and consistently
outward-oriented, and is moved to its volume centroid.
"""

from __future__ import annotations

import numpy as np


def expand_field(data: np.ndarray, origin: np.ndarray, voxel_size: float, expansion: float):
    """G eq. 6, [x, y, z] = P·[r, s, t]: scale the grain by P about its occupied-cell centroid.

    The grid is scaled (origin and voxel size) and the distances with it, so the result is still a
    distance field in mm and no resampling error is added. Returns (data, origin, voxel_size).
    """
    inside = np.argwhere(data > 0)
    centroid = origin + inside.mean(axis=0) * voxel_size
    scaled = np.multiply(data, np.float32(expansion), dtype=np.float32)
    return scaled, centroid + expansion * (origin - centroid), voxel_size * expansion


def field_surface(data: np.ndarray, origin: np.ndarray, voxel_size: float, level: float):
    """Marching-cubes surface {field = level} as (vertices, faces), outward, in mm.

    Refuses a level the field never crosses and a surface cut open by the grid edge.
    """
    from skimage import measure

    if not data.min() < level < data.max():
        raise ValueError(f"level {level:g} mm is outside the field's range [{data.min():g}, {data.max():g}] mm: "
                         "there is no surface to extract")
    faces_of_box = [data[0], data[-1], data[:, 0], data[:, -1], data[:, :, 0], data[:, :, -1]]
    if max(float(f.max()) for f in faces_of_box) >= level:
        raise ValueError(f"the surface at level {level:g} mm reaches the edge of the grid and would be cut open; "
                         "use a higher level or more padding when voxelising")
    # Values exactly at the level make marching cubes emit degenerate, non-manifold pieces.
    field = np.where(data == level, np.nextafter(np.float32(level), np.float32(np.inf)), data)
    vertices, faces, _, _ = measure.marching_cubes(field, level, spacing=(voxel_size,) * 3,
                                                   allow_degenerate=False)
    vertices = vertices.astype(np.float64)
    faces = faces.astype(np.int64)
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    if np.einsum("ij,ij->", a, np.cross(b - a, c - a)) < 0:
        faces = faces[:, ::-1].copy()  # marching cubes winds toward the lower values: make it outward
    return vertices + origin, faces


def finish_mesh(vertices: np.ndarray, faces: np.ndarray, smoothing: int, target_faces: int | None):
    """Smoothing and decimation, then checks: returns (vertices, faces) in place (not recentred).

    Refuses (ValueError) a result that is not watertight or not consistently oriented rather than
    hand on a broken element.
    """
    import trimesh

    mesh = trimesh.Trimesh(vertices, faces, process=True)
    if smoothing > 0:
        trimesh.smoothing.filter_taubin(mesh, lamb=0.5, nu=0.53, iterations=smoothing)
    if target_faces is not None and len(mesh.faces) > target_faces:
        mesh = mesh.simplify_quadric_decimation(face_count=target_faces)
        mesh.merge_vertices()
    if not mesh.is_watertight:
        raise ValueError(f"remeshed surface is not watertight ({len(mesh.faces)} faces); "
                         "raise the resolution or target_faces")
    if not mesh.is_winding_consistent:
        raise ValueError("remeshed surface is not consistently oriented")
    if mesh.volume < 0:
        mesh.invert()
    return np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)


def centred(vertices: np.ndarray, faces: np.ndarray):
    """The closed mesh moved to its volume centroid, with area-weighted vertex normals."""
    import trimesh

    from .grain_shapes import volume_centroid

    _, centroid = volume_centroid(vertices, faces)
    vertices = vertices - centroid
    return vertices, np.asarray(trimesh.Trimesh(vertices, faces, process=False).vertex_normals)
