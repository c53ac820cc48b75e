"""Grains against their vessel, from the exported file alone: how many elements reach into the vessel's solid (libigl
signed distance of every vertex to the vessel mesh) and how many sit at or over its rim.

    python tools/vessel_check.py outputs/ikura_don/ikura_don.glb [--vessel bowl] [--elements japonica]

The shared checkers (overlap, folds, skin, resting gap) look at elements against each other and a support; a grain
through a bowl's thin wall shows only here.
"""

from __future__ import annotations

import argparse

import igl
import numpy as np
import trimesh


def vessel_report(path, vessel: str = "bowl", elements: str = "japonica") -> dict:
    """The elements of the file at ``path`` against its vessel: how many (``elements``), how many reach into its
    solid (``in_solid``) and how deep (``deepest_mm``), how many centres lie within 3 mm of the rim's radius or
    beyond (``at_rim``), and how many lie outside it: beyond the rim's radius or below the vessel (``outside``)."""
    meshes = trimesh.load(path).dump(concatenate=False)
    named = [(m.metadata.get("name", ""), m) for m in meshes]
    vessel_mesh = next(m for n, m in named if n.startswith(vessel))
    parts = [m for n, m in named if n.startswith(elements)]
    vv, vf = np.asarray(vessel_mesh.vertices, float), np.asarray(vessel_mesh.faces, np.int64)
    points = np.vstack([m.vertices for m in parts])
    owner = np.repeat(np.arange(len(parts)), [len(m.vertices) for m in parts])
    depth = -igl.signed_distance(points, vv, vf)[0]  # > 0 inside the vessel's solid (y up, as glTF)
    centres = np.array([m.vertices.mean(axis=0) for m in parts])
    rim = np.hypot(vv[:, 0], vv[:, 2]).max()
    radius = np.hypot(centres[:, 0], centres[:, 2])
    return {
        "elements": len(parts),
        "in_solid": len(np.unique(owner[depth > 0])),
        "deepest_mm": max(0.0, float(depth.max())) * 1000,
        "at_rim": int((radius > rim - 0.003).sum()),
        "outside": int(((radius > rim) | (centres[:, 1] < vv[:, 1].min())).sum()),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("path")
    ap.add_argument("--vessel", default="bowl", help="name prefix of the vessel's mesh in the file")
    ap.add_argument("--elements", default="japonica", help="name prefix of the elements' meshes")
    args = ap.parse_args()
    r = vessel_report(args.path, args.vessel, args.elements)
    print(
        f"{r['elements']} elements; with a vertex in the vessel's solid: {r['in_solid']}, deepest "
        f"{r['deepest_mm']:.3f} mm; centres within 3 mm of the rim's radius or beyond: {r['at_rim']}; outside the "
        f"vessel: {r['outside']}"
    )


if __name__ == "__main__":
    main()
