"""How deep neighbouring element meshes cut into each other — the mesh-level overlap measure.

For a sample of elements, every vertex of the element is tested against each neighbour's closed mesh
with libigl's signed distance (AABB tree; sign by the fast generalised winding number, Jacobson et al.
2013, which stays right on meshes with a few folded faces — a flattened contact patch can fold — where
the pseudo-normal sign calls points far outside a thin grain deep inside it; on clean meshes the two
agree, at the same cost): a vertex inside a neighbour lies at depth −d. Depths are in element lengths
(the largest extent of the element's own mesh). A part nested inside its own element (an ikura yolk
inside the membrane) is not a neighbour: only the outermost part of each element (``parts == 0``) is
tested. Hand-written around igl because trimesh's signed distance is ~100× slower and needs rtree
(ENVIRONMENT.md)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class OverlapStats:
    """Per touching pair (a sampled element and a neighbour closer than ``contact`` element lengths): how
    deep the element's vertices reach into the neighbour, in element lengths (0 when only touching);
    per sampled element: how many neighbours it touches."""

    pair_depth: np.ndarray  # (pairs,)
    contacts: np.ndarray  # (k,) int
    sampled: np.ndarray  # (k,) element indices


def outer_shell(vertices: np.ndarray, faces: np.ndarray, parts: np.ndarray | None):
    """The element's outermost closed part: faces of part 0 (all faces without parts)."""
    if parts is None:
        return vertices, faces
    keep = faces[parts == 0]
    used, inverse = np.unique(keep, return_inverse=True)
    return vertices[used], inverse.reshape(-1, 3)


def element_overlaps(
    meshes: list, centres: np.ndarray, radii: np.ndarray, sample: np.ndarray, contact: float = 0.02
) -> OverlapStats:
    """Depths and contacts of ``sample`` elements against their neighbours (bounding spheres within the
    contact distance). ``meshes[i]`` = (vertices, faces, length) of element i's outer shell."""
    import igl
    from scipy.spatial import cKDTree

    tree = cKDTree(centres)
    longest = max(length for _, _, length in meshes)
    reach = 2.0 * float(radii.max()) + contact * longest
    depths = []
    contacts = np.zeros(len(sample), np.int64)
    for row, i in enumerate(sample):
        vertices, _, length = meshes[i]
        for j in tree.query_ball_point(centres[i], reach):
            if j == i or np.linalg.norm(centres[j] - centres[i]) > radii[i] + radii[j] + contact * length:
                continue
            other_v, other_f, _ = meshes[j]
            # Only vertices in the neighbour's box grown by the contact distance can touch or cut it: the rest
            # are farther than ``contact`` from it (exact, and most of a neighbour's vertices are far).
            margin = contact * length
            near = np.all((vertices >= other_v.min(axis=0) - margin) & (vertices <= other_v.max(axis=0) + margin), 1)
            if not near.any():
                continue
            signed = igl.signed_distance(
                vertices[near], other_v, other_f, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER
            )[0]
            closest = float(signed.min())
            if closest < contact * length:
                contacts[row] += 1
                depths.append(max(0.0, -closest) / length)
    return OverlapStats(np.array(depths), contacts, np.asarray(sample))
