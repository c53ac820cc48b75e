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

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.params import Param

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


# at most the elements it is given (the cut takes some away)
@estimated_by(passes("aggregate"))
@node(
    "cut",
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
        from .islands import bridged, contact_graph, element_surfaces, supported

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
