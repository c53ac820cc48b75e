"""Numba kernels that rasterise a triangle mesh and spheres onto a regular grid — SPEC §1.3–1.4.

Hand-written because the library routes do not fit: trimesh's ``signed_distance`` needs rtree and
costs seconds per grain at 64³ (a Python-level query per point), and binvox (what G used) is an
external binary. Here a grain costs milliseconds (the inside test of the cell centres is the shared
column winding number, ``nodes.mesh_inside.inside_cells``):

- ``mesh_distance_band``: exact unsigned distance to the triangles within a narrow band of cells.
- ``sphere_union_band``: exact signed distance ``max_i (r_i − ‖x − c_i‖)`` of a union of spheres
  within a narrow band (positive inside).

Grid convention (``nodegraph.values.Volume``): cell (i, j, k) has its centre at origin + (i, j, k)·h.
Coordinates passed in are already relative to the grid origin, so far-away elements lose no precision.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..triangle_distance import dot3, point_triangle_offset


@njit(cache=True)
def mesh_distance_band(vertices, faces, h, shape, band):
    """Unsigned distance (in length units) from cell centres to the mesh, exact within ``band`` cells.

    Cells farther than ``band·h`` from every triangle keep the value ``band·h``.
    """
    ni, nj, nk = shape
    limit = band * h
    dist2 = np.full((ni, nj, nk), limit * limit)
    t = np.empty((3, 3))
    for f in range(faces.shape[0]):
        for v in range(3):  # element by element: a row assignment compiles numba's shape-mismatch message (≈ 1 s)
            for d in range(3):
                t[v, d] = vertices[faces[f, v], d]
        nx = (t[1, 1] - t[0, 1]) * (t[2, 2] - t[0, 2]) - (t[1, 2] - t[0, 2]) * (t[2, 1] - t[0, 1])
        ny = (t[1, 2] - t[0, 2]) * (t[2, 0] - t[0, 0]) - (t[1, 0] - t[0, 0]) * (t[2, 2] - t[0, 2])
        nz = (t[1, 0] - t[0, 0]) * (t[2, 1] - t[0, 1]) - (t[1, 1] - t[0, 1]) * (t[2, 0] - t[0, 0])
        nn = np.sqrt(nx * nx + ny * ny + nz * nz)
        if nn > 0.0:
            nx, ny, nz = nx / nn, ny / nn, nz / nn
        i0 = max(int(np.ceil((min(t[0, 0], t[1, 0], t[2, 0]) - limit) / h)), 0)
        i1 = min(int(np.floor((max(t[0, 0], t[1, 0], t[2, 0]) + limit) / h)), ni - 1)
        j0 = max(int(np.ceil((min(t[0, 1], t[1, 1], t[2, 1]) - limit) / h)), 0)
        j1 = min(int(np.floor((max(t[0, 1], t[1, 1], t[2, 1]) + limit) / h)), nj - 1)
        k0 = max(int(np.ceil((min(t[0, 2], t[1, 2], t[2, 2]) - limit) / h)), 0)
        k1 = min(int(np.floor((max(t[0, 2], t[1, 2], t[2, 2]) + limit) / h)), nk - 1)
        for i in range(i0, i1 + 1):
            px = i * h
            for j in range(j0, j1 + 1):
                py = j * h
                for k in range(k0, k1 + 1):
                    pz = k * h
                    if nn > 0.0:
                        plane = dot3(nx, ny, nz, px - t[0, 0], py - t[0, 1], pz - t[0, 2])
                        if plane * plane >= dist2[i, j, k]:
                            continue  # the triangle's plane is already farther than the best triangle
                    ex, ey, ez = point_triangle_offset(px, py, pz, t[0], t[1], t[2])
                    d2 = ex * ex + ey * ey + ez * ez
                    if d2 < dist2[i, j, k]:
                        dist2[i, j, k] = d2
    return np.sqrt(dist2)


@njit(cache=True)
def sphere_union_band(centers, radii, h, shape, band):
    """Signed distance max_i (r_i − ‖x − c_i‖) of a sphere union, exact where it exceeds −band·h.

    Cells farther than ``band·h`` outside every sphere keep −band·h; interior values are exact.
    """
    ni, nj, nk = shape
    limit = band * h
    out = np.full((ni, nj, nk), -limit)
    for s in range(radii.shape[0]):
        c = centers[s]
        r = radii[s]
        reach = r + limit
        i0 = max(int(np.ceil((c[0] - reach) / h)), 0)
        i1 = min(int(np.floor((c[0] + reach) / h)), ni - 1)
        j0 = max(int(np.ceil((c[1] - reach) / h)), 0)
        j1 = min(int(np.floor((c[1] + reach) / h)), nj - 1)
        k0 = max(int(np.ceil((c[2] - reach) / h)), 0)
        k1 = min(int(np.floor((c[2] + reach) / h)), nk - 1)
        for i in range(i0, i1 + 1):
            dx = i * h - c[0]
            for j in range(j0, j1 + 1):
                dy = j * h - c[1]
                for k in range(k0, k1 + 1):
                    dz = k * h - c[2]
                    d = r - np.sqrt(dx * dx + dy * dy + dz * dz)
                    if d > out[i, j, k]:
                        out[i, j, k] = d
    return out
