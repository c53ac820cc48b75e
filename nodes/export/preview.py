"""The ``preview`` node: a path-traced, denoised PNG of the shaded scene (Mitsuba 3, ``scalar_rgb``, Intel Open
Image Denoise) — SPEC §4.

Name the node ``preview``: the engine writes an ``Image`` output as ``<node id>.png``.
"""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Image

from ..values import ShadedScene


@node(
    "preview",
    # 2: materials in the path tracer (dielectric ikura, translucent rice from the CDRF σ, glazed bowl),
    #    key light + sky + table, OIDN denoising, 1280 × 720 and 12 spp by default
    # 3: paths through ice up to 128 bounces (mitsuba_scene.path_depth): a heap of flakes was cut off dark grey
    # 4: subsurface: media inside rice, ikura yolks and ice (volpath)
    # 5: the key's glints in a one-bounce pass added after denoising (the denoiser erased them)
    version=5,
    inputs={"scene": In(ShadedScene, "shaded meshes with materials and per-vertex CDRF σ")},
    outputs={"image": Out(Image, "8-bit sRGB render")},
    params={
        "width": Param(int, 1280, "image width", range=(16, 4096), units="px"),
        "height": Param(int, 720, "image height", range=(16, 4096), units="px"),
        # 12, denoised: benchmarks/bench_preview.py on the main job (its hardest pixels: eggs over rice, against
        # 1,024 spp) measured with OIDN 8 spp 29.6 dB / 14 s, 12 spp 30.2 dB / 21 s, 16 spp 30.7 dB / 27 s at
        # 1280 × 720 on 2 cores: 12 is the fewest that reach 30 dB there within 30 s. Without OIDN, 32 spp: 22.7 dB.
        "samples": Param(
            int, 12, "samples per pixel (noise vs time; see benchmarks/bench_preview.py)", range=(1, 4096)
        ),
        "denoise": Param(bool, True, "Intel Open Image Denoise with albedo + normal guides (pyoidn)"),
        "subsurface": Param(
            bool,
            True,
            "light under the skin: a scattering medium inside each rice grain, ikura yolk and ice flake behind a "
            "dielectric boundary (volpath; mean free path and albedo from the material's subsurface radius and "
            "colour); off: the thin principled surface with the CDRF translucency per vertex",
        ),
        "elevation": Param(float, 40.0, "camera elevation above the horizon", range=(-89.0, 89.0), units="degrees"),
        "azimuth": Param(float, 20.0, "camera azimuth (0 looks along +y)", range=(-360.0, 360.0), units="degrees"),
        "fov": Param(float, 35.0, "horizontal field of view", range=(1.0, 150.0), units="degrees"),
        "margin": Param(
            float,
            0.1,
            "framing: share of the half-frame left free around the scene on its tightest side (fitted to the "
            "scene's vertices as seen by the camera, so it follows any change of the scene)",
            range=(0.0, 0.9),
        ),
        "sun_direction": Param(
            tuple[float, float, float],
            (-0.45, -0.6, 0.75),
            "direction towards the key light (match shade's key light)",
            range=(-1.0, 1.0),
        ),
    },
)
def preview(ctx, scene, *, width, height, samples, denoise, subsurface, elevation, azimuth, fov, margin, sun_direction):
    """Mitsuba path tracing of the materials (CDRF translucency per vertex) under a key light, sky and table,
    denoised; the same scene and parameters give the same bytes."""
    import numpy as np

    from .mitsuba_scene import Camera, render

    if not np.linalg.norm(sun_direction) > 0:
        raise ValueError("sun_direction: a zero vector has no direction")
    camera = Camera(elevation, azimuth, fov, margin)
    return Image(render(scene, camera, width, height, samples, sun_direction, denoised=denoise, subsurface=subsurface))
