"""Our preview beside Blender's Cycles render of the same exported .glb, under the same camera and light
(issue 26: do the two renderers agree about the same materials?).

    python tools/blender_side_by_side.py graphs/ikura_don.yaml [--draft] [--set NODE.PARAM=VALUE] [--samples N]

Runs the recipe (from the cache where it can) for its .glb and preview, then renders the .glb with Blender
Cycles (the ``bpy`` venv ``tools/make_blender_venv.sh`` makes: ``$NODEGRAPH_BLENDER_PYTHON`` or
``.venv-blender/bin/python``; tools/blender_render_glb.py) at the preview's size in the preview's studio: its
camera and lens, softbox key, fill, rim light, ambient, seamless backdrop, glints' core and exposure, as numbers
from ``nodes.export.mitsuba_scene.studio_description`` (one description, not a copy), and writes the two side by
side, captioned with their render times. It says each stage as it starts (the recipe, Blender's render with its
progress, the picture) and where each file goes. Without the Blender venv, or with one that has no bpy, it says so,
and how to make one, before anything runs (exit status 2).
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


MAKE_VENV = "bash tools/make_blender_venv.sh   (CPython 3.11 and bpy 4.5 from PyPI; a few minutes)"
PROGRESS_EVERY = 10.0  # seconds between two lines of Blender's progress


def say(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def blender_python() -> Path:
    """The Blender venv's Python, checked to hold bpy; else a message saying where it looked and how to make one,
    and exit status 2, before anything runs."""
    given = os.environ.get("NODEGRAPH_BLENDER_PYTHON")
    path = Path(given) if given else REPO / ".venv-blender" / "bin" / "python"
    where = "$NODEGRAPH_BLENDER_PYTHON" if given else "the default place"
    if not path.exists():
        say(
            f"error: no Blender venv: {path} ({where}) does not exist. This tool renders with Blender's Python "
            f"module (bpy), in a venv of its own (bpy pins numpy 1.26). Make it with:\n  {MAKE_VENV}\n"
            "or point $NODEGRAPH_BLENDER_PYTHON at the Python of a venv that has bpy."
        )
        sys.exit(2)
    probe = "import importlib.util, sys; sys.exit(importlib.util.find_spec('bpy') is None)"
    if subprocess.run([str(path), "-c", probe], capture_output=True).returncode:
        say(f"error: {path} ({where}) has no bpy (Blender's Python module). Make the venv with:\n  {MAKE_VENV}")
        sys.exit(2)
    return path


def render_with_blender(python: Path, glb: Path, settings_path: Path, render: Path) -> float:
    """Blender's render, its progress said every ``PROGRESS_EVERY`` s (its own 'Sample k/N' lines); the seconds it
    took. A failure exits with the tail of what Blender said."""
    start = last = time.perf_counter()
    tail: list[str] = []
    with subprocess.Popen(
        [str(python), str(SCRIPT), str(glb), str(settings_path), str(render)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    ) as blender:
        for line in blender.stdout:
            tail = (tail + [line.rstrip()])[-40:]
            now = time.perf_counter()
            if now - last >= PROGRESS_EVERY:
                sample = next((part.strip() for part in line.split("|") if "Sample" in part), None)
                say(f"  Blender, {now - start:.0f} s: {sample or 'importing and building the scene'}")
                last = now
    if blender.returncode or not render.exists():
        say(f"error: Blender failed rendering {glb} (exit status {blender.returncode}); what it said last:")
        say("\n".join(tail))
        sys.exit(1)
    return time.perf_counter() - start


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

    from rich.console import Console

    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodegraph.contact_sheet import grid_pixels
    from nodegraph.output_files import write_output
    from nodegraph.output_folder import recipe_folder, settings_folder
    from nodegraph.report import Reporter
    from nodegraph.values import Image

    recipe = load_recipe(args.recipe, default_registry(), args.set, draft=args.draft)
    out_dir = settings_folder(recipe_folder(args.recipe, recipe.name, args.draft), args.set)
    out = args.out or out_dir / "blender_side_by_side.png"
    say(f"1/3 running {args.recipe} for its .glb and preview (what is cached loads in seconds) into {out_dir}/")
    start = time.perf_counter()
    result = run_recipe(
        recipe,
        outputs=["export.files", "preview.image", "shade.scene"],
        cache=Cache(default_cache_dir()),
        out_dir=out_dir,
        reporter=Reporter(console=Console(stderr=True, highlight=False)),
    )
    ours_seconds = time.perf_counter() - start
    glb = next(out_dir.glob("*.glb"))
    ours = result.output("preview.image").pixels
    height, width = ours.shape[:2]
    say(
        f"2/3 rendering {glb} with Blender Cycles at {width} × {height}, {args.samples} samples, in the preview's "
        f"studio: minutes (17–32 min at 1280 × 720 and 16 samples on 2 cores, 4.5 min at 640 × 360; docs/look.md); its "
        f"progress every {PROGRESS_EVERY:.0f} s"
    )
    with tempfile.TemporaryDirectory(prefix="blender-side-") as tmp:
        settings_path, render = Path(tmp) / "settings.json", Path(tmp) / "cycles.png"
        description = settings(result.output("shade.scene"), recipe.nodes["preview"].params, args.samples)
        if "texture" in description["backdrop"]:  # the table's boards, as the preview renders them
            from nodes.export.studio import wood_png

            description["backdrop"]["texture"] = str(wood_png(Path(tmp) / description["backdrop"]["texture"]))
        settings_path.write_text(json.dumps(description))
        blender_seconds = render_with_blender(python, glb, settings_path, render)

        theirs = np.asarray(PILImage.open(render).convert("RGB"))
    labels = [
        f"nodegraph preview (Mitsuba, {recipe.nodes['preview'].params['samples']} spp + OIDN)",
        f"Blender 4.5 Cycles, {args.samples} spp + OIDN ({blender_seconds:.0f} s with import)",
    ]
    say(f"3/3 writing the two side by side (Blender took {blender_seconds:.0f} s)")
    pixels = grid_pixels([ours, theirs], 2, labels, 8, max(16, ours.shape[0] // 12))
    write_output(Image(pixels), out.parent, out.stem)
    # each render alone, at the preview's size, for an image metric (/work/shared/tools/flip_compare.py)
    write_output(Image(ours), out.parent, f"{out.stem}_preview")
    write_output(Image(theirs), out.parent, f"{out.stem}_cycles")
    print(
        f"wrote {out} (ours {ours_seconds:.0f} s with the recipe, Blender {blender_seconds:.0f} s), and each alone: "
        f"{out.parent / (out.stem + '_preview.png')}, {out.parent / (out.stem + '_cycles.png')}"
    )


if __name__ == "__main__":
    main()
