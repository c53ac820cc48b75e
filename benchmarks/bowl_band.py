"""The bowl's lower band and the table in a recipe's final preview: FLIP (``flip-evaluator``, LDR) of the recipe's
preview against the same path tracer at many samples, over the frame, a window on the bowl's lower band and one
on the table.

    python benchmarks/bowl_band.py render RECIPE SPP OUT.npz [--cache-dir DIR]   # linear layers of the final preview
    python benchmarks/bowl_band.py compare REFERENCE.npz TEST.npz --band Y0 Y1 X0 X1 --table Y0 Y1 X0 X1 [--png DIR]

``render`` uses whatever ``nodes`` is on the path, so a checkout of another commit renders its own picture of the
same recipe (its cache apart); its CPU seconds are the render's (``time.process_time``). ``compare`` denoises both
with their own guides (``mitsuba_scene.denoise``) and prints one JSON object.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()


def render(recipe_path: str, spp: int, out: str, cache_dir: str | None) -> None:
    """The final (not draft) preview's layers of ``recipe_path`` at ``spp``, saved to ``out``."""
    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodes.export import mitsuba_scene as ms

    recipe = load_recipe(Path(recipe_path), default_registry(), [], draft=False)
    cache = Cache(Path(cache_dir) if cache_dir else default_cache_dir())
    scene = run_recipe(recipe, outputs=["shade.scene"], cache=cache).output("shade.scene")
    p = recipe.nodes["preview"].params
    camera = ms.Camera(p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"], tuple(p["offset"]))
    start = time.process_time()
    layers = ms.render_layers(
        scene,
        camera,
        p["width"],
        p["height"],
        spp,
        p["sun_direction"],
        subsurface=p["subsurface"],
        ambient=p["ambient"],
        setting=p["setting"],
    )
    cpu = time.process_time() - start
    denoise_start = time.process_time()
    ms.denoise(layers)
    cpu += time.process_time() - denoise_start
    arrays = {k: getattr(layers, k) for k in ("color", "albedo", "normal", "highlights")}
    np.savez(out, cpu=cpu, **arrays)
    print(json.dumps({"recipe": recipe_path, "spp": spp, "cpu_s": round(cpu, 1)}))


def picture(path: str) -> np.ndarray:
    """The denoised 8-bit sRGB picture of saved layers, as the preview draws it."""
    from nodes.export import mitsuba_scene as ms
    from nodes.export.mesh_files import linear_to_srgb8

    saved = np.load(path)
    layers = ms.Layers(saved["color"], saved["albedo"], saved["normal"], saved["highlights"])
    return linear_to_srgb8(ms.tone_map(layers.denoised()))


def compare(reference: str, test: str, band: list[int], table: list[int], png: str | None) -> None:
    """FLIP of ``test`` against ``reference`` over the frame and the two windows (rows y0:y1, columns x0:x1)."""
    import flip_evaluator as flip

    ref, image = picture(reference), picture(test)
    error, mean, _ = flip.evaluate(ref / 255.0, image / 255.0, "LDR")
    row = {"frame": round(float(mean), 4)}
    for name, (y0, y1, x0, x1) in (("band", band), ("table", table)):
        row[name] = round(float(error[y0:y1, x0:x1].mean()), 4)
    if png:
        from PIL import Image

        for name, pixels in (("reference", ref), ("test", image)):
            Image.fromarray(pixels).save(Path(png) / f"{Path(test).stem}_{name}.png")
    print(json.dumps(row))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="mode", required=True)
    r = sub.add_parser("render")
    r.add_argument("recipe")
    r.add_argument("spp", type=int)
    r.add_argument("out")
    r.add_argument("--cache-dir")
    c = sub.add_parser("compare")
    c.add_argument("reference")
    c.add_argument("test")
    c.add_argument("--band", type=int, nargs=4, required=True)
    c.add_argument("--table", type=int, nargs=4, required=True)
    c.add_argument("--png")
    args = parser.parse_args()
    if args.mode == "render":
        render(args.recipe, args.spp, args.out, args.cache_dir)
    else:
        compare(args.reference, args.test, args.band, args.table, args.png)


if __name__ == "__main__":
    main()
