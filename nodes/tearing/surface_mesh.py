"""A closed triangle surface as half-edge arrays that splits along edges — SPEC §5 (U §3.2: half-edge
structure, every face a triangle).

Half-edge ``3f + k`` runs ``faces[f, k] → faces[f, (k + 1) % 3]``; ``twin`` pairs it with the half-edge
of the face across, or holds −1 on an opening. A face's half-edges and its corners share indices, so
splitting along edges is a union of corners: corners of one vertex stay one vertex while an unbroken
edge joins their faces (``cut``). Arrays, not linked objects; the unions run in numba
(``union_labels``): 7–37× faster than scipy's connected components on the same corner graph
(``benchmarks/bench_tearing.py --only split``), the tear's main cost after re-clustering.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import njit


@njit(cache=True)
def union_labels(n, rows, cols):
    """Connected components of n nodes joined by the pairs (rows[i], cols[i]): union-find with path
    halving; labels numbered in order of each component's smallest node (deterministic). (labels, count)."""
    parent = np.arange(n)
    for i in range(rows.shape[0]):
        a, b = rows[i], cols[i]
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        while parent[b] != b:
            parent[b] = parent[parent[b]]
            b = parent[b]
        if a != b:
            parent[max(a, b)] = min(a, b)
    label = np.full(n, -1)
    count = 0
    for i in range(n):
        r = i
        while parent[r] != r:
            r = parent[r]
        if label[r] < 0:
            label[r] = count
            count += 1
        label[i] = label[r]
    return label, count


@dataclass(frozen=True, eq=False)
class SurfaceMesh:
    """Triangles over ``n_vertices`` vertices with half-edge twins (−1: an opening) and ``cracked``:
    broken half-edge pairs that have not opened yet (neither end vertex has split, U §4.3's crack tip)."""

    faces: np.ndarray  # (F, 3) int64
    twin: np.ndarray  # (3F,) int64
    cracked: np.ndarray  # (3F,) bool
    n_vertices: int

    @classmethod
    def from_faces(cls, faces, n_vertices: int) -> SurfaceMesh:
        """Pair half-edges of a closed, consistently oriented triangle mesh; ValueError when it is not one."""
        faces = np.asarray(faces, dtype=np.int64)
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0:
            raise ValueError(f"faces: expected a non-empty (F, 3) array, got shape {faces.shape}")
        if faces.min() < 0 or faces.max() >= n_vertices:
            raise ValueError(f"faces: vertex indices must lie in [0, {n_vertices - 1}]")
        if np.any((faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])):
            raise ValueError("faces: a triangle repeats a vertex (degenerate face)")
        origin, dest = faces.ravel(), faces[:, [1, 2, 0]].ravel()
        key = origin * n_vertices + dest
        back = dest * n_vertices + origin
        order = np.argsort(key)
        if np.any(key[order][1:] == key[order][:-1]):
            raise ValueError("mesh is not consistently oriented: a directed edge is used twice")
        pos = np.searchsorted(key[order], back)
        pos = np.minimum(pos, len(key) - 1)
        found = key[order][pos] == back
        if not found.all():
            h = int(np.flatnonzero(~found)[0])
            raise ValueError(
                f"mesh is not closed: edge ({origin[h]}, {dest[h]}) has one face; tearing needs a closed surface"
            )
        twin = order[pos]
        return cls(faces, twin.astype(np.int64), np.zeros(len(twin), bool), int(n_vertices))

    @cached_property
    def origin(self) -> np.ndarray:
        """Start vertex of every half-edge (3F,)."""
        return self.faces.ravel()

    @cached_property
    def dest(self) -> np.ndarray:
        """End vertex of every half-edge (3F,) (kept: the break test reads it every step)."""
        return self.faces[:, [1, 2, 0]].ravel()

    def edges(self) -> np.ndarray:
        """One half-edge per edge: each glued pair once, each opening's half-edge (E,)."""
        h = np.arange(len(self.twin))
        return h[(self.twin < 0) | (h < self.twin)]

    def components(self) -> np.ndarray:
        """Connected component label per vertex (faces join their vertices; a vertex in no face is alone)."""
        return union_labels(self.n_vertices, self.origin, self.dest)[0]

    def cut(self, broken: np.ndarray) -> tuple[SurfaceMesh, np.ndarray]:
        """Split along the half-edge pairs flagged in ``broken`` (3F,) (U §3.2.3 steps 1–2).

        A vertex becomes one vertex per fan of its faces still joined by unbroken edges; a broken
        pair whose end vertices both stay whole keeps its twin and is only marked ``cracked`` (it
        opens once a neighbouring break splits an end). Returns the new mesh and ``source``: the old
        vertex of each new one (new vertices inherit position, velocity and rest position).
        """
        twin = self.twin
        glued = twin >= 0
        cracked = self.cracked | (glued & (broken | broken[np.maximum(twin, 0)]))
        h = np.flatnonzero(glued & ~cracked)
        h = h[h < twin[h]]
        t = twin[h]
        nxt = lambda e: 3 * (e // 3) + (e + 1) % 3  # noqa: E731  (the next corner of the same face)
        # corner of h's origin in its face (h itself) ≡ corner after t in t's face; h's end ≡ t's origin
        rows = np.concatenate([h, nxt(h)])
        cols = np.concatenate([nxt(t), t])
        corner_vertex, count = union_labels(3 * len(self.faces), rows, cols)
        source = np.empty(count, np.int64)
        source[corner_vertex] = self.origin
        lone = np.flatnonzero(np.bincount(self.origin, minlength=self.n_vertices) == 0)  # in no face: stay
        source = np.concatenate([source, lone])
        faces = corner_vertex.reshape(-1, 3).astype(np.int64)
        pairs = np.flatnonzero(glued & cracked)
        split = (corner_vertex[pairs] != corner_vertex[nxt(twin[pairs])]) | (
            corner_vertex[nxt(pairs)] != corner_vertex[twin[pairs]]
        )  # either end vertex split: the pair opens
        opened = pairs[split]
        twin = twin.copy()
        twin[opened] = -1
        cracked = cracked & (twin >= 0)
        return SurfaceMesh(faces, twin, cracked, len(source)), source

    def boundary_loops(self) -> tuple[np.ndarray, np.ndarray]:
        """The openings as vertex loops: ``(start, loop)``, loop i is ``loop[start[i]:start[i+1]]`` in the
        order of its faces' half-edges (each vertex has at most one outgoing open half-edge after ``cut``)."""
        open_h = np.flatnonzero(self.twin < 0)
        if len(open_h) == 0:
            return np.zeros(1, np.int64), np.zeros(0, np.int64)
        origin, dest = self.origin[open_h], self.dest[open_h]
        out_of = np.full(self.n_vertices, -1, np.int64)
        out_of[origin] = np.arange(len(open_h))
        if np.count_nonzero(out_of >= 0) != len(open_h):
            raise ValueError("a vertex has two outgoing open half-edges: the mesh was not split at a pinch")
        successor = out_of[dest]
        return _cycles(successor, origin)

    def is_closed(self) -> bool:
        """Every half-edge has a twin running the other way (a closed, oriented 2-manifold's edges)."""
        t = self.twin
        return bool(np.all(t >= 0) and np.all(self.origin[t] == self.dest) and np.all(self.dest[t] == self.origin))


def _cycles(successor: np.ndarray, vertex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cycles of the permutation ``successor`` as ragged loops of ``vertex``."""
    seen = np.zeros(len(successor), bool)
    loops = []
    for first in range(len(successor)):
        if seen[first]:
            continue
        loop = []
        i = first
        while not seen[i]:
            seen[i] = True
            loop.append(vertex[i])
            i = successor[i]
        loops.append(loop)
    start = np.concatenate([[0], np.cumsum([len(loop) for loop in loops])]).astype(np.int64)
    return start, np.concatenate([np.asarray(loop, np.int64) for loop in loops])


def fan_caps(loop_start: np.ndarray, loop: np.ndarray, n_vertices: int) -> np.ndarray:
    """Cap faces closing each opening: a fan around a new centroid vertex ``n_vertices + i`` for loop i
    (U §3.2.3), wound against the loop's half-edges so every edge gains its twin. (C, 3)."""
    lengths = np.diff(loop_start)
    loop_id = np.repeat(np.arange(len(lengths)), lengths)
    nxt = np.arange(len(loop)) + 1
    ends = loop_start[1:] - 1
    nxt[ends] = loop_start[:-1]
    return np.stack([loop[nxt], loop, n_vertices + loop_id], axis=1).astype(np.int64)


def cube_surface(segments: int, size: float) -> tuple[np.ndarray, np.ndarray]:
    """Cube surface with ``segments`` triangle-pair rows per edge (U table 4.1 blocks: 6k² + 2 vertices),
    centred at the origin, edge ``size``, outward winding. Returns (vertices, faces)."""
    k = int(segments)
    if k < 1:
        raise ValueError(f"segments: {k}; allowed ≥ 1")
    t = np.linspace(-0.5, 0.5, k + 1)
    u, v = np.meshgrid(t, t, indexing="ij")
    u, v = u.ravel(), v.ravel()
    points, faces = [], []
    grid = np.arange((k + 1) ** 2).reshape(k + 1, k + 1)
    a, b, c, d = grid[:-1, :-1].ravel(), grid[1:, :-1].ravel(), grid[1:, 1:].ravel(), grid[:-1, 1:].ravel()
    quads = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    for axis in range(3):
        for sign in (-1.0, 1.0):
            p = np.zeros((len(u), 3))
            i, j = (axis + 1) % 3, (axis + 2) % 3
            p[:, axis] = 0.5 * sign
            p[:, i], p[:, j] = u, v  # e_i × e_j = e_axis: outward on the + side
            faces.append((quads if sign > 0 else quads[:, ::-1]) + len(points) * len(u))
            points.append(p)
    points = np.concatenate(points)
    keys = np.round(points * 2 * k).astype(np.int64)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return points[first] * size, inverse.ravel()[np.concatenate(faces)]
