"""Elements placed inside one another part without friction between them — issue 46.

A placement keeps overlaps up to its cull's threshold, judged on the implicit shapes: a pair it keeps can still have
particles over 1 r deep in each other. Static friction, with clumping's cohesion in its load, then holds such a pair
locked: it drifts together and its contacts throw it once they give (docs/validation.md, "part without friction").
The pairs with at least a cluster's count of particle pairs deeper than ``PART_DEPTH`` radii at the start lose friction
between each other (only each other) until their deepest overlap is back under it; their contacts then part them at
the solver's own depenetration. Fewer deep particle pairs mark an ordinary contact: a pressed block of grains has 25
pairs past 0.5 r with at most 6 each, the nigiri's placement 336 with up to 15.
"""

from __future__ import annotations

import numpy as np

# radii of the smaller particle: a pair of elements with at least a cluster's count of particle pairs this deep in each
# other at the start parts without friction between them, until its deepest overlap is under it. A locked pair sits
# 1.1 r deep; the contact sweep leaves a tall pile's contacts ≤ 0.2 r (``contact_constraints._project_slab``)
PART_DEPTH = 0.5
NO_PAIRS = np.zeros((0, 2), np.int64)  # no pair parting
NO_ENTRIES = np.zeros(0, np.bool_)  # no list entry parting: the sweep rubs every pair


def deep_pairs(x: np.ndarray, r: np.ndarray, elem: np.ndarray, n: int) -> np.ndarray:
    """(k, 2) element pairs (lower first, sorted) of the first ``n`` particles (element ids ``elem``) with at least as
    many particle pairs deeper than ``PART_DEPTH`` of the smaller radius as the smaller of the two has particles."""
    from scipy.spatial import cKDTree

    if n < 2:
        return NO_PAIRS
    x, r, elem = x[:n], r[:n], elem[:n]
    i, j = cKDTree(x).query_pairs(2.0 * float(r.max()), output_type="ndarray").T
    depth = r[i] + r[j] - np.linalg.norm(x[i] - x[j], axis=1)
    deep = (elem[i] != elem[j]) & (depth > PART_DEPTH * np.minimum(r[i], r[j]))
    if not deep.any():
        return NO_PAIRS
    pairs, count = np.unique(
        np.sort(np.stack([elem[i[deep]], elem[j[deep]]], axis=1), axis=1), axis=0, return_counts=True
    )
    size = np.bincount(elem)  # particles per element
    return pairs[count >= np.minimum(size[pairs[:, 0]], size[pairs[:, 1]])].astype(np.int64)


def deepest(x: np.ndarray, r: np.ndarray, start: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """(k,) the deepest overlap of each element pair's particles, in radii of the smaller particle."""
    out = np.empty(len(pairs))
    for k, (a, b) in enumerate(pairs):
        xa, ra = x[start[a] : start[a + 1]], r[start[a] : start[a + 1]]
        xb, rb = x[start[b] : start[b + 1]], r[start[b] : start[b + 1]]
        d = np.linalg.norm(xa[:, None] - xb[None], axis=2)
        out[k] = float(((ra[:, None] + rb[None] - d) / np.minimum(ra[:, None], rb[None])).max())
    return out


def still_deep(x: np.ndarray, r: np.ndarray, start: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """The pairs of ``pairs`` still deeper than ``PART_DEPTH``: those parted get their friction back."""
    if not len(pairs):
        return pairs
    return pairs[deepest(x, r, start, pairs) > PART_DEPTH]


def entry_flags(nbr_start: np.ndarray, nbr: np.ndarray, order: np.ndarray, elem: np.ndarray, pairs: np.ndarray):
    """Per entry of the neighbour lists (CSR rows of particles ``order``), whether its particles' elements are a
    pair of ``pairs`` (``contact_constraints.PairEntries.parting``); empty when none is."""
    if not len(pairs):
        return NO_ENTRIES
    i = np.repeat(order, np.diff(nbr_start))
    ei, ej = elem[i], elem[nbr]
    span = int(elem.max()) + 1
    keys = np.minimum(ei, ej) * span + np.maximum(ei, ej)
    return np.isin(keys, pairs[:, 0] * span + pairs[:, 1])
