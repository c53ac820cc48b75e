"""Tearing — SPEC §5 (U §3.2.2–3.2.3, §4.3): which edges break, and the split topology's clusters.

Two break rules, both on the stretch of an edge over its rest length:

- ``vertex`` (U §4.1): when every edge at a vertex is stretched beyond the threshold (U: 3×), the
  faces around that vertex are extracted: the edges of its one-ring's rim break, so its fan leaves
  as a piece of its own and both openings are capped.
- ``edge`` (cracks, U §4.3's open problem): each edge beyond the threshold breaks by itself; a broken
  edge opens once one of its end vertices splits (two broken edges meet there), so a run of broken
  edges is a crack that grows, and separates a piece when it closes on itself.

Clusters (U §3.2.1) are the connected components of the split mesh, one shape-matching cluster each.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .surface_mesh import SurfaceMesh

RULES = ("vertex", "edge")


@njit(cache=True)
def stretch_ratios(x, origin, dest, rest_length, out):
    """Current over rest length of every half-edge into ``out`` (U §3.2.2's break measure)."""
    for h in range(origin.shape[0]):
        a, b = origin[h], dest[h]
        d = np.sqrt((x[a, 0] - x[b, 0]) ** 2 + (x[a, 1] - x[b, 1]) ** 2 + (x[a, 2] - x[b, 2]) ** 2)
        out[h] = d / rest_length[h]


@njit(cache=True)
def largest_stretch(x, a, b, rest_length):
    """The largest current-over-rest length of the edges (a[i], b[i]): the per-step break test."""
    worst = 0.0
    for i in range(a.shape[0]):
        p, q = a[i], b[i]
        d2 = (x[p, 0] - x[q, 0]) ** 2 + (x[p, 1] - x[q, 1]) ** 2 + (x[p, 2] - x[q, 2]) ** 2
        worst = max(worst, d2 / (rest_length[i] * rest_length[i]))
    return np.sqrt(worst)


@njit(cache=True)
def _fully_stretched(ratio, origin, dest, n, threshold):
    """Per vertex: every incident half-edge's ratio exceeds ``threshold`` (vertices in no face: False)."""
    least = np.full(n, np.inf)
    for h in range(origin.shape[0]):
        least[origin[h]] = min(least[origin[h]], ratio[h])
        least[dest[h]] = min(least[dest[h]], ratio[h])
    return (least > threshold) & (least < np.inf)


def watched_edges(mesh: SurfaceMesh, rule: str) -> np.ndarray:
    """One half-edge per edge the break test must watch: rule 'edge', the glued ones not yet cracked
    (only they can break); rule 'vertex', every edge (a vertex tears when all of its edges are long)."""
    h = mesh.edges()
    return h if rule == "vertex" else h[(mesh.twin[h] >= 0) & ~mesh.cracked[h]]


def broken_half_edges(mesh: SurfaceMesh, ratio: np.ndarray, threshold: float, rule: str) -> np.ndarray:
    """Half-edges that break under ``rule`` (see the module docstring); (3F,) bool."""
    if rule == "edge":
        return ratio > threshold
    if rule != "vertex":
        raise ValueError(f"tear rule {rule!r}; allowed: {', '.join(RULES)}")
    torn = _fully_stretched(ratio, mesh.origin, mesh.dest, mesh.n_vertices, threshold)
    corner = np.flatnonzero(torn[mesh.origin])  # corner k of face f at a torn vertex: half-edge 3f + k
    broken = np.zeros(len(ratio), bool)
    broken[3 * (corner // 3) + (corner + 1) % 3] = True  # the rim edge across from that corner
    return broken


def cluster_order(mesh: SurfaceMesh) -> tuple[np.ndarray, np.ndarray]:
    """Relabel connected components as clusters (U §3.2.2 step 3): ``order`` sorts the vertices by
    cluster (stable, so a cluster keeps its vertices' relative order), ``start`` (m + 1) the cluster
    ranges in that order."""
    labels = mesh.components()
    order = np.argsort(labels, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(labels))]).astype(np.int64)
    return order, start
