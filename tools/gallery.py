"""README gallery images from the recipes' previews: ``outputs/<recipe>/<image>.png`` → ``docs/images/<recipe>.png``,
scaled to at most ``--width`` pixels wide (Lanczos) and written as optimised PNG so each stays small.

    nodegraph run graphs/ikura_don.yaml ... ; python tools/gallery.py [--width 960]
"""

from __future__ import annotations

import argparse
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
IMAGES = {
    "ikura_don": "preview.png",
    "rice_bowl": "preview.png",
    "onigiri": "preview.png",
    "rice_bunny": "preview.png",
    "water_series": "series.png",
}


def main():
    from PIL import Image

    parser = argparse.ArgumentParser()
    parser.add_argument("--width", type=int, default=960, help="largest width in pixels")
    parser.add_argument("--series-width", type=int, default=1600, help="largest width of the water series")
    args = parser.parse_args()
    out = REPO / "docs" / "images"
    for recipe, name in IMAGES.items():
        source = REPO / "outputs" / recipe / name
        if not source.exists():
            print(f"skip {recipe}: {source} missing (run graphs/{recipe}.yaml first)")
            continue
        image = Image.open(source).convert("RGB")
        width = args.series_width if recipe == "water_series" else args.width
        if image.width > width:
            image = image.resize((width, round(image.height * width / image.width)), Image.Resampling.LANCZOS)
        target = out / f"{recipe}.png"
        image.save(target, optimize=True)
        print(f"wrote {target} ({image.width}×{image.height}, {target.stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main()
