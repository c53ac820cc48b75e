"""The rice's silhouette seen from the preview camera, read from an exported .glb alone (issue 26: the onigiri reads
as a rounded triangle, not a dome).

    python tools/silhouette.py outputs/onigiri/onigiri.glb [--elevation 12] [--azimuth 0]

The grains' vertices (export with ``--set export.instancing=false``) projected orthographically along the camera's
view (``mitsuba_scene.look_at``'s axes); the silhouette's width at 25, 50 and 75 % of its height (the vertices
within 0.5 mm of each level). A triangle's are ¾, ½ and ¼ of its base: 75 % / 25 % = ⅓."""

from __future__ import annotations

import argparse

import numpy as np
from nori_cover import world_mm


def widths(path, elevation: float = 12.0, azimuth: float = 0.0) -> tuple[np.ndarray, float, np.ndarray]:
    """(the grains' extent along x, y, z in mm; the silhouette's height; its widths at 25 / 50 / 75 %)."""
    grains = np.concatenate([v for name, v in world_mm(path).items() if "/" in name])
    el, az = np.radians(elevation), np.radians(azimuth)
    view = np.array([np.sin(az) * np.cos(el), -np.cos(az) * np.cos(el), np.sin(el)])  # towards the camera
    right = np.cross(-view, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -view)
    across, height = grains @ right, grains @ up
    levels = height.min() + np.array([0.25, 0.5, 0.75]) * np.ptp(height)
    return (
        np.ptp(grains, axis=0),
        float(np.ptp(height)),
        np.array([np.ptp(across[np.abs(height - h) < 0.5]) for h in levels]),
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("glb", nargs="+")
    parser.add_argument("--elevation", type=float, default=12.0, help="the preview's camera elevation (degrees)")
    parser.add_argument("--azimuth", type=float, default=0.0, help="the preview's camera azimuth (degrees)")
    args = parser.parse_args()
    for path in args.glb:
        extent, tall, w = widths(path, args.elevation, args.azimuth)
        print(
            f"{path}: rice {extent[0]:.1f} wide (x), {extent[1]:.1f} thick (y), {extent[2]:.1f} tall (z); seen from "
            f"the camera {tall:.1f} tall, {w[0]:.1f} / {w[1]:.1f} / {w[2]:.1f} mm wide at 25 / 50 / 75 % of its "
            f"height, 75 % / 25 % = {w[2] / w[0]:.2f}"
        )
