"""Our preview beside Blender's Cycles render of the same exported .glb, under the same camera and light
(issue 26: do the two renderers agree about the same materials?).

    python tools/blender_side_by_side.py graphs/ikura_don.yaml [--draft] [--set NODE.PARAM=VALUE] [--samples N]

Runs the recipe (from the cache where it can) for its .glb and preview, then renders the .glb with Blender
Cycles (the ``bpy`` venv ``tools/make_blender_venv.sh`` makes: ``$NODEGRAPH_BLENDER_PYTHON`` or
``.venv-blender/bin/python``; tools/blender_render_glb.py) at the preview's size in the preview's studio: its
camera and lens, softbox key, fill, rim light, ambient, seamless backdrop, glints' core and exposure, as numbers
from ``nodes.export.mitsuba_scene.studio_description`` (one description, not a copy), and writes the two side by
side, captioned with their render times. Without the Blender venv it says so and stops.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image as PILImage  # here, not in a thread: see below

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported
# the recipe's export (USD: pxr) and preview (the table's texture: PIL) run in threads side by side, each importing
# its extension module the first time; two such first imports at once hung the tool (every thread waiting, no CPU)
from pxr import Usd  # noqa: E402, F401

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "tools" / "blender_render_glb.py"


def blender_python() -> Path:
    path = Path(os.environ.get("NODEGRAPH_BLENDER_PYTHON", REPO / ".venv-blender" / "bin" / "python"))
    if not path.exists():
        sys.exit(f"no Blender venv at {path}: make it with tools/make_blender_venv.sh")
    return path


def settings(scene, preview_params: dict, samples: int) -> dict:
    """The Blender render's camera, lens, studio and exposure: the preview's own (``mitsuba_scene.studio_description``
    of the shaded scene, fitted and lit as the preview fits and lights it), and the Cycles samples."""
    from nodes.export import mitsuba_scene as ms

    p = preview_params
    camera = ms.Camera(
        p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"], tuple(p.get("offset", (0.0, 0.0)))
    )
    return {
        **ms.studio_description(
            scene, camera, p["width"], p["height"], p["sun_direction"], p["ambient"], p.get("setting", "sweep")
        ),
        "samples": samples,
    }


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("recipe", type=Path)
    parser.add_argument("--draft", action="store_true", help="the recipe's draft (small scene and preview)")
    parser.add_argument("--set", action="append", default=[], metavar="NODE.PARAM=VALUE", help="as nodegraph run")
    parser.add_argument("--samples", type=int, default=64, help="Cycles samples (denoised with OIDN)")
    parser.add_argument(
        "--out", type=Path, default=None, help="the PNG (default outputs/<recipe>/blender_side_by_side.png)"
    )
    args = parser.parse_args()
    python = blender_python()

    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodegraph.contact_sheet import grid_pixels
    from nodegraph.output_files import write_output
    from nodegraph.values import Image

    recipe = load_recipe(args.recipe, default_registry(), args.set, draft=args.draft)
    out_dir = REPO / "outputs" / f"{recipe.name}{'_draft' if args.draft else ''}"
    start = time.perf_counter()
    result = run_recipe(
        recipe,
        outputs=["export.files", "preview.image", "shade.scene"],
        cache=Cache(default_cache_dir()),
        out_dir=out_dir,
    )
    ours_seconds = time.perf_counter() - start
    glb = next(out_dir.glob("*.glb"))
    ours = result.output("preview.image").pixels
    with tempfile.TemporaryDirectory(prefix="blender-side-") as tmp:
        settings_path, render = Path(tmp) / "settings.json", Path(tmp) / "cycles.png"
        description = settings(result.output("shade.scene"), recipe.nodes["preview"].params, args.samples)
        if "texture" in description["backdrop"]:  # the table's boards, as the preview renders them
            from nodes.export.studio import wood_png

            description["backdrop"]["texture"] = str(wood_png(Path(tmp) / description["backdrop"]["texture"]))
        settings_path.write_text(json.dumps(description))
        start = time.perf_counter()
        done = subprocess.run(
            [str(python), str(SCRIPT), str(glb), str(settings_path), str(render)], capture_output=True, text=True
        )
        blender_seconds = time.perf_counter() - start
        if done.returncode or not render.exists():
            sys.exit(f"{glb}: Blender failed:\n{done.stderr[-3000:]}")
        theirs = np.asarray(PILImage.open(render).convert("RGB"))
    labels = [
        f"nodegraph preview (Mitsuba, {recipe.nodes['preview'].params['samples']} spp + OIDN)",
        f"Blender 4.5 Cycles, {args.samples} spp + OIDN ({blender_seconds:.0f} s with import)",
    ]
    pixels = grid_pixels([ours, theirs], 2, labels, 8, max(16, ours.shape[0] // 12))
    out = args.out or out_dir / "blender_side_by_side.png"
    write_output(Image(pixels), out.parent, out.stem)
    # each render alone, at the preview's size, for an image metric (/work/shared/tools/flip_compare.py)
    write_output(Image(ours), out.parent, f"{out.stem}_preview")
    write_output(Image(theirs), out.parent, f"{out.stem}_cycles")
    print(f"wrote {out} (ours {ours_seconds:.0f} s incl. the recipe, Blender {blender_seconds:.0f} s)")


if __name__ == "__main__":
    main()
