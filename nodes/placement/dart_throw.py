"""Dart throwing over candidate points with flags — SPEC §2.2 (S §3.1.2).

Candidates are visited in a random order; a free one is placed and every candidate closer than
the minimum distance (2r: exclusion spheres of radius r do not overlap) is flagged. The result
is maximal over the candidates. A sorted cell list (``spatial_grid``, cell ≥ min distance) finds the
candidates to flag; hand-written in numba because the flagging loop is sequential by nature.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..spatial_grid import CellGrid, build_grid, column_run, neighbour_block


@njit(cache=True)
def _throw(points, order, min_distance, grid):
    """Placed candidate ids in placing order; ``grid`` (``spatial_grid``) sorts the candidates by cells ≥ the
    minimum distance. Which candidates a placed one flags does not depend on the order they are visited in, so
    neither does the result (nor on how coarse the grid is)."""
    n = points.shape[0]
    flagged = np.zeros(n, np.bool_)
    placed = np.empty(n, np.int64)
    count = 0
    d2 = min_distance * min_distance
    for step in range(n):
        i = order[step]
        if flagged[i]:
            continue
        placed[count] = i
        count += 1
        flagged[i] = True
        x0, x1, y0, y1, z0, z1 = neighbour_block(grid, points[i, 0], points[i, 1], points[i, 2])
        for gx in range(x0, x1):
            for gy in range(y0, y1):
                q0, q1 = column_run(grid, gx, gy, z0, z1)
                for q in range(q0, q1):
                    j = grid.order[q]
                    if not flagged[j]:
                        dx = points[j, 0] - points[i, 0]
                        dy = points[j, 1] - points[i, 1]
                        dz = points[j, 2] - points[i, 2]
                        if dx * dx + dy * dy + dz * dz < d2:
                            flagged[j] = True
    return placed[:count]


def dart_throw(points: np.ndarray, order: np.ndarray, min_distance: float) -> np.ndarray:
    """Indices of the placed candidates, in placing order (that order is P_num)."""
    if len(points) == 0:
        return np.zeros(0, np.int64)
    points = np.ascontiguousarray(points, np.float64)
    origin = points.min(axis=0) - 1e-9
    grid = CellGrid(*build_grid(points, origin, float(min_distance), 64.0 * len(points) + 4096))
    return _throw(points, np.asarray(order, np.int64), float(min_distance), grid)


def min_distance_ratio(points: np.ndarray, min_distance: float) -> float:
    """Smallest neighbour distance over the required minimum (≥ 1 for a valid Poisson-disk set)."""
    if len(points) < 2:
        return float("inf")
    from scipy.spatial import cKDTree

    distances, _ = cKDTree(points).query(points, k=2)
    return float(distances[:, 1].min() / min_distance)
