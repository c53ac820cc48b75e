"""How far placed elements stand out of the shape they fill, and keeping each within a share of its own size —
SPEC §2.6 (the refine moves elements along their normal; issue 26: nothing floats off the shape).

An element's *reach* is how far its outermost point lies outside the shape's surface (mm; < 0: wholly inside);
its *size* is its extent along the shape's outward normal at the point of the surface nearest its centre. The
bound is reach ≤ share × size: 0 keeps every element wholly inside, 0.5 lets up to half of it stand out (its
centre on the surface). A share of the element's own size, not a fixed inset: a chestnut piece 2× a grain may
stand out 2× as far as the grain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PROBES = 8  # per element, its points furthest along the outward normal whose true distance to the shape is taken
SETTLE_STEPS = 4  # inward moves after the refine: each takes the remaining excess (curved shapes need a second)


@dataclass(frozen=True, eq=False)
class ShapeBound:
    """The closed shape the elements fill (outward normals), the share of its size an element may reach out, and
    each element template's mesh vertices in its own frame (template order: ``ElementTemplates.index``)."""

    vertices: np.ndarray
    faces: np.ndarray
    share: np.ndarray  # per template: the most of its size that may stand outside
    element_points: tuple[np.ndarray, ...]


def _signed_distance(points: np.ndarray, bound: ShapeBound):
    """(distance > 0 outside, unit outward normal at the nearest surface point) of each point."""
    import igl

    if len(points) == 0:
        return np.zeros(0), np.zeros((0, 3))
    distance, _, _, normals = igl.signed_distance(
        np.ascontiguousarray(points, np.float64),
        bound.vertices,
        bound.faces,
        sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL,
    )
    normals = np.asarray(normals, np.float64)
    return np.asarray(distance, np.float64), normals / np.linalg.norm(normals, axis=1, keepdims=True)


def _furthest(rotations, tmpl, bound: ShapeBound, direction):
    """(extent along ``direction``, the ``PROBES`` vertices furthest along it in each element's own frame)."""
    local = np.einsum("nji,nj->ni", rotations, direction)  # the direction in each element's own frame
    extent = np.zeros(len(rotations))
    tops = np.zeros((len(rotations), PROBES, 3))
    for t in np.unique(tmpl):
        rows = np.flatnonzero(tmpl == t)
        pts = bound.element_points[t]
        height = local[rows] @ pts.T  # (rows, vertices)
        extent[rows] = height.max(axis=1) - height.min(axis=1)
        k = min(PROBES, len(pts))
        top = np.argpartition(-height, k - 1, axis=1)[:, :k]
        tops[rows] = pts[np.pad(top, ((0, 0), (0, PROBES - k)), mode="edge")]
    return extent, tops


def shape_reach(positions, rotations, tmpl, bound: ShapeBound):
    """(reach, size, outward) per element: how far it stands outside the shape (mm), its extent along
    ``outward`` (the shape's outward normal nearest its centre) and that normal. Measured on the element's mesh
    vertices: the ``PROBES`` furthest along ``outward`` are tested against the shape, then the ``PROBES``
    furthest along the shape's normal nearest the one that reached out most (on a curved shape the outermost
    vertex lies off the centre's normal)."""
    n = len(positions)
    _, outward = _signed_distance(positions, bound)
    reach, direction, size = np.full(n, -np.inf), outward, None
    for _ in range(2):
        extent, tops = _furthest(rotations, tmpl, bound, direction)
        size = extent if size is None else size
        world = positions[:, None, :] + np.einsum("nij,npj->npi", rotations, tops)
        distance, normals = _signed_distance(world.reshape(-1, 3), bound)
        distance, normals = distance.reshape(n, PROBES), normals.reshape(n, PROBES, 3)
        reach = np.maximum(reach, distance.max(axis=1))
        direction = normals[np.arange(n), distance.argmax(axis=1)]
    return reach, size, outward


def offset_caps(placement, tmpl, bound: ShapeBound) -> np.ndarray:
    """The largest offset t along each element's normal (from where it is now) that keeps reach ≤ share × size,
    to first order (reach grows by t·(normal · outward)); +inf where the normal runs along the surface."""
    reach, size, outward = shape_reach(placement.positions, placement.rotations, tmpl, bound)
    along = np.einsum("ij,ij->i", placement.normals, outward)
    cap = (bound.share[tmpl] * size - reach) / np.maximum(along, 0.5)
    return np.where(along > 0.5, cap, np.inf)


def settle_inside(positions, rotations, tmpl, bound: ShapeBound) -> np.ndarray:
    """Move each element still reaching out more than share × size in along the shape's inward normal by its
    excess (``positions`` in place); returns the displacement of each element."""
    start = positions.copy()
    rows = np.arange(len(positions))
    for _ in range(SETTLE_STEPS):
        reach, size, outward = shape_reach(positions[rows], rotations[rows], tmpl[rows], bound)
        excess = reach - bound.share[tmpl[rows]] * size
        over = excess > 1e-6 * np.maximum(size, 1e-9)
        if not over.any():
            break
        rows, excess, outward = rows[over], excess[over], outward[over]
        positions[rows] -= (excess * (1.0 + 1e-6))[:, None] * outward
    return positions - start
