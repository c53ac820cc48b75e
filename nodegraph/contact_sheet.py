"""Images side by side in a grid, a caption under each: the ``image_grid`` node's tiles and a sweep's contact
sheet of its previews, labelled with each point's parameter values."""

from __future__ import annotations

import numpy as np


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
