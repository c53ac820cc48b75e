"""The kakigori's preview alone (640 × 480, 8 spp, from its cached shaded scene), with the ice a scattering medium
(``on``, the preview's default) or the thin diffuser (``off``): the medium's price, timed as whole processes
(docs/look.md, "Light under the skin of shaved ice"):

    farm-bench -n 3 --vs "python benchmarks/kakigori_preview.py off" -- python benchmarks/kakigori_preview.py on

``--cache-dir DIR``: the node cache to take the shaded scene from (default: nodegraph's); the first run fills it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from nodegraph import runtime

runtime.configure()  # numba's kernel cache and locator, before a kernel module is imported

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("media", choices=["on", "off"], help="ice as a medium (on) or a thin diffuser (off)")
    parser.add_argument("--cache-dir", type=Path, default=None)
    args = parser.parse_args()

    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe
    from nodes.export import mitsuba_scene as ms

    recipe = load_recipe(ROOT / "graphs" / "kakigori.yaml", default_registry(), [])
    cache = Cache(args.cache_dir or default_cache_dir())
    scene = run_recipe(recipe, outputs=["shade.scene"], cache=cache).output("shade.scene")
    p = recipe.nodes["preview"].params
    camera = ms.Camera(
        p["elevation"], p["azimuth"], p["fov"], p["margin"], p["f_stop"], p["focus"], tuple(p.get("offset", (0.0, 0.0)))
    )
    ms.render(scene, camera, 640, 480, 8, p["sun_direction"], subsurface=args.media == "on", ambient=p["ambient"])


if __name__ == "__main__":
    main()
