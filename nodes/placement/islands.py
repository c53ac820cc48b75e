"""The kept elements' contact graph and what floats in it, for the ``cut`` node (issue 26): two elements touch when
a vertex of one lies within a reach of a vertex of the other (a small typed kernel on ``spatial_grid``'s cells: no
library finds vertex pairs between different elements and keeps only the element pairs); its pieces and shortest
bridges by scipy's csgraph. Its own module so that loading the node registry imports neither numba nor scipy (a
cached re-run needs neither: tests/engine/test_cached_rerun_imports.py).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..kernel_arrays import kernel_array
from ..spatial_grid import CellGrid, build_grid, column_run, neighbour_block
from ..values import Aggregate


def element_surfaces(aggregate: Aggregate) -> tuple[np.ndarray, np.ndarray, float]:
    """Every element's outer-part vertices in world space (those of its ``parts == 0`` faces: an ikura yolk nested
    inside its membrane touches no neighbour), the element each belongs to, and the median element length (the
    largest extent of the library meshes)."""
    shapes = aggregate.without_normals()
    points, outer = [], {}
    for i in range(len(aggregate.placement)):
        mesh = shapes.element_mesh(i)
        key = (int(aggregate.placement.kinds[i]), int(aggregate.placement.variants[i]))
        if key not in outer:
            outer[key] = slice(None) if mesh.parts is None else np.unique(mesh.faces[mesh.parts == 0])
        points.append(mesh.vertices[outer[key]])
    owner = np.repeat(np.arange(len(points)), [len(v) for v in points])
    lengths = [float(np.ptp(m.vertices, axis=0).max()) for library in aggregate.libraries for m in library.meshes]
    return np.concatenate(points), owner, float(np.median(lengths))


@njit(cache=True)
def touching_pairs(points, owner, count, reach, grid):
    """(k, 2) pairs i < j of elements with a vertex of i within ``reach`` of a vertex of j, each pair once.
    ``points`` grouped by element (``owner`` non-decreasing); ``grid`` (``spatial_grid``) sorts them by cells of
    at least ``reach``, so a point's partners lie in the 27 cells around its own."""
    order = grid.order
    xs = points[order]
    es = owner[order]
    seen = np.full(count, -1, np.int64)  # seen[j] = i: the pair (i, j) is out already
    out = np.empty((8 * count + 16, 2), np.int64)
    found = 0
    for p in range(points.shape[0]):
        i = owner[p]
        px, py, pz = points[p, 0], points[p, 1], points[p, 2]
        x0, x1, y0, y1, z0, z1 = neighbour_block(grid, px, py, pz)
        for gx in range(x0, x1):
            for gy in range(y0, y1):
                q0, q1 = column_run(grid, gx, gy, z0, z1)
                for q in range(q0, q1):
                    j = es[q]
                    if j <= i or seen[j] == i:
                        continue
                    ex, ey, ez = xs[q, 0] - px, xs[q, 1] - py, xs[q, 2] - pz
                    if ex * ex + ey * ey + ez * ez <= reach * reach:
                        seen[j] = i
                        if found == out.shape[0]:
                            grown = np.empty((2 * found, 2), np.int64)
                            grown[:found] = out
                            out = grown
                        out[found, 0] = i
                        out[found, 1] = j
                        found += 1
    return out[:found]


def contact_graph(points: np.ndarray, owner: np.ndarray, count: int, reach: float):
    """The elements' contact graph (``count`` × ``count``, symmetric CSR of ones): i and j touch when a vertex
    of i lies within ``reach`` of a vertex of j (``touching_pairs``; same-element vertex pairs are skipped, not
    listed: on the bunny's 2.5 M grain vertices a cKDTree listed 16 M pairs within 0.7 mm, almost all within one
    grain, in 3.5 CPU s). The grid's cells grow past ``reach`` when there would be over 16 a point."""
    from scipy.sparse import coo_matrix

    points = kernel_array(points)
    owner = kernel_array(owner, np.int64)
    grid = CellGrid(*build_grid(points, points.min(axis=0), float(reach), 16.0 * len(points) + 4096))
    pairs = touching_pairs(points, owner, count, float(reach), grid)
    i, j = pairs[:, 0], pairs[:, 1]
    return coo_matrix((np.ones(2 * len(i)), (np.r_[i, j], np.r_[j, i])), shape=(count, count)).tocsr()


def supported(graph, keep: np.ndarray, grounded: np.ndarray) -> np.ndarray:
    """True for the kept elements joined to a grounded kept element by a chain of kept elements in contact."""
    from scipy.sparse.csgraph import connected_components

    kept = np.flatnonzero(keep)
    _, label = connected_components(graph[kept][:, kept], directed=False)
    out = np.zeros(len(keep), bool)
    out[kept] = np.isin(label, label[grounded[kept]])
    return out


def bridged(graph, keep: np.ndarray, grounded: np.ndarray) -> np.ndarray:
    """``keep`` plus, for each floating piece, the fewest removed elements joining it to the supported ones.

    One piece at a time, the cheapest first: Dijkstra from every supported element, stepping onto a removed
    element costs 1 and onto a kept one 1/(n + 1) (so no chain of kept elements outweighs one removed); the piece
    nearest by that cost gets its path, and the next search starts from the grown set, so a later piece may lean on
    an earlier bridge. A piece no path reaches stays out."""
    from scipy.sparse.csgraph import dijkstra

    n = len(keep)
    keep = keep.copy()
    unreachable = np.zeros(n, bool)
    while True:
        held = supported(graph, keep, grounded)
        floating = keep & ~held & ~unreachable
        if not floating.any():
            return keep & ~unreachable
        cost = np.where(keep, 1.0 / (n + 1), 1.0)
        steps = graph.copy()
        steps.data = cost[steps.indices]  # entering column j costs cost[j]
        distance, previous, _ = dijkstra(steps, indices=np.flatnonzero(held), min_only=True, return_predecessors=True)
        target = np.flatnonzero(floating)[np.argmin(distance[floating])]
        if not np.isfinite(distance[target]):
            unreachable |= floating
            continue
        while target >= 0 and not held[target]:
            keep[target] = True
            target = previous[target]
