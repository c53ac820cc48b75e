"""README gallery: every recipe's preview with its element count and cold time, in one command.

    python tools/gallery.py --run            # run every recipe cold (fresh cache), then write the gallery
    python tools/gallery.py --run sushi kakigori     # some recipes only
    python tools/gallery.py                  # from outputs/<recipe>/ as the last runs left them

Each recipe runs at full size into ``outputs/<recipe>/`` with an empty node cache (numba's compiled kernels
are kept, so the time is the recipe's, not the compiler's); its wall time, the load average it ran under
and the element count of its ``measure`` table are kept in ``outputs/<recipe>/gallery.json``. Each preview
(``preview.png``; the rice bunny's cut view ``cut_preview.png``; the water series' ``series.png``) is then
scaled to at most ``--width`` pixels (Lanczos) and written as an optimised PNG to ``docs/images/``, and
``docs/images/gallery.md`` gets the Markdown table (picture, recipe) for the README; the counts and cold times are
the scene table's (``docs/performance.md``, from ``benchmarks/measured/scenes.jsonl``), not written twice.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
# recipe → (its preview images, the noun its count is in)
RECIPES = {
    "ikura_don": (("preview.png",), "elements"),
    "rice_bowl": (("preview.png",), "grains"),
    "onigiri": (("preview.png",), "grains"),
    "onigiri_cylinder": (("preview.png",), "grains"),
    "rice_bunny": (("preview.png", "cut_preview.png"), "grains"),
    "sushi": (("preview.png",), "grains"),
    "kakigori": (("preview.png",), "flakes"),
    "rice_chestnut": (("preview.png",), "elements"),
    "water_series": (("series.png",), "grains"),
}


def run_cold(recipe: str) -> dict:
    """Run the recipe at full size in a fresh node cache into outputs/<recipe>/; time, load and count."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    loaded = load_recipe(REPO / "graphs" / f"{recipe}.yaml", default_registry(), [])
    out = REPO / "outputs" / recipe
    with tempfile.TemporaryDirectory(prefix="gallery-") as tmp:
        start = time.perf_counter()
        result = run_recipe(loaded, cache=Cache(Path(tmp) / "cache"), out_dir=out, rrd=out / f"{recipe}.rrd")
        seconds = time.perf_counter() - start
    count = None
    if "measure" in loaded.nodes:
        count = int(result.output("measure.table").columns["elements"][0])
    info = {"cold_s": round(seconds, 1), "load": round(os.getloadavg()[0], 1), "count": count}
    (out / "gallery.json").write_text(json.dumps(info, indent=1) + "\n")
    return info


def compile_kernels(recipe: str) -> None:
    """A throw-away run of the recipe at a tiny preview, so numba's cache holds its kernels before timing."""
    from nodegraph.api import Cache, default_registry, load_recipe, run_recipe

    path = REPO / "graphs" / f"{recipe}.yaml"
    registry = default_registry()
    previews = [n for n, e in load_recipe(path, registry, []).nodes.items() if e.spec.type_name == "preview"]
    small = [f"{n}.{p}={v}" for n in previews for p, v in (("width", 32), ("height", 32), ("samples", 1))]
    with tempfile.TemporaryDirectory(prefix="gallery-compile-") as tmp:
        run_recipe(load_recipe(path, registry, small), cache=Cache(Path(tmp) / "cache"), out_dir=Path(tmp) / "out")


def publish(recipe: str, width: int, series_width: int) -> list[str]:
    """Scaled previews into docs/images/; the Markdown rows for them (empty if the recipe has not run)."""
    from PIL import Image

    images, _ = RECIPES[recipe]
    folder = REPO / "outputs" / recipe
    rows = []
    for name in images:
        source = folder / name
        if not source.exists():
            print(f"skip {recipe}/{name}: {source} missing (run graphs/{recipe}.yaml or gallery.py --run {recipe})")
            continue
        image = Image.open(source).convert("RGB")
        largest = series_width if recipe == "water_series" else width
        if image.width > largest:
            image = image.resize((largest, round(image.height * largest / image.width)), Image.Resampling.LANCZOS)
        stem = recipe if name in ("preview.png", "series.png") else f"{recipe}_{Path(name).stem}"
        target = REPO / "docs" / "images" / f"{stem}.png"
        image.save(target, optimize=True)
        print(f"wrote {target.relative_to(REPO)} ({image.width}×{image.height}, {target.stat().st_size // 1024} KiB)")
        view = "" if name in ("preview.png", "series.png") else f" ({Path(name).stem.replace('_', ' ')})"
        rows.append(f"| ![{recipe}{view}](images/{stem}.png) | `{recipe}.yaml`{view} |")
    return rows


# the counts and times are not written here: they are the scene table's (docs/performance.md), measured with their
# load and kept in benchmarks/measured/scenes.jsonl, so that the README, this gallery and the docs say one figure
SOURCE = (
    "Each recipe's elements and cold time, with the load they were measured under: "
    '[`docs/performance.md`](../performance.md), "Scene table" (`benchmarks/measured/scenes.jsonl`).'
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recipes", nargs="*", help=f"recipe names (default: all of {', '.join(RECIPES)})")
    parser.add_argument("--run", action="store_true", help="run each recipe cold first (minutes each on 2 cores)")
    parser.add_argument("--width", type=int, default=960, help="largest width in pixels")
    parser.add_argument("--series-width", type=int, default=1600, help="largest width of the water series")
    args = parser.parse_args(argv)
    unknown = [r for r in args.recipes if r not in RECIPES]
    if unknown:
        parser.error(f"unknown recipe(s) {', '.join(unknown)}; known: {', '.join(RECIPES)}")
    names = args.recipes or list(RECIPES)
    rows = []
    for recipe in names:
        if args.run:
            compile_kernels(recipe)
            info = run_cold(recipe)
            print(f"{recipe}: {info['cold_s']:.1f} s cold, load {info['load']:.1f}, count {info['count']}", flush=True)
        rows += publish(recipe, args.width, args.series_width)
    table = "\n".join(["| preview | recipe |", "|---|---|", *rows, "", SOURCE])
    (REPO / "docs" / "images" / "gallery.md").write_text(table + "\n")
    print(f"\n{table}\n\nwrote docs/images/gallery.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
