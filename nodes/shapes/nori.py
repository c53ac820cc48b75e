"""The ``nori`` node: a band of nori (dried seaweed) wrapped around the lower part of a shape — the onigiri's
sheet, folded under its flat side and up both faces (SPEC §2 scenery; issue 26: an onigiri reads as one by its
band)."""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh


@node(
    "nori",
    version=1,
    inputs={"shape": In(Mesh, "the closed shape the band wraps (the onigiri's mould): its faces along ±y")},
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
    },
)
def nori(ctx, shape, *, width, height, gap, columns, rows):
    """The shape's surface under a plane ``height`` above its lowest point, in a strip ``width`` wide across x,
    moved ``gap`` out along the surface normal: a rectangular sheet folded round the shape's bottom."""
    from .solids import wrap_band

    vertices, faces = wrap_band(shape.vertices, shape.faces, width, height, gap, columns, rows)
    return Mesh(vertices, faces, name="nori")
