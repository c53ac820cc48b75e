"""The white-furnace test of a surface: a sphere (radius 1.5 mm) in a uniform white sky. Nothing absorbs, so a
renderer that conserves energy shows it exactly as bright as the sky (1); what it returns below 1 is energy a BSDF
loses, above 1 energy it makes (Heitz et al. 2016, "Multiple-scattering microfacet BSDFs", §6)."""

from __future__ import annotations

import numpy as np

RADIUS, FOV, DISTANCE = 1.5, 20.0, 20.0  # mm, degrees, mm: the sphere fills a third of the frame


def white_furnace(bsdf: dict, medium: dict | None = None, spp: int = 32, size: int = 24) -> float:
    """Mean radiance inside the sphere's outline (0.95 of its radius), Mitsuba's ``volpath`` (a medium inside the
    sphere where ``medium`` is given), ``size`` × ``size`` pixels at ``spp`` samples."""
    import mitsuba as mi

    from .mitsuba_scene import VARIANT

    mi.set_variant(VARIANT)
    view = mi.ScalarTransform4f().look_at(origin=[0, 0, DISTANCE], target=[0, 0, 0], up=[0, 1, 0])
    scene = {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": 1024, "rr_depth": 1024},
        "sensor": {
            "type": "perspective",
            "fov": FOV,
            "to_world": view,
            "film": {"type": "hdrfilm", "width": size, "height": size, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "sky": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        "sphere": {"type": "sphere", "radius": RADIUS, "bsdf": bsdf} | ({"interior": medium} if medium else {}),
    }
    image = np.asarray(mi.render(mi.load_dict(scene)), np.float64)
    y, x = np.mgrid[:size, :size] - (size - 1) / 2
    outline = RADIUS / (np.tan(np.radians(FOV / 2)) * DISTANCE) * size / 2
    return float(image[np.hypot(x, y) < 0.95 * outline].mean())
