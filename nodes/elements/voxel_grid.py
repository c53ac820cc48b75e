"""Grid sizing and occupancy of mesh ∪ spheres — SPEC §1.3 (G §3.1.1: the volume M).

Replaces G's external binvox: the mesh is voxelised by the exact column winding count shared with
placement and the colliders (``nodes.mesh_inside``) and the spheres by their exact signed distance
(``grid_kernels``), so a cell is occupied exactly when its centre lies inside the mesh or a sphere.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..kernel_arrays import kernel_array

#: Largest grid accepted: 2²⁶ cells (e.g. 406³) keeps the distance-field chain under ~2 GiB.
MAX_CELLS = 2**26
MIN_RESOLUTION = 8


@dataclass(frozen=True)
class Grid:
    """Cell (i, j, k) has its centre at ``origin + (i, j, k)·voxel_size`` (as ``values.Volume``)."""

    origin: np.ndarray
    voxel_size: float
    shape: tuple[int, int, int]

    def local(self, points: np.ndarray) -> np.ndarray:
        """Coordinates relative to the grid origin (kernels work there: no precision lost far away)."""
        return np.ascontiguousarray(np.asarray(points, np.float64) - self.origin)


def geometry_bounds(
    vertices: np.ndarray | None, centers: np.ndarray | None, radii: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """Axis-aligned bounds of the mesh vertices and the spheres (centre ± radius)."""
    lows, highs = [], []
    if vertices is not None and len(vertices):
        lows.append(vertices.min(axis=0))
        highs.append(vertices.max(axis=0))
    if centers is not None and len(centers):
        lows.append((centers - radii[:, None]).min(axis=0))
        highs.append((centers + radii[:, None]).max(axis=0))
    if not lows:
        raise ValueError("nothing to voxelise: give a mesh, spheres, or both")
    return np.min(lows, axis=0), np.max(highs, axis=0)


def grid_for(lo: np.ndarray, hi: np.ndarray, resolution: int | None, voxel_size: float | None, padding: int) -> Grid:
    """A grid around [lo, hi] with ``padding`` empty cells each side.

    ``resolution`` = cells along the longest side, padding included; ``voxel_size`` (mm), when
    given, wins. Refuses grids under 8 cells, a degenerate extent, or over ``MAX_CELLS`` cells.
    """
    extent = hi - lo
    longest = float(extent.max())
    if not np.isfinite(extent).all() or longest <= 0.0:
        raise ValueError(f"the geometry has no extent (bounds {lo} … {hi}); nothing to voxelise")
    if voxel_size is None:
        if resolution is None or resolution < MIN_RESOLUTION or resolution < 2 * padding + 4:
            raise ValueError(
                f"resolution {resolution} is too small: need at least "
                f"{max(MIN_RESOLUTION, 2 * padding + 4)} cells along the longest side"
            )
        voxel_size = longest / (resolution - 1 - 2 * padding)
    elif not voxel_size > 0.0:
        raise ValueError(f"voxel_size must be > 0 mm, got {voxel_size}")
    counts = [int(math.ceil(e / voxel_size - 1e-9)) + 1 + 2 * padding for e in extent]
    cells = counts[0] * counts[1] * counts[2]
    if max(counts) < MIN_RESOLUTION:
        raise ValueError(
            f"voxel_size {voxel_size:g} mm gives only {max(counts)} cells along the longest "
            f"side; need at least {MIN_RESOLUTION}"
        )
    if cells > MAX_CELLS:
        raise ValueError(
            f"grid of {counts[0]}×{counts[1]}×{counts[2]} = {cells:,} cells exceeds the limit of "
            f"{MAX_CELLS:,} (about 2 GiB of working memory); lower resolution or raise voxel_size"
        )
    centre = (lo + hi) / 2.0
    origin = centre - (np.array(counts) - 1) / 2.0 * voxel_size
    return Grid(origin, float(voxel_size), (counts[0], counts[1], counts[2]))


def check_spheres(centers: np.ndarray, radii: np.ndarray) -> None:
    """Refuse spheres with non-finite centres or radii that are not positive."""
    if not np.isfinite(centers).all() or not np.isfinite(radii).all():
        raise ValueError("spheres: NaN or infinite centre or radius")
    bad = np.flatnonzero(radii <= 0.0)
    if len(bad):
        raise ValueError(
            f"spheres: {len(bad)} radii are ≤ 0 (first: sphere {bad[0]}, r = {radii[bad[0]]}); "
            "every sphere needs a positive radius"
        )


def element_geometry(mesh, spheres):
    """(vertices, faces, centers, radii) of an optional mesh and sphere set, None where absent or empty.

    The spheres are checked (finite, positive radii) before any grid work.
    """
    vertices = None if mesh is None else mesh.vertices
    faces = None if mesh is None else mesh.faces
    if spheres is None or not len(spheres):
        return vertices, faces, None, None
    check_spheres(spheres.centers, spheres.radii)
    return vertices, faces, spheres.centers, spheres.radii


def mesh_occupancy(grid: Grid, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Cells whose centre lies inside the closed mesh (column winding number > 0, ``nodes.mesh_inside``)."""
    from ..mesh_inside import inside_cells

    return inside_cells(grid.local(vertices), kernel_array(faces, np.int64), grid.voxel_size, grid.shape)


def sphere_field(grid: Grid, centers: np.ndarray, radii: np.ndarray, band: float) -> np.ndarray:
    """Signed distance of the sphere union (positive inside), exact above −band cells."""
    from .grid_kernels import sphere_union_band

    return sphere_union_band(grid.local(centers), kernel_array(radii), grid.voxel_size, grid.shape, float(band))


def occupancy(
    grid: Grid,
    vertices: np.ndarray | None,
    faces: np.ndarray | None,
    centers: np.ndarray | None,
    radii: np.ndarray | None,
) -> np.ndarray:
    """The volume M of eq. 5: cells inside the mesh or any sphere; refuses empty or split results."""
    inside = np.zeros(grid.shape, dtype=bool)
    if vertices is not None:
        inside |= mesh_occupancy(grid, vertices, faces)
    if centers is not None and len(centers):
        inside |= sphere_field(grid, centers, radii, 1.0) > 0.0
    check_single_piece(inside, grid.voxel_size)
    return inside


def check_single_piece(inside: np.ndarray, voxel_size: float) -> None:
    """An element is one solid: refuse an empty volume or one in separate pieces, saying which."""
    from scipy import ndimage

    if not inside.any():
        raise ValueError(
            f"the volume is empty: no cell centre lies inside the mesh or a sphere at voxel size "
            f"{voxel_size:g} mm; the geometry is smaller than a cell, raise the resolution"
        )
    labels, count = ndimage.label(inside)
    if count > 1:
        sizes = np.sort(np.bincount(labels.ravel())[1:])[::-1]
        raise ValueError(
            f"the volume falls into {count} separate pieces (cells per piece: {sizes[:5].tolist()}); "
            "spheres that do not touch the mesh or each other make loose fragments — keep sphere "
            "centres on or inside the base mesh"
        )
