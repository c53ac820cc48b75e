"""Inside/outside of a closed mesh on a regular grid by crossing parity along z columns — SPEC §2.2 volume fill.

Each triangle is rasterised onto the (x, y) column centres it covers; the sorted crossing heights
of a column split it into inside/outside runs. Hand-written in numba because trimesh's ray queries
need the optional rtree package and are ~100× slower for whole grids.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _crossings(vertices, faces, xs, ys, count_only, column_start, heights):
    nx, ny = xs.shape[0], ys.shape[0]
    fill = np.zeros(nx * ny, np.int64)
    x0, dx = xs[0], xs[1] - xs[0] if nx > 1 else 1.0
    y0, dy = ys[0], ys[1] - ys[0] if ny > 1 else 1.0
    for f in range(faces.shape[0]):
        a, b, c = vertices[faces[f, 0]], vertices[faces[f, 1]], vertices[faces[f, 2]]
        det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
        if det == 0.0:
            continue
        i_lo = max(int(np.ceil((min(a[0], b[0], c[0]) - x0) / dx)), 0)
        i_hi = min(int(np.floor((max(a[0], b[0], c[0]) - x0) / dx)), nx - 1)
        j_lo = max(int(np.ceil((min(a[1], b[1], c[1]) - y0) / dy)), 0)
        j_hi = min(int(np.floor((max(a[1], b[1], c[1]) - y0) / dy)), ny - 1)
        for i in range(i_lo, i_hi + 1):
            px = xs[i]
            for j in range(j_lo, j_hi + 1):
                py = ys[j]
                wb = ((px - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (py - a[1])) / det
                wc = ((b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1])) / det
                wa = 1.0 - wb - wc
                if wa < 0.0 or wb < 0.0 or wc < 0.0:
                    continue
                col = i * ny + j
                if not count_only:
                    heights[column_start[col] + fill[col]] = wa * a[2] + wb * b[2] + wc * c[2]
                fill[col] += 1
    return fill


@njit(cache=True)
def _parity(column_start, heights, zs, nx, ny):
    inside = np.zeros((nx, ny, zs.shape[0]), np.bool_)
    for col in range(nx * ny):
        raw = np.sort(heights[column_start[col]:column_start[col + 1]])
        # A column through an edge shared by two triangles hits both at the same height: count it once.
        keep = np.ones(raw.shape[0], np.bool_)
        for k in range(1, raw.shape[0]):
            keep[k] = raw[k] - raw[k - 1] > 1e-12
        h = raw[keep]
        if h.shape[0] % 2 == 1:
            continue  # an odd count means a grazing hit: leave the column empty rather than guess
        k = 0
        for level in range(zs.shape[0]):
            while k < h.shape[0] and h[k] <= zs[level]:
                k += 1
            inside[col // ny, col % ny, level] = k % 2 == 1
    return inside


def inside_columns(vertices, faces, xs, ys, zs) -> np.ndarray:
    """Boolean grid inside[i, j, k] for the points (xs[i], ys[j], zs[k]) of a closed mesh."""
    counts = _crossings(vertices, faces, xs, ys, True, np.zeros(1, np.int64), np.zeros(1))
    column_start = np.zeros(len(counts) + 1, np.int64)
    np.cumsum(counts, out=column_start[1:])
    heights = np.empty(column_start[-1])
    _crossings(vertices, faces, xs, ys, False, column_start, heights)
    return _parity(column_start, heights, np.asarray(zs, np.float64), len(xs), len(ys))


@njit(cache=True)
def inside_points(vertices, faces, points):
    """inside[i]: the ray from points[i] towards +z crosses the closed mesh an odd number of times."""
    n = points.shape[0]
    inside = np.zeros(n, np.bool_)
    heights = np.empty(faces.shape[0])
    for p in range(n):
        px, py, pz = points[p, 0], points[p, 1], points[p, 2]
        count = 0
        for f in range(faces.shape[0]):
            a, b, c = vertices[faces[f, 0]], vertices[faces[f, 1]], vertices[faces[f, 2]]
            if max(a[2], b[2], c[2]) < pz or min(a[0], b[0], c[0]) > px or max(a[0], b[0], c[0]) < px \
                    or min(a[1], b[1], c[1]) > py or max(a[1], b[1], c[1]) < py:
                continue
            det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
            if det == 0.0:
                continue
            wb = ((px - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (py - a[1])) / det
            wc = ((b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1])) / det
            wa = 1.0 - wb - wc
            if wa < 0.0 or wb < 0.0 or wc < 0.0:
                continue
            z = wa * a[2] + wb * b[2] + wc * c[2]
            if z > pz:
                heights[count] = z
                count += 1
        h = np.sort(heights[:count])
        distinct = 0
        for k in range(count):
            if k == 0 or h[k] - h[k - 1] > 1e-12:
                distinct += 1
        inside[p] = distinct % 2 == 1
    return inside
