"""The Blender import table: each .glb / .usdc given, imported into Blender 4.5 with the nodegraph add-on —
objects, meshes drawn and the mesh data they share (fewer where instanced), vertices, material names, how many
materials transmit (and their IOR), how many scatter under the surface (weight, radius in mm), which alpha below 1
(see-through without refraction), import seconds and file size — as a Markdown table.

    python tools/blender_import_table.py outputs/ikura_don/ikura_don.glb outputs/ikura_don/ikura_don.usdc

Blender runs as the ``bpy`` module of the venv ``tools/make_blender_venv.sh`` makes (``$NODEGRAPH_BLENDER_PYTHON``
or ``.venv-blender/bin/python``), one fresh process per file (tests/export/blender_roundtrip.py).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "tests" / "export" / "blender_roundtrip.py"


def blender_python() -> Path:
    path = Path(os.environ.get("NODEGRAPH_BLENDER_PYTHON", REPO / ".venv-blender" / "bin" / "python"))
    if not path.exists():
        sys.exit(f"no Blender venv at {path}: make it with tools/make_blender_venv.sh")
    return path


def import_report(path: Path, addon: bool) -> dict:
    with tempfile.TemporaryDirectory(prefix="blender-import-") as tmp:
        report = Path(tmp) / "report.json"
        done = subprocess.run(
            [str(blender_python()), str(SCRIPT), str(path), str(report), "-"],
            capture_output=True,
            text=True,
            env={**os.environ, "NODEGRAPH_BLENDER_ADDON": "1" if addon else "0"},
        )
        if done.returncode:
            sys.exit(f"{path}: Blender failed:\n{done.stderr[-2000:]}")
        return json.loads(report.read_text())


def _radius_mm(material: dict) -> str:
    """Subsurface Radius × Subsurface Scale (Blender's metres) in millimetres, red / green / blue."""
    return " / ".join(f"{r * material['subsurface_scale'] * 1000:.2f}" for r in material["subsurface_radius"])


def row(path: Path, got: dict) -> str:
    materials = got["materials"].values()
    transmit = sorted({(round(m["transmission"], 2), round(m["ior"], 2)) for m in materials if m["transmission"] > 0})
    scatter = [f"{m['subsurface']:.2f}, radius {_radius_mm(m)} mm" for m in materials if m["subsurface"] > 0]
    see_through = sorted({round(m["alpha"], 2) for m in materials if m["alpha"] < 1})
    return (
        f"| {path.name} | {got['objects']:,} | {got['meshes']:,} | {got['mesh_data']:,} | {got['vertices']:,} | "
        f"{', '.join(sorted(got['materials']))} | "
        f"{sum(1 for m in materials if m['transmission'] > 0)} "
        f"({', '.join(f'{t} at IOR {i}' for t, i in transmit) or '—'}) | "
        f"{len(scatter)} ({', '.join(scatter) or '—'}) | {', '.join(map(str, see_through)) or '—'} | "
        f"{got['seconds']:.1f} | {path.stat().st_size / 2**20:.1f} |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+", type=Path, help=".glb or .usdc files")
    parser.add_argument("--no-addon", action="store_true", help="Blender's importers alone, without the add-on")
    args = parser.parse_args(argv)
    print(
        "| file | objects | meshes | mesh data | vertices | materials | transmitting (weight at IOR) | subsurface "
        "| alpha < 1 | s | MiB |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for path in args.files:
        print(row(path, import_report(path, not args.no_addon)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
