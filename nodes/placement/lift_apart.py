"""The ``lift_apart`` node: elements placed at one spacing, lifted apart by each one's own size — SPEC §2.6.

A placement whose r comes from its elements spaces every point by the smallest of them (S §3.1.2), and the kinds and
variants are drawn only after (``mix_ratio``): where the variants differ much in size, two large ones drawn side by
side start deeply inside one another, and a simulation's contacts throw them apart, out of their bowl. This step
takes each element's bounding sphere (its outer part's: an egg's membrane), goes through the elements from the
lowest up, and lifts one (along +z, against gravity) just far enough that it overlaps none below it, nor a settled
particle it falls onto (``below``: a pile's, whose top a large element placed near it reached into), by more than
``overlap`` of the smaller radius; the lifted ones then fall onto the others. An element already within that is not
moved, and a placement with none beyond it is passed on unchanged (the same values, bit for bit).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Table

from ..values import Aggregate, ElementLibrary, ParticleState, Placement


def bounding_radii(libraries) -> list[np.ndarray]:
    """Per library, each mesh's bounding radius about its origin, over its outer part (part 0 of a mesh of several
    parts: an egg's membrane round its yolk)."""
    from .poisson_place import _outer_part

    radii = []
    for library in libraries:
        per_mesh = []
        for mesh in library.meshes:
            vertices, faces = _outer_part(mesh)
            used = np.asarray(vertices)[np.unique(np.asarray(faces))] if len(faces) else np.asarray(vertices)
            per_mesh.append(float(np.linalg.norm(used, axis=1).max()))
        radii.append(np.array(per_mesh))
    return radii


def lift_heights(
    positions: np.ndarray,
    radii: np.ndarray,
    share: float,
    fixed: np.ndarray | None = None,
    fixed_radii: np.ndarray | None = None,
) -> np.ndarray:
    """New heights (z) for spheres at ``positions`` of ``radii``: from the lowest up (ties by index), each is raised
    to the least height at which it overlaps none of those already settled, nor of the ``fixed`` spheres (settled
    from the start, never moved: the particles of a pile below), by more than ``share`` of the smaller radius; one
    already clear keeps its height exactly."""
    from scipy.spatial import cKDTree

    n = len(positions)
    z = positions[:, 2].copy()
    fixed = np.zeros((0, 3)) if fixed is None else np.asarray(fixed, np.float64)
    fixed_radii = np.zeros(0) if fixed_radii is None else np.asarray(fixed_radii, np.float64)
    if n == 0 or n + len(fixed) < 2:
        return z
    every = np.concatenate([positions, fixed])  # the fixed after the elements: index n + k
    sizes = np.concatenate([radii, fixed_radii])
    heights = np.concatenate([z, fixed[:, 2]])
    xy = every[:, :2]
    near = cKDTree(xy).query_ball_point(xy[:n], float(radii.max() + sizes.max()))
    settled = np.concatenate([np.zeros(n, bool), np.ones(len(fixed), bool)])
    for i in np.lexsort((np.arange(n), z)):
        others = np.asarray([j for j in near[i] if settled[j]], np.int64)
        settled[i] = True
        if not len(others):
            continue
        least = sizes[i] + sizes[others] - share * np.minimum(sizes[i], sizes[others])  # the closest allowed
        reach = least**2 - ((xy[others] - xy[i]) ** 2).sum(axis=1)
        keep = reach > 0.0
        if not keep.any():
            continue
        half = np.sqrt(reach[keep])
        lows, highs = heights[others[keep]] - half, heights[others[keep]] + half  # too deep in each between these
        height = z[i]
        inside = (lows < height) & (height < highs)
        while inside.any():  # raise it past every band it sits in, until it sits in none
            height = float(highs[inside].max())
            inside = (lows < height) & (height < highs)
        z[i] = heights[i] = height
    return z


@estimated_by(passes("placement"))
@node(
    "lift_apart",
    inputs={
        "placement": In(Placement, "mixed elements (kinds and variants drawn)"),
        "libraries": In(ElementLibrary, "element libraries in the placement's kind order", many=True),
        "below": In(
            ParticleState,
            "settled particles the elements fall onto (a simulation's, as its obstacles): none starts deeper in one",
            optional=True,
            many=True,
        ),
    },
    outputs={
        "placement": Out(Placement, "the elements, those too deep in one below lifted along +z"),
        "aggregate": Out(Aggregate, "placement with its libraries"),
        "stats": Out(Table, "elements lifted, the highest lift (mm), the deepest overlap share before and after"),
    },
    params={
        "overlap": Param(
            float,
            0.5,
            "the deepest overlap of two elements' bounding spheres left, as a share of the smaller one's radius "
            "(0: none touch)",
            range=(0.0, 1.0),
        ),
    },
)
def lift_apart(ctx, placement, libraries, below=None, *, overlap):
    """Lowest first, each element lifted (+z) until no element below overlaps it deeper than ``overlap`` × the
    smaller bounding radius; round elements are what a bounding sphere fits (an elongated grain is better served by
    ``overlap_refine`` and ``cull``)."""
    from .element_templates import matching_libraries, with_kind_names

    libraries = matching_libraries(placement, libraries)
    per_kind = bounding_radii(libraries)
    radii = (
        np.array([per_kind[k][v % len(per_kind[k])] for k, v in zip(placement.kinds, placement.variants)])
        if len(placement)
        else np.zeros(0)
    )
    before = _deepest_share(placement.positions, radii)
    below = list(below or [])
    fixed = np.concatenate([b.positions for b in below]) if below else None
    fixed_radii = np.concatenate([b.radii for b in below]) if below else None
    z = lift_heights(placement.positions, radii, overlap, fixed, fixed_radii)
    lift = z - placement.positions[:, 2]
    if np.any(lift > 0.0):
        positions = placement.positions.copy()
        positions[:, 2] = z
        # said nowhere but in ``stats``: a lift is this node doing its work, nothing a user need change
        placement = dataclasses.replace(with_kind_names(placement, libraries), positions=positions)
    stats = Table(
        {
            "lifted": np.array([int((lift > 0).sum())]),
            "max_lift": np.array([float(lift.max()) if len(lift) else 0.0]),
            "overlap_before": np.array([before]),
            "overlap_after": np.array([_deepest_share(placement.positions, radii)]),
        }
    )
    return {"placement": placement, "aggregate": Aggregate(placement, libraries), "stats": stats}


def _deepest_share(positions: np.ndarray, radii: np.ndarray) -> float:
    """The deepest overlap of two bounding spheres, as a share of the smaller radius (0 when none overlap)."""
    from scipy.spatial import cKDTree

    if len(positions) < 2:
        return 0.0
    pairs = cKDTree(positions).query_pairs(2.0 * float(radii.max()), output_type="ndarray")
    if not len(pairs):
        return 0.0
    i, j = pairs[:, 0], pairs[:, 1]
    depth = radii[i] + radii[j] - np.linalg.norm(positions[i] - positions[j], axis=1)
    return float(max(0.0, (depth / np.minimum(radii[i], radii[j])).max()))
