"""The ``image_grid`` node: images side by side in a grid, each with a caption — e.g. the water-content
series of G fig. 3.1.2.1 (``graphs/water_series.yaml``: the same rice at 0, 8, 16 and 24 %).

The engine writes an ``Image`` output as ``<node id>.png``.
"""

from __future__ import annotations

from nodegraph.contact_sheet import grid_pixels
from nodegraph.cost import Cost, estimated_by
from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Image


def _cost(q) -> Cost:
    """The most elements a tile shows (tiles of one scene shaded otherwise show the same ones); None when one is not
    known."""
    counts = [c.elements for c in q.inputs.get("images", [])]
    return Cost(elements=None if not counts or None in counts else max(counts))


@estimated_by(_cost)
@node(
    "image_grid",
    inputs={"images": In(Image, "tiles of one size, in order (e.g. previews)", many=True)},
    outputs={"image": Out(Image, "the tiles side by side, captioned")},
    params={
        "columns": Param(int, 4, "tiles per row", range=(1, 64)),
        "labels": Param(list[str], [], "one caption per tile, in order (none: no captions)"),
        "gap": Param(int, 8, "white space between tiles", range=(0, 256), units="px"),
        "label_height": Param(int, 40, "height of the caption strip under each tile", range=(8, 512), units="px"),
    },
)
def image_grid(ctx, images, *, columns, labels, gap, label_height):
    """Tiles side by side (rows of ``columns``) with a caption under each."""
    return Image(grid_pixels([image.pixels for image in images], columns, labels, gap, label_height))
