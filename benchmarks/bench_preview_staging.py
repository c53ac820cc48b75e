"""The main job's preview alone, priced in CPU seconds: the old packshot against the table (issue 48).

    python benchmarks/bench_preview_staging.py [--size W H] [--samples N]
    python benchmarks/bench_preview_staging.py --quick   # a few grains and eggs in a bowl at 96 × 54, 1 sample

Runs graphs/ikura_don.yaml to its shaded scene (from the cache where it can), then renders it, media on, twice: as
the packshot (camera 50° up, fov 35°, the key (−0.45, −0.6, 0.75), the sweep) and as the recipe stages it (its
preview's elevation, azimuth, fov, key and setting).
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

from nodegraph import runtime

runtime.configure()

ROOT = Path(__file__).resolve().parents[1]


def cpu() -> float:
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--size", type=int, nargs=2, default=(1280, 720))
    parser.add_argument("--samples", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="a small food scene at 96 × 54, 1 sample (seconds)")
    args = parser.parse_args()
    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodes.export import mitsuba_scene as ms

    recipe = load_recipe(ROOT / "graphs" / "ikura_don.yaml", default_registry(), [])
    p = recipe.nodes["preview"].params
    if args.quick:
        from bench_preview import quick_scene

        scene = quick_scene()[0]
        args.size, args.samples = (96, 54), 1
    else:
        scene = run_recipe(recipe, outputs=["shade.scene"], cache=Cache(default_cache_dir())).output("shade.scene")
    stagings = {
        "packshot (50°, fov 35°, sweep)": (ms.Camera(50.0, 20.0, 35.0, 0.1, 5.6, 0.25), (-0.45, -0.6, 0.75), "sweep"),
        f"the recipe's ({p['elevation']:g}°, fov {p['fov']:g}°, {p['setting']})": (
            ms.Camera(
                p["elevation"],
                p["azimuth"],
                p["fov"],
                p["margin"],
                p["f_stop"],
                p["focus"],
                tuple(p.get("offset", (0.0, 0.0))),
            ),
            p["sun_direction"],
            p["setting"],
        ),
    }
    width, height = args.size
    for name, (camera, light, setting) in stagings.items():
        start, wall = cpu(), time.perf_counter()
        ms.render(scene, camera, width, height, args.samples, light, subsurface=True, setting=setting)
        print(f"{name}: {cpu() - start:.1f} CPU s, {time.perf_counter() - wall:.1f} s wall", flush=True)


if __name__ == "__main__":
    main()
