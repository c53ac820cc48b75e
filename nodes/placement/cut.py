"""The ``cut`` node: an aggregate minus a half-space or a sphere, so a volume fill's inside shows — G's rice
bunny with a cut revealing the filled inside (G §4; SPEC §2.2: G fills the shape's volume, S only its surface).

Whole elements are kept or removed by their centre (no element is sliced): the cut face shows the grains as
they lie inside, which is what G's cut view is for.

A cut can leave pieces resting on nothing: a plane through the bunny's head removed the grains that joined its
ears to it, and the ears hung in the air (issue 26). The kept elements and their contacts form a graph (two
elements touch when a vertex of one lies within ``gap`` of a vertex of the other, so their surfaces are closer
than that; ``gap`` should be about an edge of the meshes or more, or touching meshes can be missed: the bunny's
grain meshes have edges of 0.44 mm, the draft's 0.67, and ``gap`` 0.1 grain lengths is 0.75 mm); a piece of it
holding no element on the floor (within ``gap`` of the lowest kept point, where a preview's backdrop lies) floats.
``islands`` says what becomes of such a piece: ``bridge`` keeps the fewest removed elements that join it back to
the supported ones (a shortest path through the contact graph whose cost is the removed elements it passes),
``drop`` removes it, ``keep`` leaves it floating (version 1's cut).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numba import njit

from nodegraph.node import In, Out, node
from nodegraph.params import Param

from ..kernel_arrays import kernel_array
from ..values import Aggregate

KINDS = ("plane", "sphere")
ISLANDS = ("bridge", "drop", "keep")


def cut_mask(positions: np.ndarray, kind: str, normal, offset: float, center, radius: float) -> np.ndarray:
    """True for the elements kept. The plane and sphere are placed relative to the centre of the positions'
    bounding box; ``plane`` removes centres with (p − c)·n̂ > ``offset``, ``sphere`` those within ``radius`` of
    c + ``center``."""
    if len(positions) == 0:
        return np.zeros(0, bool)
    middle = 0.5 * (positions.min(axis=0) + positions.max(axis=0))
    if kind == "plane":
        n = np.asarray(normal, np.float64)
        length = np.linalg.norm(n)
        if not length > 0:
            raise ValueError("normal: a zero vector has no direction; give the side to remove, e.g. [0, -1, 0]")
        return (positions - middle) @ (n / length) <= offset
    if kind == "sphere":
        return np.linalg.norm(positions - (middle + np.asarray(center, np.float64)), axis=1) > radius
    raise ValueError(f"kind: '{kind}' is not a cut; allowed: {', '.join(KINDS)}")


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
def touching_pairs(points, owner, count, reach, cells, dims, start, order):
    """(k, 2) pairs i < j of elements with a vertex of i within ``reach`` of a vertex of j, each pair once.
    ``points`` grouped by element (``owner`` non-decreasing); ``cells`` their grid cells (size ≥ reach), z fastest,
    counting-sorted (``order``; cell k holds sorted positions start[k]:start[k + 1]), so a point's partners lie in
    the 27 cells around its own, 9 runs of the sorted order."""
    xs = points[order]
    es = owner[order]
    seen = np.full(count, -1, np.int64)  # seen[j] = i: the pair (i, j) is out already
    out = np.empty((8 * count + 16, 2), np.int64)
    found = 0
    for p in range(points.shape[0]):
        i = owner[p]
        px, py, pz = points[p, 0], points[p, 1], points[p, 2]
        z0, z1 = max(cells[p, 2] - 1, 0), min(cells[p, 2] + 1, dims[2] - 1)
        for gx in range(max(cells[p, 0] - 1, 0), min(cells[p, 0] + 2, dims[0])):
            for gy in range(max(cells[p, 1] - 1, 0), min(cells[p, 1] + 2, dims[1])):
                base = (gx * dims[1] + gy) * dims[2]
                for q in range(start[base + z0], start[base + z1 + 1]):
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
    origin, cell = points.min(axis=0), reach
    while True:
        cells = ((points - origin) / cell).astype(np.int64)
        dims = cells.max(axis=0) + 1
        if np.prod(dims.astype(np.float64)) <= 16 * len(points) + 4096:
            break
        cell *= 2.0
    keys = (cells[:, 0] * dims[1] + cells[:, 1]) * dims[2] + cells[:, 2]
    start = np.zeros(int(np.prod(dims)) + 1, np.int64)
    np.cumsum(np.bincount(keys, minlength=len(start) - 1), out=start[1:])
    order = np.argsort(keys, kind="stable")
    pairs = touching_pairs(points, owner, count, reach, cells, dims, start, order)
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


@node(
    "cut",
    # 2: islands, gap (pieces the cut leaves resting on nothing are bridged back by default)
    version=2,
    inputs={"aggregate": In(Aggregate, "placed or simulated elements (a volume fill)")},
    outputs={
        "aggregate": Out(
            Aggregate,
            "the elements whose centres lie outside the removed region (and, with islands bridge, the removed "
            "elements that join a floating piece back)",
        )
    },
    params={
        "kind": Param(
            str, "plane", "plane: remove a half-space; sphere: remove a ball (elements by their centre)", choices=KINDS
        ),
        "normal": Param(
            tuple[float, float, float],
            (0.0, -1.0, 0.0),
            "plane: direction of the removed side (point it at the camera: −y faces a preview at azimuth 0)",
            range=(-1.0, 1.0),
        ),
        "offset": Param(
            float,
            0.0,
            "plane: distance of the plane from the elements' bounding-box centre along the normal",
            range=(-1e4, 1e4),
            units="mm",
        ),
        "center": Param(
            tuple[float, float, float],
            (0.0, 0.0, 0.0),
            "sphere: its centre relative to the elements' bounding-box centre",
            range=(-1e4, 1e4),
            units="mm",
        ),
        "radius": Param(float, 20.0, "sphere: radius of the removed ball", range=(0.0, 1e4), units="mm"),
        "islands": Param(
            str,
            "bridge",
            "kept pieces with no chain of touching elements to the floor: bridge: keep the fewest removed elements "
            "that join them back; drop: remove them; keep: leave them floating",
            choices=ISLANDS,
        ),
        "gap": Param(
            float,
            0.1,
            "two elements touch when a vertex of one lies closer than this to a vertex of the other (keep it above the "
            "meshes' edge length), and an element lies on the floor when as close to the lowest kept point",
            range=(0.01, 1.0),
            units="element lengths",
        ),
    },
)
def cut(ctx, aggregate, *, kind, normal, offset, center, radius, islands, gap):
    """Keep whole elements by their centre (``cut_mask``), then bridge or drop the pieces left floating
    (``bridged``, ``supported``); per-element deformations and bends go with them."""
    keep = cut_mask(aggregate.placement.positions, kind, normal, offset, center, radius)
    if not keep.any():
        raise ValueError(f"the {kind} cut removes every element; move it (offset, center) or shrink it (radius)")
    if islands != "keep":
        points, owner, length = element_surfaces(aggregate)
        graph = contact_graph(points, owner, len(keep), gap * length)
        lowest = np.full(len(keep), np.inf)
        np.minimum.at(lowest, owner, points[:, 2])
        grounded = keep & (lowest <= lowest[keep].min() + gap * length)
        keep = bridged(graph, keep, grounded) if islands == "bridge" else supported(graph, keep, grounded)
    if hasattr(aggregate, "subset"):  # an aggregate with per-vertex state (flattened contacts, yolk offsets)
        return aggregate.subset(keep)
    per_element = {
        name: getattr(aggregate, name)[keep]
        for name in ("deformations", "bends")
        if getattr(aggregate, name) is not None
    }
    return dataclasses.replace(aggregate, placement=aggregate.placement.subset(keep), **per_element)
