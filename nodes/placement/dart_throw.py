"""Dart throwing over candidate points with flags — SPEC §2.2 (S §3.1.2).

Candidates are visited in a random order; a free one is placed and every candidate closer than
the minimum distance (2r: exclusion spheres of radius r do not overlap) is flagged. The result
is maximal over the candidates. A sorted cell list (cell = min distance) finds the candidates to
flag; hand-written in numba because the flagging loop is sequential by nature.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _cell_keys(points, origin, cell, dims):
    n = points.shape[0]
    keys = np.empty(n, np.int64)
    for i in range(n):
        ix = int((points[i, 0] - origin[0]) / cell)
        iy = int((points[i, 1] - origin[1]) / cell)
        iz = int((points[i, 2] - origin[2]) / cell)
        keys[i] = (ix * dims[1] + iy) * dims[2] + iz
    return keys


@njit(cache=True)
def _throw(points, order, min_distance, origin, dims, sorted_keys, sorted_index):
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
        cx = int((points[i, 0] - origin[0]) / min_distance)
        cy = int((points[i, 1] - origin[1]) / min_distance)
        cz = int((points[i, 2] - origin[2]) / min_distance)
        for x in range(max(cx - 1, 0), min(cx + 2, dims[0])):
            for y in range(max(cy - 1, 0), min(cy + 2, dims[1])):
                for z in range(max(cz - 1, 0), min(cz + 2, dims[2])):
                    key = (x * dims[1] + y) * dims[2] + z
                    start = np.searchsorted(sorted_keys, key)
                    k = start
                    while k < n and sorted_keys[k] == key:
                        j = sorted_index[k]
                        if not flagged[j]:
                            dx = points[j, 0] - points[i, 0]
                            dy = points[j, 1] - points[i, 1]
                            dz = points[j, 2] - points[i, 2]
                            if dx * dx + dy * dy + dz * dz < d2:
                                flagged[j] = True
                        k += 1
    return placed[:count]


def dart_throw(points: np.ndarray, order: np.ndarray, min_distance: float) -> np.ndarray:
    """Indices of the placed candidates, in placing order (that order is P_num)."""
    if len(points) == 0:
        return np.zeros(0, np.int64)
    points = np.ascontiguousarray(points, np.float64)
    origin = points.min(axis=0) - 1e-9
    dims = np.floor((points.max(axis=0) - origin) / min_distance).astype(np.int64) + 1
    keys = _cell_keys(points, origin, float(min_distance), dims)
    sorted_index = np.argsort(keys, kind="stable")
    return _throw(
        points, np.asarray(order, np.int64), float(min_distance), origin, dims, keys[sorted_index], sorted_index
    )


def min_distance_ratio(points: np.ndarray, min_distance: float) -> float:
    """Smallest neighbour distance over the required minimum (≥ 1 for a valid Poisson-disk set)."""
    if len(points) < 2:
        return float("inf")
    from scipy.spatial import cKDTree

    distances, _ = cKDTree(points).query(points, k=2)
    return float(distances[:, 1].min() / min_distance)
