"""Per-element properties of a library, for placement and simulation — SPEC §2.2, §2.6, §3."""

from __future__ import annotations

import numpy as np

from ..kernel_arrays import kernel_array


def element_props(meshes: list) -> dict[str, np.ndarray]:
    """expansion, volume, circumradius, inradius, length, width, thickness per mesh (mm, mm³).

    Refuses a mesh that is open, inconsistently oriented or inside out: every consumer needs solids.
    ``inradius`` comes from the mesh when it carries one (GrainMesh), else from a point sample of
    the exact distance from the centroid to the surface (a lower bound).
    """
    import trimesh

    rows = []
    for i, mesh in enumerate(meshes):
        tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=True)
        if not tm.is_watertight or not tm.is_winding_consistent:
            raise ValueError(f"mesh {i} ({mesh.name or 'unnamed'}) is not a closed, consistently oriented surface")
        if tm.volume <= 0:
            raise ValueError(f"mesh {i} ({mesh.name or 'unnamed'}) is inside out or has no volume")
        centre = tm.center_mass
        extent = np.ptp(tm.vertices, axis=0)
        inradius = float(getattr(mesh, "inradius", 0.0))
        if inradius <= 0.0:
            inradius = surface_distance(centre, np.asarray(tm.vertices), np.asarray(tm.faces, np.int64))
        rows.append(
            (
                float(getattr(mesh, "expansion", 1.0)),
                float(tm.volume),
                float(np.linalg.norm(tm.vertices - centre, axis=1).max()),
                inradius,
                *extent,
            )
        )
    table = np.array(rows)
    names = ("expansion", "volume", "circumradius", "inradius", "length", "width", "thickness")
    # Keys in sorted order, the order a library read back from the cache has (the codec stores dicts sorted).
    return {name: np.ascontiguousarray(table[:, names.index(name)]) for name in sorted(names)}


def surface_distance(point: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> float:
    """Exact distance from one point to a triangle mesh (the band kernel on a one-cell grid)."""
    from .grid_kernels import mesh_distance_band

    reach = 2.0 * float(np.ptp(vertices, axis=0).max()) + float(np.abs(vertices - point).max()) + 1.0
    local = np.ascontiguousarray(vertices - point)
    return float(mesh_distance_band(local, kernel_array(faces, np.int64), reach, (1, 1, 1), 1.0)[0, 0, 0])
