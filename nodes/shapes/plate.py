"""The ``plate`` node: a round plate under the shape set on it, sized by that shape — SPEC §2 scenery.

A plate stated in millimetres stays the size it was written for: ``--set onigiri.size=30`` left a 30 mm onigiri
on a 170 mm plate. Stated as shares of the shape it holds (its rim radius a multiple of the shape's plan radius,
its rim and thickness shares of that radius, its well a gap under the shape's lowest point), it follows the shape
as a ``vessel_region`` follows its bowl.
"""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh

from ..values import Aggregate


def _check(params: dict) -> list[tuple[str, str]]:
    """The shape set on the plate stands in its flat well: the well's radius (size × well plan radii) holds it."""
    if params["size"] * params["well"] < 1.0:
        return [
            (
                "size",
                f"a plate {params['size']:g} plan radii across with a well {params['well']:g} of that is narrower "
                f"than the shape set on it; allowed: size ≥ {1.0 / params['well']:.3g} (size × well ≥ 1)",
            )
        ]
    return []


@node(
    "plate",
    inputs={
        "shape": In(Mesh, "what is set on the plate: the plate is centred under it and sized by it"),
        "rests": In(
            Aggregate,
            "the elements set on it, where they stand out of the shape's bottom (grains placed on its surface): "
            "the well goes `gap` under their lowest vertex instead of the shape's",
            optional=True,
        ),
    },
    outputs={"mesh": Out(Mesh, "the plate, closed, the top of its flat well `gap` under the shape's lowest point")},
    params={
        "size": Param(
            float,
            1.9,
            "rim radius as a multiple of the shape's plan radius (its farthest point from its middle, seen from above)",
            range=(1.0, 100.0),
        ),
        "depth": Param(float, 0.12, "rim height above the well, as a share of the rim radius", range=(0.001, 1.0)),
        "wall": Param(float, 0.06, "the plate's thickness, as a share of the rim radius", range=(0.001, 0.5)),
        "well": Param(float, 0.6, "radius of its flat well as a share of the rim radius", range=(0.05, 0.95)),
        "gap": Param(
            float, 0.5, "the well's top under the shape's lowest point (it lands on it)", range=(0.0, 1e3), units="mm"
        ),
        "resolution": Param(int, 4, "mesh resolution level: 12·2^(level−1) segments", range=(1, 7)),
    },
    check=_check,
)
def plate(ctx, shape, rests=None, *, size, depth, wall, well, gap, resolution):
    """A plate (``solids.plate``) centred under ``shape``, its rim radius ``size`` × the shape's plan radius, its
    well under the shape's lowest point or, given ``rests``, its elements' (they rest on it: none through it)."""
    from . import solids

    lo, hi = shape.vertices.min(axis=0), shape.vertices.max(axis=0)
    if rests is not None and len(rests.placement):
        lo[2] = min(float(rests.element_mesh(i).vertices[:, 2].min()) for i in range(len(rests.placement)))
    middle = 0.5 * (lo + hi)
    radius = size * float(np.hypot(*(shape.vertices[:, :2] - middle[:2]).T).max())
    mesh = solids.plate(
        radius,
        depth * radius,
        wall * radius,
        well,
        segments=12 * 2 ** (resolution - 1),
        rings=max(4, 2**resolution),
    )
    mesh.apply_translation((middle[0], middle[1], lo[2] - gap))
    return Mesh.from_trimesh(mesh, name="plate")
