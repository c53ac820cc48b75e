"""Where the main job's eggs show their eyes, and whether each yolk stays inside its membrane (docs/look.md, "Ikura
colour").

    python benchmarks/ikura_eyes.py [RECIPE.yaml]

Runs the recipe to its shaded scene (from the cache where it can). Per egg: its eye axis, from the membrane's centre
through the oil droplet's (the yolk), against the direction to the preview's camera (its elevation and azimuth);
and the least distance from the yolk's vertices to the membrane's, negative where a yolk vertex lies outside the
skin along its own direction from the egg's centre.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from nodegraph import runtime

runtime.configure()


def main() -> None:
    from nodegraph.api import Cache, default_cache_dir, default_registry, load_recipe, run_recipe

    path = Path(sys.argv[1] if len(sys.argv) > 1 else "graphs/ikura_don.yaml")
    recipe = load_recipe(path, default_registry(), [])
    scene = run_recipe(recipe, outputs=["shade.scene"], cache=Cache(default_cache_dir())).output("shade.scene")
    p = recipe.nodes["preview"].params
    el, az = np.radians(p.get("elevation", 40.0)), np.radians(p.get("azimuth", 20.0))
    view = np.array([np.sin(az) * np.cos(el), -np.cos(az) * np.cos(el), np.sin(el)])  # towards the camera
    eggs: dict[str, dict] = {}
    for mesh in scene.meshes:
        parts = mesh.name.split("/")
        if parts[0].startswith("ikura") and len(parts) == 3:
            eggs.setdefault(parts[1], {})[parts[2]] = mesh
    gaps, facing = [], []
    for egg in eggs.values():
        skin = egg["membrane"].vertices
        centre = skin.mean(axis=0)
        yolk = egg["yolk"].vertices - centre
        rim = skin - centre
        reach = np.linalg.norm(rim, axis=1)
        nearest = np.argmax((yolk / np.linalg.norm(yolk, axis=1)[:, None]) @ (rim / reach[:, None]).T, axis=1)
        inside = np.linalg.norm(yolk, axis=1) < reach[nearest]
        least = float(np.linalg.norm(yolk[:, None, :] - rim[None, :, :], axis=-1).min())
        gaps.append(least if inside.all() else -least)
        axis = egg["yolk"].vertices.mean(axis=0) - centre
        if np.linalg.norm(axis) > 1e-6:  # a concentric droplet has no eye
            facing.append(float(axis @ view / np.linalg.norm(axis)))
    gaps, facing = np.array(gaps), np.array(facing)
    print(
        f"eggs {len(eggs)}: yolk to skin, least {gaps.min():.3f} mm, p5 {np.percentile(gaps, 5):.3f}, median "
        f"{np.median(gaps):.3f}; yolks through their skin {int((gaps < 0).sum())}"
    )
    if len(facing):
        print(
            f"eyes {len(facing)}: within 60° of the camera's direction {np.mean(facing > 0.5):.2f}, on its side "
            f"{np.mean(facing > 0):.2f}"
        )


if __name__ == "__main__":
    main()
