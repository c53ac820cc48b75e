"""Elements → particle clusters: a sphere packing of each element's volume — SPEC §3 (G: simulate
a low-resolution proxy, carry the high-resolution grain along).

Per distinct element mesh: a signed distance grid φ of the body (yolk faces, ``parts == 1``, excluded);
every sphere is centred on an interior grid point with radius = its depth −φ, so it touches the surface
from inside. Half the count is medial-style (SPEC §2.5's medial spheres, S §3.2.2): the deepest point
first, then each time the largest sphere touching the shell vertex farthest outside the spheres so far,
so the union reaches the tips and edges (the former packing used only points at least half as deep as
the deepest: its spheres covered the core, and meshes settled ≈ 15 % of a length into each other). The
other half spreads through that core (farthest-point), so the shape-matching fit keeps a cluster spread
in three directions (the quadratic goal needs ≥ 10 non-collinear particles; a round grain's medial
spheres all lie on its axis).
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


def element_cluster(mesh, count: int, cells: int = 24) -> ElementCluster:
    """Sphere packing of ``mesh`` with ``count`` particles (fewer only if the mesh is tiny): up to half
    reaching the surface (until every shell vertex is within a quarter grid cell of a sphere), the rest
    spread through the core."""
    import trimesh

    from .collider import signed_distance_grid

    body_faces, yolk_faces = _body_and_yolk(mesh)
    vertices = np.asarray(mesh.vertices)
    body = trimesh.Trimesh(vertices, body_faces, process=True)
    if not body.is_watertight:
        body = body.convex_hull  # documented repair: an open element mesh is packed by its hull
    lo, hi = body.bounds
    pitch = float((hi - lo).max()) / cells
    phi, origin, pitch = signed_distance_grid([body], lo - 2 * pitch, hi + 2 * pitch, pitch)
    depth = -phi
    if not depth.max() > 0:
        raise ValueError(f"element mesh {mesh.name or ''!r} has no interior at {pitch:.3g} resolution")
    idx = np.argwhere(depth > 0)
    points = origin + idx * pitch
    depths = depth[tuple(idx.T)]
    shell = np.asarray(body.vertices, np.float64)
    chosen = [int(np.argmax(depths))]
    outside = np.linalg.norm(shell - points[chosen[0]], axis=1) - depths[chosen[0]]  # gap to the union
    while len(chosen) < min((count + 1) // 2, len(points)):
        v = int(np.argmax(outside))
        if outside[v] <= 0.25 * pitch:
            break
        reach = np.linalg.norm(points - shell[v], axis=1) - depths  # ≈ 0 for spheres touching vertex v
        near = np.flatnonzero(reach <= max(reach.min(), 0.0) + 0.5 * pitch)
        best = int(near[np.argmax(depths[near])])
        if best in chosen:  # the sphere reaching v is kept already: v is as covered as the grid allows
            outside[v] = 0.0
            continue
        chosen.append(best)
        outside = np.minimum(outside, np.linalg.norm(shell - points[best], axis=1) - depths[best])
    # the rest of ``count`` spread through the core (points at least half as deep as the deepest, farthest
    # from those kept): the shape-matching fit needs a cluster spread in three directions
    core = np.flatnonzero(depths >= 0.5 * depths.max())
    spread = np.min(np.linalg.norm(points[core, None, :] - points[chosen][None, :, :], axis=2), axis=1)
    while len(chosen) < min(count, len(points)) and spread.max() > 0:
        best = int(np.argmax(spread))
        chosen.append(int(core[best]))
        spread = np.minimum(spread, np.linalg.norm(points[core] - points[core[best]], axis=1))
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
