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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("path")
    ap.add_argument("--vessel", default="bowl", help="name prefix of the vessel's mesh in the file")
    ap.add_argument("--elements", default="japonica", help="name prefix of the elements' meshes")
    args = ap.parse_args()
    meshes = trimesh.load(args.path).dump(concatenate=False)
    named = [(m.metadata.get("name", ""), m) for m in meshes]
    vessel = next(m for n, m in named if n.startswith(args.vessel))
    elements = [m for n, m in named if n.startswith(args.elements)]
    vv, vf = np.asarray(vessel.vertices, float), np.asarray(vessel.faces, np.int64)
    points = np.vstack([m.vertices for m in elements])
    owner = np.repeat(np.arange(len(elements)), [len(m.vertices) for m in elements])
    depth = -igl.signed_distance(points, vv, vf)[0]  # > 0 inside the vessel's solid (y up, as glTF)
    centres = np.array([m.vertices.mean(axis=0) for m in elements])
    rim = np.hypot(vv[:, 0], vv[:, 2]).max()
    over = int((np.hypot(centres[:, 0], centres[:, 2]) > rim - 0.003).sum())
    print(
        f"{len(elements)} elements; with a vertex in the vessel's solid: {len(np.unique(owner[depth > 0]))}, deepest "
        f"{max(0.0, float(depth.max())) * 1000:.3f} mm; centres within 3 mm of the rim's radius or beyond: {over}"
    )


if __name__ == "__main__":
    main()
