"""A shaded scene as a Mitsuba 3 scene (``scalar_rgb``, headless) — the preview of SPEC §4 colours.

The CDRF vertex colours already hold the direct lighting, so every surface is a diffuse BSDF whose
reflectance is its vertex colour under a uniform sky of radiance ≈ 1: the path tracer then adds only
what the per-vertex shading cannot — occlusion between grains and eggs, and contact shadows. A small
bright "sun" along the key light gives glossy materials (ikura's clearcoat) their highlights.
Meshes go to Mitsuba as binary PLY files in a temporary folder, one per material (its PLY loader is
~50× faster than filling ``mi.Mesh`` buffers from Python).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..values import Material, ShadedScene

SKY = 1.0  # radiance of the uniform sky (the CDRF colours are multiplied by ≈ this × visibility)
SUN_SHARE = 0.1  # the sun's irradiance as a share of the sky's: highlights without re-lighting much
SUN_ANGLE = 0.06  # rad, angular radius of the sun
GLOSS = 0.08  # mirror share of glossy materials (≈ Fresnel reflectance of a wet surface)


@dataclass(frozen=True)
class Camera:
    """An orbit camera aimed at the scene's bounding-sphere centre, distance chosen to fit it."""

    elevation: float  # degrees above the horizon
    azimuth: float  # degrees, 0 = looking along +y, 90 = along −x
    fov: float  # degrees, horizontal
    margin: float  # 1 = the bounding sphere touches the frame


def write_ply(path: Path, vertices, faces, normals, colors) -> None:
    """Binary little-endian PLY with float normals and float linear colours (Mitsuba: ``vertex_color``)."""
    from .mesh_files import binary_ply

    rows = np.hstack([vertices, normals, colors[:, :3]]).astype("<f4")
    path.write_bytes(binary_ply([(("x", "y", "z", "nx", "ny", "nz", "r", "g", "b"), rows)], faces))


def _bsdf(material: Material) -> dict:
    colour = {"type": "mesh_attribute", "name": "vertex_color"}
    if material.clearcoat >= 0.5 or material.roughness <= 0.15:
        # a thin mirror layer (Mitsuba's plastic needs a texture mean that vertex colours lack)
        return {
            "type": "blendbsdf",
            "weight": GLOSS,
            "bsdf_0": {"type": "diffuse", "reflectance": colour},
            "bsdf_1": {"type": "conductor", "material": "none"},
        }
    return {"type": "diffuse", "reflectance": colour}


def look_at(bounds: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(origin, target) so that the bounding sphere fits the horizontal field of view."""
    centre = bounds.mean(axis=0)
    radius = 0.5 * np.linalg.norm(bounds[1] - bounds[0])
    el, az = np.radians(camera.elevation), np.radians(camera.azimuth)
    view = np.array([np.sin(az) * np.cos(el), -np.cos(az) * np.cos(el), np.sin(el)])
    distance = camera.margin * radius / np.sin(np.radians(camera.fov) / 2)
    return centre + distance * view, centre


def scene_dict(
    scene: ShadedScene, folder: Path, camera: Camera, width: int, height: int, spp: int, light_direction: np.ndarray
) -> dict:
    """The Mitsuba scene description; PLY files are written into ``folder``."""
    import mitsuba as mi

    from .mesh_files import stacked

    shapes = {}
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for index, material in enumerate(scene.materials):
        members = [m for m, k in zip(scene.meshes, scene.material_of) if k == index and len(m.faces)]
        if not members:
            continue
        vertices, faces = stacked(members)
        normals = np.concatenate(
            [m.normals if m.normals is not None else np.zeros((len(m.vertices), 3)) for m in members]
        )
        colors = np.concatenate(
            [
                m.colors[:, :3] if m.colors is not None else np.tile(material.base_color, (len(m.vertices), 1))
                for m in members
            ]
        )
        path = folder / f"material_{index}.ply"
        write_ply(path, vertices, faces, normals, colors)
        shapes[f"shape_{index}"] = {
            "type": "ply",
            "filename": str(path),
            "bsdf": _bsdf(material),
            "face_normals": False,
        }
        lo, hi = np.minimum(lo, vertices.min(0)), np.maximum(hi, vertices.max(0))
    if not shapes:
        raise ValueError("scene: no mesh with faces to render")
    bounds = np.stack([lo, hi])
    origin, target = look_at(bounds, camera)
    radius = 0.5 * np.linalg.norm(hi - lo)
    sun_distance = 50 * radius
    sun_radius = sun_distance * np.tan(SUN_ANGLE)
    solid_angle = np.pi * np.tan(SUN_ANGLE) ** 2
    sun_radiance = SUN_SHARE * SKY * np.pi / solid_angle
    d = np.asarray(light_direction, np.float64) / np.linalg.norm(light_direction)
    return {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {
            "type": "perspective",
            "fov": camera.fov,
            "fov_axis": "x",
            "to_world": mi.ScalarTransform4f().look_at(origin=origin.tolist(), target=target.tolist(), up=[0, 0, 1]),
            "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": SKY}},
        "sun": {
            "type": "sphere",
            "center": (target + sun_distance * d).tolist(),
            "radius": float(sun_radius),
            "emitter": {"type": "area", "radiance": {"type": "rgb", "value": float(sun_radiance)}},
        },
        **shapes,
    }


def render(scene: ShadedScene, camera: Camera, width: int, height: int, spp: int, light_direction) -> np.ndarray:
    """Path-traced preview, 8-bit sRGB (height, width, 3)."""
    import tempfile

    import mitsuba as mi

    from .mesh_files import linear_to_srgb8

    mi.set_variant("scalar_rgb")
    with tempfile.TemporaryDirectory(prefix="nodegraph_preview_") as folder:
        loaded = mi.load_dict(scene_dict(scene, Path(folder), camera, width, height, spp, light_direction))
        image = np.asarray(mi.render(loaded, seed=0), np.float64)
    return linear_to_srgb8(image)
