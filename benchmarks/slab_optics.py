"""Which renderer carries light under a skin rightly: a slab of the main job's rice (15 % water) and of the ikura
membrane, rendered by the preview's Mitsuba (``mitsuba_scene.medium``, ``boundary_bsdf``, ``material_bsdf``) and by
Cycles through the Blender add-on (``tools/slab_cycles.py``), against references that use neither renderer.

    python benchmarks/slab_optics.py [--spp N] [--photons N] [--addon DIR]

The set-up: a slab 200 mm wide under a white sky (radiance 1) over the upper hemisphere and black below, seen
straight on from above (R) or below (T). By reciprocity a pixel is then the slab's directional-hemispherical
reflectance (transmittance) for light at normal incidence: the quantity the references give.

- **Rice**: the preview's medium (σt and single-scattering albedo from the subsurface colour and radius, Chiang et
  al. 2016) behind a smooth dielectric at IOR 1.4. Reference: an analogue Monte Carlo random walk of the same
  medium in a slab with Fresnel boundaries (``random_walk``, numpy, isotropic phase, a path depth of 64 as the
  preview's and unlimited), and for the semi-infinite slab the dipole's total diffuse reflectance (Jensen et al.
  2001, eq. 5 with Groenhuis' F_dr) plus the Fresnel reflection at normal incidence.
- **Membrane**: a clear dielectric at IOR 1.36 tinting each crossing by √(subsurface colour). Reference: Fresnel's
  reflectance of one interface and the light that comes back from the far face, summed over the reflections
  inside: R = F0 + (1 − F0)² c F0 / (1 − c F0²), c the colour through two crossings.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
DEPTH = 64  # mitsuba_scene.MAX_DEPTH_MEDIA


def fresnel(cos_i: np.ndarray, n1: float, n2: float) -> np.ndarray:
    """Unpolarised Fresnel reflectance from index n1 into n2 (1 past the critical angle)."""
    sin_t2 = (n1 / n2) ** 2 * (1.0 - cos_i**2)
    cos_t = np.sqrt(np.clip(1.0 - sin_t2, 0.0, 1.0))
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)
    return np.where(sin_t2 >= 1.0, 1.0, 0.5 * (rs**2 + rp**2))


def random_walk(sigma_t, albedo, n, h, photons, depth=None, seed=1):
    """(R, T) per channel of a slab ``h`` mm thick of an isotropic medium (σt mm⁻¹, the same in every channel, so
    every channel walks the same path and weighs it by albedo^k for its k scattering events) behind smooth Fresnel
    boundaries at index ``n``, lit at normal incidence. ``depth``: a path ends after this many vertices (crossings,
    reflections and scattering events, as a path tracer's depth), None: unlimited."""
    rng = np.random.default_rng(seed)
    albedo = np.asarray(albedo, np.float64)
    f0 = float(fresnel(np.array(1.0), 1.0, n))
    reflected, transmitted = np.full(3, f0 * photons), np.zeros(3)
    z, mu = np.zeros(photons), -np.ones(photons)
    scatters, vertices = np.zeros(photons, np.int64), np.ones(photons, np.int64)
    alive = np.ones(photons, bool)
    while alive.any():
        idx = np.nonzero(alive)[0]
        znew = z[idx] + mu[idx] * rng.exponential(1.0 / sigma_t, len(idx))
        top, bottom = znew > 0.0, znew < -h
        hit = top | bottom
        s = idx[~hit]
        z[s], mu[s] = znew[~hit], rng.uniform(-1.0, 1.0, len(s))
        scatters[s] += 1
        vertices[s] += 1
        b = idx[hit]
        z[b] = np.where(top[hit], 0.0, -h)
        vertices[b] += 1
        back = rng.uniform(size=len(b)) < fresnel(np.abs(mu[b]), n, 1.0)
        mu[b[back]] *= -1.0
        out = b[~back]
        up = z[out] == 0.0
        weight = (1.0 - f0) * albedo[None, :] ** scatters[out][:, None]
        if depth is not None:
            weight *= (vertices[out] <= depth)[:, None]
        reflected += weight[up].sum(axis=0)
        transmitted += weight[~up].sum(axis=0)
        alive[out] = False
        if depth is not None:
            alive[idx[vertices[idx] >= depth]] = False
    return reflected / photons, transmitted / photons


def mitsuba(bsdf: dict, interior: dict | None, h: float, side: str, spp: int) -> np.ndarray:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    sky = np.zeros((256, 512, 3), np.float32)
    sky[:128] = 1.0  # +y up: the upper hemisphere white
    eye, at = ([0, 5.0, 0], [0, 0, 0]) if side == "top" else ([0, -h - 5.0, 0], [0, -h, 0])
    slab = {
        "type": "cube",
        "to_world": mi.ScalarTransform4f().translate([0, -h / 2, 0]) @ mi.ScalarTransform4f().scale([100, h / 2, 100]),
        "bsdf": bsdf,
    }
    if interior is not None:
        slab["interior"] = interior
    scene = mi.load_dict(
        {
            "type": "scene",
            "integrator": {"type": "volpath", "max_depth": DEPTH, "rr_depth": 5},
            "sensor": {
                "type": "orthographic",
                "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=at, up=[0, 0, 1])
                @ mi.ScalarTransform4f().scale([0.5, 0.5, 1]),
                "film": {"type": "hdrfilm", "width": 2, "height": 2, "pixel_format": "rgb", "rfilter": {"type": "box"}},
                "sampler": {"type": "independent", "sample_count": spp},
            },
            "sky": {"type": "envmap", "bitmap": mi.Bitmap(sky)},
            "slab": slab,
        }
    )
    return np.asarray(mi.render(scene, seed=1)).reshape(-1, 3).mean(axis=0)


def cycles(look: dict, kind: str, h: float, side: str, spp: int, addon: Path) -> np.ndarray:
    python = os.environ.get("NODEGRAPH_BLENDER_PYTHON", str(REPO / ".venv-blender" / "bin" / "python"))
    with tempfile.TemporaryDirectory() as tmp:
        look_path, out = Path(tmp) / "look.json", Path(tmp) / "out.json"
        look_path.write_text(json.dumps(look))
        done = subprocess.run(
            [
                python,
                str(REPO / "tools" / "slab_cycles.py"),
                str(addon),
                str(look_path),
                kind,
                str(h),
                side,
                str(spp),
                str(out),
            ],
            capture_output=True,
            text=True,
        )
        if done.returncode or not out.exists():
            sys.exit(f"Blender failed:\n{done.stderr[-2000:]}")
        return np.asarray(json.loads(out.read_text()))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--spp", type=int, default=4096, help="samples per pixel of each 2 × 2 render")
    parser.add_argument("--photons", type=int, default=200_000, help="random walks of the reference")
    parser.add_argument(
        "--addon", type=Path, default=REPO / "blender", help="the folder holding the add-on (another version's)"
    )
    args = parser.parse_args()
    from nodes.export import mitsuba_scene as ms
    from nodes.export.look import diffuse_reflectance, principled_attributes, random_walk_coefficients
    from nodes.shading.materials import ikura_materials, rice_material

    def show(label, values):
        print(f"{label:58s} {' / '.join(f'{v:.3f}' for v in values)}")

    rice = rice_material(15.0)
    channels, albedo = random_walk_coefficients(rice.subsurface_color, rice.subsurface_radius)  # the refracting grain
    sigma_t = float(channels.mean())
    look = principled_attributes(rice, 0.0)
    print(f"rice at 15 % water: σt {sigma_t:.3f} mm⁻¹, albedo {np.round(albedo, 4).tolist()}, IOR {rice.ior}")
    for h, sides in ((2.7, ("top", "bottom")), (60.0, ("top",))):
        for side in sides:
            what = f"rice slab {h:g} mm, {'R' if side == 'top' else 'T'}"
            k = 0 if side == "top" else 1
            show(f"{what}: reference, depth 64", random_walk(sigma_t, albedo, rice.ior, h, args.photons, DEPTH)[k])
            show(f"{what}: reference, unlimited", random_walk(sigma_t, albedo, rice.ior, h, args.photons)[k])
            if h > 10:
                show(
                    f"{what}: dipole + F0",
                    diffuse_reflectance(albedo, rice.ior) + float(fresnel(np.array(1.0), 1.0, rice.ior)),
                )
            show(f"{what}: Mitsuba (preview)", mitsuba(ms.boundary_bsdf(rice), ms.medium(rice), h, side, args.spp))
            show(f"{what}: Cycles (add-on)", cycles(look, "rice", h, side, args.spp // 4, args.addon))
    membrane = ikura_materials()[0]
    c = np.asarray(membrane.subsurface_color)
    f0 = float(fresnel(np.array(1.0), 1.0, membrane.ior))
    look = {**principled_attributes(membrane, 0.0), "coatRoughness": membrane.clearcoat_roughness}
    show("membrane slab 3 mm, R: Fresnel", f0 + (1 - f0) ** 2 * c * f0 / (1 - c * f0**2))
    show(
        "membrane slab 3 mm, R: Mitsuba (preview)",
        mitsuba(ms.material_bsdf(membrane, False), None, 3.0, "top", args.spp),
    )
    show("membrane slab 3 mm, R: Cycles (add-on)", cycles(look, "membrane", 3.0, "top", args.spp // 4, args.addon))


if __name__ == "__main__":
    main()
