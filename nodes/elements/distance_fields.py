"""Distance fields of an element on its grid — SPEC §1.4 (G eq. 5) and an exact alternative.

Two routes, both signed (positive inside, negative outside, in mm):

- ``binary_field``: G eq. 5 on the occupancy M. Inside, the distance to the nearest cell with
  M = 0; outside, minus the distance to the nearest cell with M = 1 (Euclidean by the ``edt``
  package, ~4× faster than scipy; Manhattan by scipy's chamfer transform). The zero level sits
  half-way between boundary cells: stair steps of up to half a voxel.
- ``exact_field``: the signed distance of mesh ∪ spheres, exact within a narrow band of cells
  (what marching cubes reads) and filled from the binary field farther away.
"""

from __future__ import annotations

import numpy as np

from ..kernel_arrays import kernel_array
from .voxel_grid import Grid, mesh_occupancy, sphere_field

METRICS = ("euclidean", "manhattan")


def _threads() -> int:
    """edt's threads: numba's thread count, the process's cores (nodegraph/runtime.py), at most 8."""
    import numba

    return max(1, min(numba.get_num_threads(), 8))


def cell_distance(mask: np.ndarray, metric: str) -> np.ndarray:
    """Distance in cells from every True cell to the nearest False cell (0 on False cells)."""
    if metric == "euclidean":
        import edt

        return edt.edt(np.ascontiguousarray(mask), black_border=False, parallel=_threads()).astype(np.float32)
    if metric == "manhattan":
        from scipy import ndimage

        return ndimage.distance_transform_cdt(mask, metric="taxicab").astype(np.float32)
    raise ValueError(f"metric must be one of {METRICS}, got {metric!r}")


def binary_field(inside: np.ndarray, voxel_size: float, metric: str) -> np.ndarray:
    """Signed eq. 5 field in mm: +h·(cells to nearest outside cell), −h·(cells to nearest inside cell)."""
    field = cell_distance(inside, metric)
    field -= cell_distance(~inside, metric)
    field *= np.float32(voxel_size)
    return field


def exact_field(
    grid: Grid,
    inside: np.ndarray,
    vertices: np.ndarray | None,
    faces: np.ndarray | None,
    centers: np.ndarray | None,
    radii: np.ndarray | None,
    band: int,
) -> np.ndarray:
    """Signed distance of mesh ∪ spheres (max of the signed distances), exact within ``band`` cells.

    Beyond the band, the binary Euclidean field shifted by half a cell (the surface lies about half
    a cell past the last occupied centre) fills in, clamped so it never re-enters the band.
    """
    from .grid_kernels import mesh_distance_band

    h = grid.voxel_size
    limit = band * h
    near = None
    if vertices is not None:
        unsigned = mesh_distance_band(grid.local(vertices), kernel_array(faces, np.int64), h, grid.shape, float(band))
        near = np.where(mesh_occupancy(grid, vertices, faces), unsigned, -unsigned)
    if centers is not None and len(centers):
        spheres = sphere_field(grid, centers, radii, float(band))  # already −band·h where no sphere reaches
        near = spheres if near is None else np.maximum(near, spheres, out=near)
    if near is None:
        raise ValueError("exact distance field needs a mesh and/or spheres")
    far_in = np.maximum(cell_distance(inside, "euclidean") - 0.5, band) * h
    far_out = -np.maximum(cell_distance(~inside, "euclidean") - 0.5, band) * h
    field = np.where(np.abs(near) < limit, near, np.where(inside, far_in, far_out))
    return field.astype(np.float32)
