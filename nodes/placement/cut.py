"""The ``cut`` node: an aggregate minus a half-space or a sphere, so a volume fill's inside shows — G's rice
bunny with a cut revealing the filled inside (G §4; SPEC §2.2: G fills the shape's volume, S only its surface).

Whole elements are kept or removed by their centre (no element is sliced): the cut face shows the grains as
they lie inside, which is what G's cut view is for.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param

from ..values import Aggregate

KINDS = ("plane", "sphere")


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


@node(
    "cut",
    version=1,
    inputs={"aggregate": In(Aggregate, "placed or simulated elements (a volume fill)")},
    outputs={"aggregate": Out(Aggregate, "the elements whose centres lie outside the removed region")},
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
    },
)
def cut(ctx, aggregate, *, kind, normal, offset, center, radius):
    """Keep whole elements by their centre (``cut_mask``); per-element deformations and bends go with them."""
    keep = cut_mask(aggregate.placement.positions, kind, normal, offset, center, radius)
    if not keep.any():
        raise ValueError(f"the {kind} cut removes every element; move it (offset, center) or shrink it (radius)")
    if hasattr(aggregate, "subset"):  # an aggregate with per-vertex state (flattened contacts, yolk offsets)
        return aggregate.subset(keep)
    per_element = {
        name: getattr(aggregate, name)[keep]
        for name in ("deformations", "bends")
        if getattr(aggregate, name) is not None
    }
    return dataclasses.replace(aggregate, placement=aggregate.placement.subset(keep), **per_element)
