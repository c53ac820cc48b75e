"""Grain vertices beyond the nori sheet, read from an exported .glb alone (issue 26: nothing pokes through the band).

    python tools/nori_cover.py outputs/onigiri/onigiri.glb

For each grain vertex in the band's strip (its x range less 1 mm, above the grains' lowest millimetre, 3 mm under
the band's top edge), its distance from the band's axis (the y middle and the top edge of the sheet, in the y–z
plane) against that of the sheet's nearest vertex in (x, angle): > 0 is a vertex through the sheet."""

from __future__ import annotations

import sys

import numpy as np
import trimesh
from scipy.spatial import cKDTree


def world_mm(path) -> dict[str, np.ndarray]:
    """Every node's vertices in our Z-up millimetres (the .glb is glTF's Y-up metres)."""
    scene = trimesh.load(path)
    out = {}
    for name in scene.graph.nodes_geometry:
        transform, geometry = scene.graph[name]
        x, y_up, z = trimesh.transform_points(scene.geometry[geometry].vertices, transform).T
        out[name] = 1e3 * np.column_stack([x, -z, y_up])
    return out


def beyond_sheet(path) -> tuple[int, np.ndarray]:
    world = world_mm(path)
    nori = world["nori"]
    grains = np.concatenate([v for name, v in world.items() if "/" in name])
    centre = np.array([0.5 * (nori[:, 1].min() + nori[:, 1].max()), nori[:, 2].max()])
    x0, x1 = nori[:, 0].min() + 1.0, nori[:, 0].max() - 1.0
    lowest = grains[:, 2].min()
    strip = grains[
        (grains[:, 0] > x0) & (grains[:, 0] < x1) & (grains[:, 2] < centre[1] - 3.0) & (grains[:, 2] > lowest + 1.0)
    ]

    def polar(points):
        rel = points[:, 1:] - centre
        return np.arctan2(rel[:, 1], rel[:, 0]), np.hypot(rel[:, 0], rel[:, 1])

    sheet_angle, sheet_radius = polar(nori)
    angle, radius = polar(strip)
    nearest = cKDTree(np.column_stack([nori[:, 0], 30.0 * sheet_angle])).query(
        np.column_stack([strip[:, 0], 30.0 * angle])
    )[1]
    return len(strip), radius - sheet_radius[nearest]


if __name__ == "__main__":
    for path in sys.argv[1:]:
        count, beyond = beyond_sheet(path)
        print(
            f"{path}: {count:,} grain vertices in the band's strip, {(beyond > 0).sum():,} beyond the sheet "
            f"(the nearest {-beyond.max():.2f} mm under it)"
        )
