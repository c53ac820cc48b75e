"""Whether any grain ends outside a thin-walled bowl, read from the exported file alone (issue 46: "no grain through a
thin wall at any setting that check accepts"). Runs ``graphs/rice_bowl.yaml`` at full size for each wall thickness ×
speed clamp at the fewest substeps the solver accepts (3: at 2 it refuses, gravity alone moving a particle past what
2 iterations hold), exports the .glb, and reads it with ``tools/vessel_check.py``: the elements outside the bowl
(centre beyond its rim's radius or below it) and those reaching into its wall. One JSON row per setting on stdout.

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

from repo_tool import load_tool

ROOT = Path(__file__).resolve().parents[1]


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
                row = {"wall_mm": float(wall), "speed_clamp": float(clamp), "substeps": args.substeps}
                row |= load_tool("vessel_check").vessel_report(out / "rice_bowl.glb")
                row |= {"seconds": round(time.perf_counter() - start, 1), "load": round(os.getloadavg()[0], 1)}
                print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
