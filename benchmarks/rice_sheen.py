"""The rice of a full-size preview as cooked-rice appearance is graded by image analysis: over a window of rice, the
mean CIELAB, and the gloss as the Hokkaido agricultural station's method counts it (hro.or.jp, "画像解析による米飯の
白さ・つやの評価", 1999: mean luminance for whiteness; gloss area, the share of high-luminance pixels; gloss
intensity, their mean luminance), high meaning L* ≥ ``GLOSS_L``.

    python benchmarks/rice_sheen.py SCENE PREVIEW.png [SCENE PREVIEW.png ...]   # SCENE: rice_bowl, onigiri, ikura_don

For ikura_don it also prints the eggs' mean CIELAB hue and chroma (``eggs``): the eggs are lit through by the rice
under them, so a change to the rice must leave them as they are.
"""

from __future__ import annotations

import argparse

import numpy as np

# windows of rice only in each recipe's 1280 × 720 preview (x, y, width, height): the heap's lit front, the
# onigiri's lit top above its nori, the rice between the eggs and the bowl's left rim
WINDOWS = {"rice_bowl": (330, 200, 230, 170), "onigiri": (480, 70, 140, 90), "ikura_don": (110, 280, 70, 120)}
EGGS = (300, 150, 400, 250)  # ikura_don: a window of eggs; its pixels with a* > EGG_A are eggs
EGG_A = 25.0
GLOSS_L = 95.0  # L* from which a pixel counts as gloss: the highlights, above every lit grain's body


def sheen(scene: str, path: str) -> dict[str, float]:
    """Mean L*, a*, b* of the scene's rice window, its gloss area (%) and gloss intensity (mean L* there)."""
    from PIL import Image
    from skimage.color import rgb2lab

    x, y, w, h = WINDOWS[scene]
    pixels = np.asarray(Image.open(path).convert("RGB"), np.float64)[y : y + h, x : x + w] / 255.0
    lab = rgb2lab(pixels).reshape(-1, 3)
    high = lab[:, 0] >= GLOSS_L
    return {
        "L": round(float(lab[:, 0].mean()), 1),
        "a": round(float(lab[:, 1].mean()), 1),
        "b": round(float(lab[:, 2].mean()), 1),
        "gloss_area": round(100.0 * float(high.mean()), 2),
        "gloss_L": round(float(lab[high, 0].mean()), 1) if high.any() else None,
    }


def eggs(path: str) -> dict[str, float]:
    """Mean CIELAB hue (degrees) and chroma of the eggs in ikura_don's egg window."""
    from PIL import Image
    from skimage.color import rgb2lab

    x, y, w, h = EGGS
    lab = rgb2lab(np.asarray(Image.open(path).convert("RGB"), np.float64)[y : y + h, x : x + w] / 255.0).reshape(-1, 3)
    egg = lab[lab[:, 1] > EGG_A]
    hue = np.degrees(np.arctan2(egg[:, 2], egg[:, 1]))
    return {"hue": round(float(hue.mean()), 1), "chroma": round(float(np.hypot(egg[:, 1], egg[:, 2]).mean()), 1)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pairs", nargs="+", help="SCENE PREVIEW.png, repeated")
    args = parser.parse_args()
    for scene, path in zip(args.pairs[::2], args.pairs[1::2]):
        print(scene, path, sheen(scene, path), eggs(path) if scene == "ikura_don" else "")


if __name__ == "__main__":
    main()
