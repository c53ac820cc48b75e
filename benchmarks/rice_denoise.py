"""The preview's denoised rice against a converged render of the same scene: FLIP (NVIDIA's perceptual difference,
``flip-evaluator``, LDR) of the recipe's preview (3 spp + OIDN) against the preview's own path tracer at many
samples with no denoiser, on the main job's draft (640 × 360), and the mean sRGB of the rice.

    python benchmarks/rice_denoise.py [--spp 3] [--reference-spp 128] [--guides 1,4] [--out DIR]

The reference is rendered once per scene and kept in ``--out`` (``reference_<spp>.npy``, keyed by the scene's
materials), so variants of the denoiser are compared against the same converged picture. ``--guides``: guide passes
averaged into the denoiser's albedo and normal (``mitsuba_scene.GUIDE_PASSES``), each row also with OIDN's
``clean_aux``. The rice's pixels: those whose albedo guide is the cooked rice's (``guide_albedo``).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import time
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()

ROOT = Path(__file__).resolve().parents[1]
REFERENCE_GUIDE_PASSES = 8  # the reference's guides, for its denoised copy


def draft_scene():
    """The main job's draft: its shaded scene and the preview's parameters (from the cache)."""
    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodes.export.mitsuba_scene import Camera

    recipe = load_recipe(ROOT / "graphs" / "ikura_don.yaml", default_registry(), [], draft=True)
    result = run_recipe(recipe, outputs=["shade.scene"], cache=Cache(default_cache_dir()))
    p = recipe.nodes["preview"].params
    camera = Camera(p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"], tuple(p["offset"]))
    return result.output("shade.scene"), camera, p


def before(scene, ms):
    """``scene`` with the rice as it was before issue 48's rice: its wet radius (1.2, 0.9, 0.6) mm, and the glints'
    pass reflecting the key's core off a grain at the coat's weight, not the skin's (``gloss``)."""
    import dataclasses

    from nodes.shading import materials

    gloss = ms.gloss
    ms.gloss = lambda material, skin=False: gloss(material)
    water = None
    out = []
    for m in scene.materials:
        if m.name == "rice":
            t = (m.subsurface - 0.3) / 0.6  # rice_material: subsurface = 0.3 + 0.6 t
            water = t * materials.WATER_MAX
            m = dataclasses.replace(m, subsurface_radius=materials._mix((0.3, 0.2, 0.1), (1.2, 0.9, 0.6), t))
        out.append(m)
    print(f"before: rice at {water:.1f} % water", flush=True)
    return dataclasses.replace(scene, materials=out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=3)
    ap.add_argument("--reference-spp", type=int, default=128)
    ap.add_argument("--guides", default="1", help="comma-separated guide passes to try")
    ap.add_argument("--out", type=Path, default=Path("/tmp/rice_denoise"))
    ap.add_argument(
        "--before",
        action="store_true",
        help="the rice as it was: radius (1.2, 0.9, 0.6) wet, glints at the coat's weight",
    )
    ap.add_argument("--tag", default="", help="names the reference (what the scene's materials do not say)")
    a = ap.parse_args()
    import flip_evaluator as flip
    from PIL import Image

    from nodes.export import mitsuba_scene as ms
    from nodes.export.mesh_files import linear_to_srgb8

    scene, camera, p = draft_scene()
    if a.before:
        scene = before(scene, ms)
    w, h, sun = p["width"], p["height"], p["sun_direction"]
    common = dict(subsurface=p["subsurface"], ambient=p["ambient"], setting=p["setting"])
    a.out.mkdir(parents=True, exist_ok=True)
    key = hashlib.sha1(repr(sorted((m.name, repr(m)) for m in scene.materials)).encode()).hexdigest()[:10]
    key = f"{key}_{a.tag}" if a.tag else key
    cached = a.out / f"reference_{a.reference_spp}_{key}.npz"
    if not cached.exists():
        t = time.perf_counter()
        ms.GUIDE_PASSES = REFERENCE_GUIDE_PASSES
        truth = ms.render_layers(scene, camera, w, h, a.reference_spp, sun, 1, **common)
        np.savez(cached, **{f: getattr(truth, f) for f in ("color", "albedo", "normal", "highlights")})
        print(f"reference {a.reference_spp} spp: {time.perf_counter() - t:.0f} s wall", flush=True)
    truth = ms.Layers(**dict(np.load(cached)))
    references = {
        "noisy": linear_to_srgb8(ms.tone_map(truth.noisy())),
        "denoised": linear_to_srgb8(ms.tone_map(truth.denoised())),
    }
    for name, image in references.items():
        Image.fromarray(image).save(a.out / f"reference_{name}_{key}.png")
    rice = next(m for m in scene.materials if m.name == "rice")
    print(f"rice radius {rice.subsurface_radius}", flush=True)
    mask = np.all(np.abs(truth.albedo - np.asarray(ms.guide_albedo(rice), np.float32)) < 1e-3, axis=-1)
    rows = []
    for passes in (int(v) for v in a.guides.split(",")):
        ms.GUIDE_PASSES = passes
        t = time.perf_counter()
        layers = ms.render_layers(scene, camera, w, h, a.spp, sun, 0, **common)
        seconds = time.perf_counter() - t
        for clean in (False, True):
            ms.CLEAN_AUX = clean
            image = linear_to_srgb8(ms.tone_map(layers.denoised()))
            Image.fromarray(image).save(a.out / f"preview_{key}_g{passes}_clean{int(clean)}.png")
            row = {"guide_passes": passes, "clean_aux": clean}
            for name, reference in references.items():
                err, mean, _ = flip.evaluate(reference / 255.0, image / 255.0, "LDR")
                err = np.asarray(err)
                row[f"flip_{name}"] = round(float(mean), 4)
                row[f"flip_{name}_rice"] = round(float(err[mask].mean()), 4)
                row[f"rice_srgb_{name}_reference"] = np.round(reference[mask].mean(axis=0)).astype(int).tolist()
            row |= {
                "rice_srgb": np.round(image[mask].mean(axis=0)).astype(int).tolist(),
                "layers_wall_s": round(seconds, 1),
                "scene": key,
            }
            rows.append(row)
            print(json.dumps(row), flush=True)
    ms.CLEAN_AUX, ms.GUIDE_PASSES = False, 1


if __name__ == "__main__":
    main()
