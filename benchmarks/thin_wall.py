"""Whether any grain ends outside a thin-walled bowl, read from the exported file alone (issue 46: "no grain through a
thin wall at any setting that check accepts"). Runs ``graphs/rice_bowl.yaml`` at full size for each wall thickness ×
speed clamp at the fewest substeps the solver accepts (3: at 2 it refuses, gravity alone moving a particle past what
2 iterations hold), exports the .glb, and counts the elements whose centre lies beyond the bowl's rim radius or below
its floor (trimesh; glTF's metres, y up). One JSON row per setting on stdout.

    python benchmarks/thin_wall.py [--walls 0.5,0.05] [--clamps 2,8] [--substeps 3]
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

ROOT = Path(__file__).resolve().parents[1]


def outside(glb: Path) -> tuple[int, list[tuple[str, float, float]]]:
    """The elements of ``glb`` (meshes named kind/index) and those whose centre is outside the bowl: beyond its rim
    radius from its axis, or below its lowest point (each: name, mm from the axis, mm above the floor)."""
    import trimesh

    meshes = trimesh.load(glb).dump()
    bowl = next(m for m in meshes if "bowl" in m.metadata.get("name", "").lower())
    low, high = bowl.bounds
    centre, rim = (low + high) / 2, max(high[0] - low[0], high[2] - low[2]) / 2
    elements = [m for m in meshes if "/" in m.metadata.get("name", "")]
    out = []
    for mesh in elements:
        p = mesh.vertices.mean(axis=0)
        distance = float(np.hypot(p[0] - centre[0], p[2] - centre[2]))
        if distance > rim or p[1] < low[1]:
            out.append((mesh.metadata["name"], round(distance * 1e3, 1), round(float(p[1] - low[1]) * 1e3, 1)))
    return len(elements), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--walls", default="0.5,0.05", help="bowl wall thicknesses, mm")
    parser.add_argument("--clamps", default="2,8", help="xpbd speed clamps, particle radii per substep")
    parser.add_argument("--substeps", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="thin-wall-") as folder:
        for wall in args.walls.split(","):
            for clamp in args.clamps.split(","):
                out = Path(folder) / f"{wall}-{clamp}"
                command = [sys.executable, "-m", "nodegraph.cli", "run", "graphs/rice_bowl.yaml", "--output", "export"]
                command += ["--set", f"bowl.wall={wall}", "--set", f"rice_sim.speed_clamp={clamp}"]
                command += ["--set", f"rice_sim.substeps={args.substeps}", "--out-dir", str(out), "--no-rrd", "-q"]
                command += ["--cache-dir", str(Path(folder) / "cache")]
                start = time.perf_counter()
                subprocess.run(command, cwd=ROOT, check=True)
                count, escaped = outside(out / "rice_bowl.glb")
                row = {"wall_mm": float(wall), "speed_clamp": float(clamp), "substeps": args.substeps}
                row |= {"elements": count, "outside": len(escaped), "first": escaped[:3]}
                row |= {"seconds": round(time.perf_counter() - start, 1), "load": round(os.getloadavg()[0], 1)}
                print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
