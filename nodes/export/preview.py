"""The ``preview`` node: a path-traced PNG of the shaded scene (Mitsuba 3, ``scalar_rgb``) — SPEC §4.

Name the node ``preview``: the engine writes an ``Image`` output as ``<node id>.png``.
"""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Image

from ..values import ShadedScene


@node(
    "preview",
    version=1,
    inputs={"scene": In(ShadedScene, "shaded meshes (CDRF vertex colours)")},
    outputs={"image": Out(Image, "8-bit sRGB render")},
    params={
        "width": Param(int, 480, "image width", range=(16, 4096), units="px"),
        "height": Param(int, 360, "image height", range=(16, 4096), units="px"),
        "samples": Param(int, 8, "samples per pixel (noise vs time)", range=(1, 4096)),
        "elevation": Param(float, 40.0, "camera elevation above the horizon", range=(-89.0, 89.0), units="degrees"),
        "azimuth": Param(float, 20.0, "camera azimuth (0 looks along +y)", range=(-360.0, 360.0), units="degrees"),
        "fov": Param(float, 35.0, "horizontal field of view", range=(1.0, 150.0), units="degrees"),
        "margin": Param(float, 1.0, "framing: 1 fits the scene's bounding sphere, smaller zooms in", range=(0.2, 5.0)),
        "sun_direction": Param(
            tuple[float, float, float],
            (-0.45, -0.6, 0.75),
            "direction towards the highlight light (match shade's key light)",
            range=(-1.0, 1.0),
        ),
    },
)
def preview(ctx, scene, *, width, height, samples, elevation, azimuth, fov, margin, sun_direction):
    """Mitsuba path tracing of CDRF-coloured diffuse/glossy surfaces under a sky: occlusion + highlights."""
    import numpy as np

    from .mitsuba_scene import Camera, render

    if not np.linalg.norm(sun_direction) > 0:
        raise ValueError("sun_direction: a zero vector has no direction")
    return Image(render(scene, Camera(elevation, azimuth, fov, margin), width, height, samples, sun_direction))
