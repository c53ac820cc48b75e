"""The ``image_grid`` node: images side by side in a grid, each with a caption — e.g. the water-content
series of G fig. 3.1.2.1 (``graphs/water_series.yaml``: the same rice at 0, 8, 16 and 24 %).

The engine writes an ``Image`` output as ``<node id>.png``.
"""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Image


def grid_pixels(images: list[np.ndarray], columns: int, labels: list[str], gap: int, label_height: int) -> np.ndarray:
    """uint8 RGB tiles of equal size in rows of ``columns``, on white, a caption under each (Pillow's font)."""
    if not images:
        raise ValueError("images: give at least one image")
    shapes = {image.shape[:2] for image in images}
    if len(shapes) != 1:
        raise ValueError(f"images: all tiles must have the same size, got {sorted(shapes)} (set the previews alike)")
    if labels and len(labels) != len(images):
        raise ValueError(f"labels: {len(labels)} given for {len(images)} images (one each, or none)")
    (h, w), n = shapes.pop(), len(images)
    columns = min(columns, n)
    rows = -(-n // columns)
    cell_h = h + (label_height if labels else 0)
    out = np.full((rows * cell_h + (rows + 1) * gap, columns * w + (columns + 1) * gap, 3), 255, np.uint8)
    for k, image in enumerate(images):
        r, c = divmod(k, columns)
        y, x = gap + r * (cell_h + gap), gap + c * (w + gap)
        out[y : y + h, x : x + w] = image[..., :3]
    if labels:
        from PIL import Image as PILImage
        from PIL import ImageDraw, ImageFont

        canvas = PILImage.fromarray(out)
        draw = ImageDraw.Draw(canvas)
        font = ImageFont.load_default(size=max(8, int(label_height * 0.6)))
        for k, label in enumerate(labels):
            r, c = divmod(k, columns)
            y, x = gap + r * (cell_h + gap) + h, gap + c * (w + gap)
            draw.text((x + w / 2, y + label_height / 2), label, fill=(40, 40, 40), font=font, anchor="mm")
        out = np.asarray(canvas)
    return out


@node(
    "image_grid",
    version=1,
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
