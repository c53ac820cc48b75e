"""How much of the preview's FLIP against Cycles is noise and how much is a different picture: FLIP (NVIDIA's
perceptual difference, LDR) of each renderer against itself at another seed, and of the two at many samples,
over the frame and over each region (eggs, rice, bowl, table and backdrop) of the main job's draft.

    python benchmarks/flip_floor.py [--spp 2] [--high-spp 64] [--cycles-spp 32] [--cycles-high-spp 128] [--out DIR]

Renders (kept in ``--out`` by name, so a rerun compares without rendering again): the preview at ``--spp`` with
seeds 0 and 1 and at ``--high-spp``, each denoised as the preview is; Cycles (``tools/blender_render_glb.py``, the
preview's studio, OIDN) at ``--cycles-spp`` with seeds 0 and 1 and at ``--cycles-high-spp``. Regions: each pixel's
material, from one sample a pixel of Mitsuba's shape index (the denoiser's guide pass).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np
from repo_tool import load_tool

from nodegraph import runtime

runtime.configure()

ROOT = Path(__file__).resolve().parents[1]
REGIONS = {"eggs": ("ikura",), "rice": ("rice",), "bowl": ("ceramic",)}  # material names start with these
OTHER = "table"  # every pixel no element covers: the table's boards and the studio behind


def draft(out: Path):
    """The main job's draft from the cache: its shaded scene, the preview node's parameters and its .glb."""
    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe

    recipe = load_recipe(ROOT / "graphs" / "ikura_don.yaml", default_registry(), [], draft=True)
    result = run_recipe(recipe, outputs=["export.files", "shade.scene"], cache=Cache(default_cache_dir()), out_dir=out)
    return result.output("shade.scene"), recipe.nodes["preview"].params, next(out.glob("*.glb"))


def camera_of(p: dict):
    from nodes.export.mitsuba_scene import Camera

    return Camera(
        p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"], tuple(p.get("offset", (0, 0)))
    )


def regions(scene, p: dict) -> np.ndarray:
    """Each pixel's region name (``REGIONS``, else ``OTHER``), from the shape hit by one sample a pixel."""
    import mitsuba as mi

    from nodes.export import mitsuba_scene as ms

    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory() as folder:
        description = ms.scene_dict(
            scene,
            Path(folder),
            camera_of(p),
            p["width"],
            p["height"],
            1,
            p["sun_direction"],
            subsurface=p["subsurface"],
            ambient=p["ambient"],
            setting=p["setting"],
        )
        loaded = mi.load_dict(description, optimize=False)
        index = mi.load_dict({"type": "aov", "aovs": "si:shape_index"})
        hit = np.rint(np.asarray(mi.render(loaded, integrator=index, seed=0, spp=1))[..., 0]).astype(int)
        keys = [shape.id() for shape in loaded.shapes()]
    names = np.full(len(keys) + 1, OTHER, dtype=object)
    for position, key in enumerate(keys):
        if key.startswith("shape_"):
            material = scene.materials[int(key.removeprefix("shape_"))].name
            names[position + 1] = next((r for r, stems in REGIONS.items() if material.startswith(stems)), OTHER)
    return names[np.clip(hit, 0, len(keys))]


def preview(scene, p: dict, spp: int, seed: int, path: Path) -> np.ndarray:
    """The preview at ``spp`` and ``seed``, denoised as the preview node does (kept at ``path``)."""
    from PIL import Image

    from nodes.export import mitsuba_scene as ms

    if not path.exists():
        image = ms.render(
            scene,
            camera_of(p),
            p["width"],
            p["height"],
            spp,
            p["sun_direction"],
            seed=seed,
            subsurface=p["subsurface"],
            ambient=p["ambient"],
            setting=p["setting"],
        )
        Image.fromarray(image).save(path)
        print(f"rendered {path}", flush=True)
    return np.asarray(Image.open(path).convert("RGB"))


def cycles(scene, p: dict, glb: Path, samples: int, seed: int, path: Path) -> np.ndarray:
    """Cycles' render of ``glb`` in the preview's studio at ``samples`` and ``seed`` (kept at ``path``)."""
    side = load_tool("blender_side_by_side")
    from PIL import Image

    if not path.exists():
        with tempfile.TemporaryDirectory(prefix="flip-floor-") as tmp:
            description = side.settings(scene, p, samples) | {"seed": seed}
            if "texture" in description["backdrop"]:
                from nodes.export.studio import wood_png

                description["backdrop"]["texture"] = str(wood_png(Path(tmp) / description["backdrop"]["texture"]))
            settings_path = Path(tmp) / "settings.json"
            settings_path.write_text(json.dumps(description))
            seconds = side.render_with_blender(side.blender_python(), glb, settings_path, path)
        print(f"rendered {path} ({seconds:.0f} s)", flush=True)
    return np.asarray(Image.open(path).convert("RGB"))


def compare(reference: np.ndarray, test: np.ndarray, region: np.ndarray) -> dict:
    """FLIP mean over the frame, its 95th percentile, and its mean over each region."""
    import flip_evaluator as flip

    # the error itself, not its magma colours (flip_evaluator's default), for the percentile and the regions
    err, mean, _ = flip.evaluate(reference / np.float32(255), test / np.float32(255), "LDR", applyMagma=False)
    err = np.asarray(err).reshape(reference.shape[:2])
    out = {"frame": round(float(mean), 4), "p95": round(float(np.percentile(err, 95)), 4)}
    for name in (*REGIONS, OTHER):
        out[name] = round(float(err[region == name].mean()), 4)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=2, help="the preview's samples (the draft's)")
    ap.add_argument("--high-spp", type=int, default=64)
    ap.add_argument("--cycles-spp", type=int, default=32)
    ap.add_argument("--cycles-high-spp", type=int, default=128)
    ap.add_argument("--tag", default="", help="names this build's previews in --out (Cycles reads only the file)")
    ap.add_argument("--out", type=Path, default=Path("/tmp/flip_floor"))
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    scene, p, glb = draft(a.out / "draft")
    region = regions(scene, p)
    shares = {name: round(float((region == name).mean()), 3) for name in (*REGIONS, OTHER)}
    print(json.dumps({"pixels": shares}), flush=True)
    t = f"_{a.tag}" if a.tag else ""
    ours = {seed: preview(scene, p, a.spp, seed, a.out / f"preview{t}_{a.spp}_s{seed}.png") for seed in (0, 1)}
    ours_high = preview(scene, p, a.high_spp, 0, a.out / f"preview{t}_{a.high_spp}_s0.png")
    theirs = {
        seed: cycles(scene, p, glb, a.cycles_spp, seed, a.out / f"cycles_{a.cycles_spp}_s{seed}.png") for seed in (0, 1)
    }
    theirs_high = cycles(scene, p, glb, a.cycles_high_spp, 0, a.out / f"cycles_{a.cycles_high_spp}_s0.png")
    pairs = {
        f"Cycles {a.cycles_spp} spp, seed 1 against seed 0": (theirs[0], theirs[1]),
        f"preview {a.spp} spp, seed 1 against seed 0": (ours[0], ours[1]),
        f"preview {a.spp} spp against Cycles {a.cycles_spp} spp": (theirs[0], ours[0]),
        f"preview {a.spp} spp against preview {a.high_spp} spp": (ours_high, ours[0]),
        f"Cycles {a.cycles_spp} spp against Cycles {a.cycles_high_spp} spp": (theirs_high, theirs[0]),
        f"preview {a.high_spp} spp against Cycles {a.cycles_high_spp} spp": (theirs_high, ours_high),
    }
    if a.cycles_high_spp == a.cycles_spp:  # no converged Cycles: the structural pair takes its seed 0
        del pairs[f"Cycles {a.cycles_spp} spp against Cycles {a.cycles_high_spp} spp"]
    for name, (reference, test) in pairs.items():
        print(json.dumps({"pair": name, **compare(reference, test, region)}), flush=True)


if __name__ == "__main__":
    main()
