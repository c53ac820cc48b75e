"""The ``nori`` node: a band of nori (dried seaweed) wrapped around the lower part of a shape — the onigiri's
sheet, folded under its flat side and up both faces (SPEC §2 scenery; issue 26: an onigiri reads as one by its
band). Given the settled grains, the sheet drapes over them rather than the mould they slumped out of."""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh
from nodes.values import Aggregate


@node(
    "nori",
    inputs={
        "shape": In(Mesh, "the closed shape the band wraps (the onigiri's mould): its faces along ±y"),
        "aggregate": In(
            Aggregate,
            "the grains as they rest: the sheet lies on them (a slumped onigiri is lower and wider than its mould)",
            optional=True,
        ),
    },
    outputs={"mesh": Out(Mesh, "the band: an open sheet named 'nori' (shade gives it the nori material)")},
    params={
        "width": Param(float, 30.0, "band width along x, centred on the shape", range=(0.1, 1e4), units="mm"),
        "height": Param(
            float,
            25.0,
            "how far up the faces the band reaches, from the shape's lowest point",
            range=(0.1, 1e4),
            units="mm",
        ),
        "gap": Param(float, 0.3, "distance of the sheet from the shape's surface", range=(0.0, 100.0), units="mm"),
        "columns": Param(int, 24, "faces across the band's width", range=(1, 1000)),
        "rows": Param(int, 64, "faces along the band, from one face's top edge round to the other's", range=(2, 4000)),
        "reach": Param(
            float,
            2.0,
            "with an aggregate: how far along the sheet a grain holds it up (its stiffness: it spans the grains' tops)",
            range=(0.0, 100.0),
            units="mm",
        ),
        "ribs": Param(
            float,
            0.0,
            "height of the sheet's fine ribbing (the lines of the mat it dried on), outwards; 0 = a smooth sheet",
            range=(0.0, 10.0),
            units="mm",
        ),
        "rib_period": Param(float, 1.6, "spacing of the ribs along the band", range=(0.01, 100.0), units="mm"),
    },
)
def nori(ctx, shape, aggregate=None, *, width, height, gap, columns, rows, reach, ribs, rib_period):
    """The shape's surface (or the grains on it) under a plane ``height`` above the shape's lowest point, in a
    strip ``width`` wide across x, ``gap`` outside it: a rectangular sheet folded round the shape's bottom."""
    from .solids import wrap_band

    drape = None if aggregate is None else band_points(aggregate, shape, width, reach)
    vertices, faces = wrap_band(
        shape.vertices, shape.faces, width, height, gap, columns, rows, drape, reach, ribs, rib_period
    )
    return Mesh(vertices, faces, name="nori")


def band_points(aggregate: Aggregate, shape: Mesh, width: float, reach: float):
    """The vertices of the elements that can reach the band's strip (its width about the shape's middle x, plus
    ``reach``), in world space."""
    import numpy as np

    middle = 0.5 * (shape.vertices[:, 0].min() + shape.vertices[:, 0].max())
    extent = max(np.linalg.norm(m.vertices, axis=1).max() for lib in aggregate.libraries for m in lib.meshes)
    near = np.flatnonzero(np.abs(aggregate.placement.positions[:, 0] - middle) <= 0.5 * width + reach + extent)
    if not len(near):
        return np.empty((0, 3))
    shapes = aggregate.without_normals()
    points = np.concatenate([shapes.element_mesh(int(i)).vertices for i in near])
    return points[np.abs(points[:, 0] - middle) <= 0.5 * width + reach]
