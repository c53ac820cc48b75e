"""Uniform cell grid over points and the search of the 27 cells around a point: the one neighbour search of the
contact lists (``simulation.spatial_hash``), the refine's neighbour lists (``placement.refine_kernels``), the
cut's contact graph (``placement.islands``) and dart throwing (``placement.dart_throw``).

Cell (ix, iy, iz) of a grid with ``dims`` cells per axis, corner ``lo`` and cell size ``cell`` has the key
(ix·dims[1] + iy)·dims[2] + iz (z fastest). The points are sorted by key; cell k holds the sorted positions
start[k]:start[k + 1], and ``order`` gives the point at each sorted position. Because z is fastest, the three
cells (gx, gy, iz − 1 … iz + 1) are one run of the sorted order, so the 27 cells around a point are 9 runs
(``column_run``), one per column (gx, gy) of the block (``neighbour_block``)::

    x0, x1, y0, y1, z0, z1 = neighbour_block(grid, x, y, z)
    for gx in range(x0, x1):
        for gy in range(y0, y1):
            q0, q1 = column_run(grid, gx, gy, z0, z1)
            for q in range(q0, q1):
                j = grid.order[q]  # a point in one of the 27 cells; the caller tests the distance

The two loops stay in the caller: written as one loop over the 9 columns (a helper giving column c's run), the
contact lists' scan took 12–17 % more CPU (50k particles, one thread).

The visiting order is part of the callers' results (the contact sweep is Gauss–Seidel in it, the refine sums
its overlaps in it): columns in key order (gx, then gy ascending), each run front to back, i.e. the points of
the 27 cells in the order of the sorted points. A point's partners within distance d lie in those cells when
``cell`` ≥ d. ``grid_shape`` doubles the cell while the grid would have more than ``max_cells`` cells (a
scattered or exploding scene), which only makes the search coarser, never wrong, but changes which cells are
visited and so the order of the partners found.

Hand-written in numba rather than scipy's cKDTree because the callers visit neighbours inside their own
kernels (flagging, skipping same-element pairs, listing pairs once), the contact lists are rebuilt every
substep, and a tree lists pairs in its own order (the refine's rows would change order, so its results in the
last bits) and would list every same-element pair of the cut (16 M on the bunny). A path that only needs the
pairs within a radius, once, uses cKDTree (``contact_flattening``'s neighbour lists,
``dart_throw.min_distance_ratio``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class CellGrid(NamedTuple):
    """Points sorted by cell (``build_grid``): cell k holds sorted positions start[k]:start[k + 1]."""

    start: np.ndarray  # (cells + 1,) int64
    order: np.ndarray  # (n,) int64: the point id at each sorted position
    lo: np.ndarray  # (3,) the grid's corner
    dims: np.ndarray  # (3,) int64 cells per axis, z fastest
    cell: float  # cell size


@njit(cache=True)
def grid_shape(lo, hi, cell, max_cells):
    """(dims, cell): cells of size ``cell`` from ``lo`` past ``hi`` per axis, the size doubled until there are
    at most ``max_cells`` of them (the product taken in float: no overflow for a scene that flew apart)."""
    dims = np.empty(3, np.int64)
    while True:
        for k in range(3):
            dims[k] = int((hi[k] - lo[k]) / cell) + 1
        if float(dims[0]) * float(dims[1]) * float(dims[2]) <= max_cells:
            return dims, cell
        cell *= 2.0


@njit(cache=True, inline="always")
def _cell(lo, dims, cell, x, y, z):
    """``cell_of`` on a grid's fields."""
    ix = min(int((x - lo[0]) / cell), dims[0] - 1)
    iy = min(int((y - lo[1]) / cell), dims[1] - 1)
    iz = min(int((z - lo[2]) / cell), dims[2] - 1)
    return ix, iy, iz


@njit(cache=True, inline="always")
def cell_of(grid, x, y, z):
    """(ix, iy, iz): the cell of point (x, y, z) ≥ ``grid.lo``, clamped to the grid (a point on its far face)."""
    return _cell(grid.lo, grid.dims, grid.cell, x, y, z)


@njit(cache=True, inline="always")
def neighbour_block(grid, x, y, z):
    """(x0, x1, y0, y1, z0, z1): the cells gx in [x0, x1), gy in [y0, y1), gz in [z0, z1) of the 3 × 3 × 3 block
    around the cell of point (x, y, z), clipped to the grid."""
    ix, iy, iz = cell_of(grid, x, y, z)
    nx, ny, nz = grid.dims[0], grid.dims[1], grid.dims[2]
    return max(ix - 1, 0), min(ix + 2, nx), max(iy - 1, 0), min(iy + 2, ny), max(iz - 1, 0), min(iz + 2, nz)


@njit(cache=True, inline="always")
def column_run(grid, gx, gy, z0, z1):
    """(q0, q1): the sorted positions of the cells (gx, gy, z0 … z1 − 1), one run (z is fastest)."""
    base = (gx * grid.dims[1] + gy) * grid.dims[2]
    return grid.start[base + z0], grid.start[base + z1]


@njit(cache=True)
def cell_keys(x, lo, dims, cell):
    """The key of each point's cell (``cell_of``)."""
    n = x.shape[0]
    keys = np.empty(n, np.int64)
    for i in range(n):
        ix, iy, iz = _cell(lo, dims, cell, x[i, 0], x[i, 1], x[i, 2])
        keys[i] = (ix * dims[1] + iy) * dims[2] + iz
    return keys


@njit(cache=True)
def cell_starts(keys, total):
    """start (total + 1,): cell k holds sorted positions start[k]:start[k + 1] once the points are sorted by key
    (by ``counting_sort`` or any other sort: the order within a cell is the sort's)."""
    start = np.zeros(total + 1, np.int64)
    for i in range(keys.shape[0]):
        start[keys[i] + 1] += 1
    for k in range(total):
        start[k + 1] += start[k]
    return start


@njit(cache=True)
def counting_sort(keys, total):
    """(start, order): the points sorted by key, stably (a cell's points in id order), by counting."""
    start = cell_starts(keys, total)
    fill = start[:-1].copy()
    order = np.empty(keys.shape[0], np.int64)
    for i in range(keys.shape[0]):
        order[fill[keys[i]]] = i
        fill[keys[i]] += 1
    return start, order


@njit(cache=True)
def build_grid(x, lo, cell, max_cells):
    """A ``CellGrid``'s fields (start, order, lo, dims, cell) over points ``x`` ≥ ``lo``: cells of at least
    ``cell`` (``grid_shape``), the points counting-sorted by cell. Returned as a tuple: a parallel kernel builds
    the named tuple itself (it finds the class at its call)."""
    hi = np.empty(3)
    for k in range(3):
        hi[k] = x[:, k].max()
    dims, cell = grid_shape(lo, hi, cell, max_cells)
    keys = cell_keys(x, lo, dims, cell)
    start, order = counting_sort(keys, dims[0] * dims[1] * dims[2])
    return start, order, lo, dims, cell
