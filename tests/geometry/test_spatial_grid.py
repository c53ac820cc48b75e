"""``nodes.spatial_grid``: the 27-cell search finds every pair within a cell size, visits each candidate once and in
the sorted order (what the contact sweep's Gauss–Seidel order and the refine's sums follow), on fine and grown
grids; dart throwing does not depend on how coarse the grid is."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from scipy.spatial import cKDTree

from nodes.placement.dart_throw import _throw
from nodes.spatial_grid import CellGrid, build_grid, column_run, neighbour_block


@njit(cache=True)
def _visits(x, grid):
    """For each point, the sorted positions of the 27 cells around it, in visiting order (CSR)."""
    n = x.shape[0]
    start = np.zeros(n + 1, np.int64)
    out = np.empty(n * n, np.int64)  # each candidate at most once a point
    at = 0
    for i in range(n):
        x0, x1, y0, y1, z0, z1 = neighbour_block(grid, x[i, 0], x[i, 1], x[i, 2])
        for gx in range(x0, x1):
            for gy in range(y0, y1):
                q0, q1 = column_run(grid, gx, gy, z0, z1)
                for q in range(q0, q1):
                    out[at] = q
                    at += 1
        start[i + 1] = at
    return start, out[:at]


@pytest.mark.parametrize("max_cells", [1e9, 64.0])  # 64: the grid grows its cells several times
def test_the_27_cells_hold_every_pair_within_a_cell_once_in_sorted_order(max_cells):
    rng = np.random.default_rng(3)
    x = rng.random((300, 3))
    x[:100] = np.round(x[:100], 1)  # points on cell faces and equal points
    cell = 0.08
    grid = CellGrid(*build_grid(x, x.min(axis=0), cell, max_cells))
    assert grid.cell >= cell and np.prod(grid.dims) <= max_cells
    assert sorted(grid.order) == list(range(len(x)))
    start, visited = _visits(x, grid)
    near = cKDTree(x).query_ball_point(x, cell)
    for i in range(len(x)):
        row = visited[start[i] : start[i + 1]]
        assert np.all(np.diff(row) > 0)  # each candidate once, in the sorted order
        assert set(near[i]) <= set(grid.order[row])


def test_dart_throwing_does_not_depend_on_the_grid():
    """A placed candidate flags every candidate within the distance whatever order it visits them in."""
    rng = np.random.default_rng(5)
    points = rng.random((2000, 3))
    order = rng.permutation(len(points))
    lo = points.min(axis=0) - 1e-9
    placed = [
        _throw(points, order, 0.05, CellGrid(*build_grid(points, lo, cell, 1e9))) for cell in (0.05, 0.11, 0.4, 2.0)
    ]
    assert all(np.array_equal(placed[0], p) for p in placed[1:])
    assert cKDTree(points[placed[0]]).query(points[placed[0]], k=2)[0][:, 1].min() >= 0.05
