"""A white furnace for a grain's skin and a glaze: the main job's rice (15 % water) as a sphere of radius 1.5 mm,
its medium's albedo raised to 1, and a white body under a clear glaze (``materials.coated``), in a uniform white
sky. Nothing absorbs, so a renderer that conserves energy shows the sphere exactly as bright as the sky (1). The
preview's skin (``mitsuba_scene.boundary_bsdf``) and Mitsuba's rough dielectric at the skin's roughness, beside
Cycles' Principled transmission at the same roughness with single- and multiple-scattering GGX
(``tools/cycles_furnace.py``, the Blender venv of ``tools/blender_side_by_side.py``); the preview's glaze
(``mitsuba_scene.coat_bsdf``) beside Disney's coat over Mitsuba's principled.

    python benchmarks/furnace.py [--spp 256]
"""

from __future__ import annotations

import argparse
import json
import subprocess
from pathlib import Path

from repo_tool import load_tool

from nodegraph import runtime

runtime.configure()

ROOT = Path(__file__).resolve().parents[1]
SIZE = 64  # px


def mitsuba(skin: dict, medium: dict | None, spp: int) -> float:
    """Mean radiance inside the grain's outline (``furnace.white_furnace`` at 64 × 64 pixels)."""
    from nodes.export.furnace import white_furnace

    return round(white_furnace(skin, medium, spp, SIZE), 4)


def cycles(roughness: float, ior: float, sigma_t: float, distribution: str, spp: int) -> float:
    from nodes.export.furnace import RADIUS

    side = load_tool("blender_side_by_side")
    command = [str(side.blender_python()), str(ROOT / "tools" / "cycles_furnace.py")]
    out = subprocess.run(
        command + [str(v) for v in (RADIUS, roughness, ior, sigma_t, distribution, spp)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return json.loads(next(line for line in out.splitlines() if line.startswith("FURNACE "))[8:])["mean"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--spp", type=int, default=256)
    a = ap.parse_args()
    import mitsuba as mi

    from nodes.export import mitsuba_scene as ms
    from nodes.export.look import boundary_roughness
    from nodes.shading.materials import coated, rice_material

    mi.set_variant("scalar_rgb")
    rice = rice_material(15.0)
    clear = {**ms.medium(rice), "albedo": {"type": "rgb", "value": [1.0, 1.0, 1.0]}}
    roughness, sigma_t = boundary_roughness(rice), ms.medium(rice)["scale"]
    rough = {"type": "roughdielectric", "int_ior": rice.ior, "alpha": ms.alpha(roughness), "distribution": "ggx"}
    rows = {
        "Mitsuba, the preview's skin": mitsuba(ms.boundary_bsdf(rice), clear, a.spp),
        f"Mitsuba, rough dielectric (GGX, α {ms.alpha(roughness):.3f})": mitsuba(rough, clear, a.spp),
        "Cycles, Principled transmission, GGX": cycles(roughness, rice.ior, sigma_t, "GGX", a.spp),
        "Cycles, Principled transmission, multiscatter GGX (the add-on's)": cycles(
            roughness, rice.ior, sigma_t, "MULTI_GGX", a.spp
        ),
    }
    white = coated("white", (1.0, 1.0, 1.0), 0.04)
    rows["a white body under a glaze: Mitsuba, the preview's (plastic)"] = mitsuba(ms.coat_bsdf(white), None, a.spp)
    rows["a white body under a glaze: Mitsuba, Disney's coat over principled"] = mitsuba(
        ms._principled(white), None, a.spp
    )
    for skin, mean in rows.items():
        print(json.dumps({"skin": skin, "mean": mean}), flush=True)


if __name__ == "__main__":
    main()
