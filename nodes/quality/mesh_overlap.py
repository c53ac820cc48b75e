"""How deep neighbouring element meshes cut into each other — the mesh-level overlap measure.

For a sample of elements, every vertex of the element is tested against each neighbour's closed mesh
with libigl's signed distance (AABB tree; sign by the fast generalised winding number, Jacobson et al.
2013, which stays right on meshes with a few folded faces — a flattened contact patch can fold — where
the pseudo-normal sign calls points far outside a thin grain deep inside it; on clean meshes the two
agree, at the same cost): a vertex inside a neighbour lies at depth −d. Depths are in element lengths
(the largest extent of the element's own mesh). A part nested inside its own element (an ikura yolk
inside the membrane) is not a neighbour: only the outermost part of each element (``parts == 0``) is
tested. Hand-written around igl because trimesh's signed distance is ~100× slower and needs rtree
(ENVIRONMENT.md).

Most of the cost is libigl building each neighbour's AABB tree and winding-number hierarchy (≈ 2.3 ms for a
900-vertex grain, then ≈ 7 µs a point); ``overlap_plan`` groups the calls into tasks (8 neighbour meshes each), each
giving its own values, run in turn in one thread: libigl holds the GIL (``nodegraph/runtime.py``)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np


@dataclass(frozen=True)
class OverlapStats:
    """Per touching pair (a sampled element and a neighbour closer than ``contact`` element lengths): how
    deep the element's vertices reach into the neighbour, in element lengths (0 when only touching);
    per sampled element: how many neighbours it touches."""

    pair_depth: np.ndarray  # (pairs,)
    contacts: np.ndarray  # (k,) int
    sampled: np.ndarray  # (k,) element indices


def outer_shell(faces: np.ndarray, parts: np.ndarray | None) -> tuple[np.ndarray | None, np.ndarray]:
    """The element's outermost closed part: (the vertices its part-0 faces use, those faces renumbered to
    them); (None, faces) without parts. The same for every element of one library mesh."""
    if parts is None:
        return None, faces
    keep = faces[parts == 0]
    used, inverse = np.unique(keep, return_inverse=True)
    return used, inverse.reshape(-1, 3)


def volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The signed volume a closed mesh encloses (divergence theorem over its faces), the same float as
    ``trimesh.Trimesh(vertices, faces).volume`` (its ``mass_properties`` integral 0, term for term) without
    building a Trimesh and its inertia."""
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    ab, bc = b - a, c - b
    cross_x = ab[:, 1] * bc[:, 2] - ab[:, 2] * bc[:, 1]
    return float((cross_x * (a[:, 0] + b[:, 0] + c[:, 0])).sum() / 6.0)


def element_overlaps(
    meshes: list,
    centres: np.ndarray,
    radii: np.ndarray,
    sample: np.ndarray,
    contact: float = 0.02,
    bounds: np.ndarray | None = None,
) -> OverlapStats:
    """Depths and contacts of ``sample`` elements against their neighbours (bounding spheres within the
    contact distance). ``meshes[i]`` = (vertices, faces, length) of element i's outer shell; ``bounds[i]`` its
    vertices' (min, max) (computed when not given)."""
    plan = overlap_plan(meshes, centres, radii, sample, contact, bounds)
    return plan.stats([task() for task in plan.tasks])


@dataclass(frozen=True)
class OverlapPlan:
    """The touching candidates of a sample and the libigl calls that measure them: ``tasks`` (independent calls,
    run in any order) each give the closest signed distance of their pairs, in ``order``."""

    rows: np.ndarray  # (pairs,) each pair's row in ``sample``
    lengths: np.ndarray  # (pairs,) the sampled element's length
    order: np.ndarray  # the pairs in the order the tasks' results come
    tasks: list
    sample: np.ndarray
    contact: float

    def stats(self, results: list[np.ndarray]) -> OverlapStats:
        """The depths and contacts from the tasks' results."""
        closest = np.empty(len(self.rows))
        if len(self.order):
            closest[self.order] = np.concatenate(results)
        depths = []
        contacts = np.zeros(len(self.sample), np.int64)
        for row, length, nearest in zip(self.rows.tolist(), self.lengths.tolist(), closest.tolist()):
            if nearest < self.contact * length:
                contacts[row] += 1
                depths.append(max(0.0, -nearest) / length)
        return OverlapStats(np.array(depths), contacts, np.asarray(self.sample))


def overlap_plan(
    meshes: list,
    centres: np.ndarray,
    radii: np.ndarray,
    sample: np.ndarray,
    contact: float = 0.02,
    bounds: np.ndarray | None = None,
    per_task: int = 8,
) -> OverlapPlan:
    """The pairs (a sampled element, a neighbour whose bounding sphere is within the contact distance of its own,
    with some of the element's vertices in the neighbour's box grown by that distance) and one libigl call per
    neighbour mesh, on the vertices of every sampled element near it: its AABB tree and winding-number hierarchy
    are built once, not once per pair (each point's distance is its own, so the values are those of a call per
    pair); ``per_task`` neighbours a task."""
    from scipy.spatial import cKDTree

    if bounds is None:
        bounds = np.array([(v.min(axis=0), v.max(axis=0)) for v, _, _ in meshes])
    longest = max(length for _, _, length in meshes)
    reach = 2.0 * float(radii.max()) + contact * longest
    candidates = cKDTree(centres).query_ball_point(centres[sample], reach)
    rows, lengths, neighbours, points = [], [], [], []
    for row, (i, near_i) in enumerate(zip(sample.tolist(), candidates)):
        vertices, _, length = meshes[i]
        margin = contact * length
        js = np.array([j for j in near_i if j != i], np.int64)
        if not len(js):
            continue
        gap = radii[i] + radii[js] + margin
        # The spheres' test, vectorised: numpy's norm of one vector (a BLAS dot) and of rows may differ in the
        # last bit, so a distance within 1e-9 of its gap is decided by the one-vector norm, as it always was.
        apart = np.linalg.norm(centres[js] - centres[i], axis=1)
        tie = np.abs(apart - gap) <= 1e-9 * gap
        far = apart > gap
        far[tie] = [np.linalg.norm(centres[j] - centres[i]) > g for j, g in zip(js[tie], gap[tie])]
        js = js[~far]
        # Only vertices in the neighbour's box grown by the contact distance can touch or cut it: the rest are
        # farther than ``contact`` from it (exact, and most of a neighbour's vertices are far).
        lo, hi = bounds[js, 0] - margin, bounds[js, 1] + margin
        inside = np.all((vertices >= lo[:, None]) & (vertices <= hi[:, None]), axis=2)
        for j, near in zip(js.tolist(), inside):
            if near.any():
                rows.append(row)
                lengths.append(length)
                neighbours.append(j)
                points.append(vertices[near])
    by_neighbour: dict[int, list[int]] = {}
    for k, j in enumerate(neighbours):
        by_neighbour.setdefault(j, []).append(k)
    groups = list(by_neighbour.items())
    chunks = [groups[c : c + per_task] for c in range(0, len(groups), per_task)]
    tasks = [
        partial(_closest, [(meshes[j][0], meshes[j][1], [points[k] for k in ks]) for j, ks in chunk])
        for chunk in chunks
    ]
    order = np.array([k for _, ks in groups for k in ks], np.int64)
    return OverlapPlan(np.array(rows, np.int64), np.array(lengths), order, tasks, np.asarray(sample), contact)


def _closest(calls: list) -> np.ndarray:
    """Per call (a neighbour's vertices and faces, the point sets of its pairs): each point set's smallest signed
    distance to the neighbour (libigl, sign by the fast winding number), calls one after another."""
    import igl

    closest = []
    for other_v, other_f, sets in calls:
        signed = igl.signed_distance(
            np.concatenate(sets), other_v, other_f, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER
        )[0]
        closest.append(np.minimum.reduceat(signed, np.cumsum([0] + [len(p) for p in sets[:-1]])))
    return np.concatenate(closest)
