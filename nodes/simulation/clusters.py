"""Elements → particle clusters: a sphere packing of each element's volume — SPEC §3 (G: simulate
a low-resolution proxy, carry the high-resolution grain along).

Per distinct element mesh: a signed distance grid of the body (yolk faces, ``parts == 1``, excluded),
interior grid points at least half as deep as the deepest one, farthest-point sampling of
``count`` of them (deterministic, from the deepest), each a sphere of radius = its depth, so the
spheres touch the surface from inside.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ElementCluster:
    """Particles of one element mesh in its local frame, and its buoyant part if any."""

    centres: np.ndarray  # (k, 3) local frame
    radii: np.ndarray  # (k,)
    yolk_centre: np.ndarray | None = None  # local frame
    yolk_radius: float = 0.0
    membrane_centre: np.ndarray | None = None  # local frame
    membrane_radius: float = 0.0  # inner room of the body around its centre (for the yolk)


def _body_and_yolk(mesh):
    faces = np.asarray(mesh.faces)
    parts = mesh.parts
    if parts is None or not np.any(parts == 1):
        return faces, None
    return faces[parts != 1], faces[parts == 1]


def element_cluster(mesh, count: int, depth_fraction: float = 0.5, cells: int = 24) -> ElementCluster:
    """Sphere packing of ``mesh`` with ``count`` particles (fewer if the mesh is tiny)."""
    import trimesh

    from .collider import signed_distance_grid

    body_faces, yolk_faces = _body_and_yolk(mesh)
    vertices = np.asarray(mesh.vertices)
    body = trimesh.Trimesh(vertices, body_faces, process=True)
    if not body.is_watertight:
        body = body.convex_hull  # documented repair: an open element mesh is packed by its hull
    lo, hi = body.bounds
    pitch = float((hi - lo).max()) / cells
    phi, origin, pitch = signed_distance_grid([body], lo - pitch, hi + pitch, pitch)
    depth = -phi
    deepest = depth.max()
    if not deepest > 0:
        raise ValueError(f"element mesh {mesh.name or ''!r} has no interior at {pitch:.3g} resolution")
    idx = np.argwhere(depth >= depth_fraction * deepest)
    points = origin + idx * pitch
    depths = depth[tuple(idx.T)]
    chosen = [int(np.argmax(depths))]
    gap = np.linalg.norm(points - points[chosen[0]], axis=1)
    for _ in range(min(count, len(points)) - 1):
        nxt = int(np.argmax(gap))
        if gap[nxt] <= 0:
            break
        chosen.append(nxt)
        gap = np.minimum(gap, np.linalg.norm(points - points[nxt], axis=1))
    centres = points[chosen]
    radii = depths[chosen]
    if yolk_faces is None:
        return ElementCluster(centres, radii)
    yolk_vertices = vertices[np.unique(yolk_faces)]
    yolk_centre = yolk_vertices.mean(axis=0)
    yolk_radius = float(np.linalg.norm(yolk_vertices - yolk_centre, axis=1).mean())
    body = vertices[np.unique(body_faces)]
    body_centre = body.mean(axis=0)
    membrane = float(np.linalg.norm(body - body_centre, axis=1).min())
    return ElementCluster(centres, radii, yolk_centre, yolk_radius, body_centre, membrane)


def matrix_to_quat(rotations: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations → (n, 4) quaternions w-x-y-z (scipy orthonormalises slightly off input)."""
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_matrix(rotations).as_quat()
    return np.ascontiguousarray(xyzw[:, [3, 0, 1, 2]])
