"""The ``medial_spheres`` node: each element's implicit function, computed once — SPEC §2.5 (S §3.2.2, G eq. 2)."""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Table

from ..values import ElementLibrary


@node(
    "medial_spheres",
    version=3,
    inputs={"library": In(ElementLibrary, "elements whose implicit functions overlap_refine and cull evaluate")},
    outputs={
        "library": Out(
            ElementLibrary,
            "the same elements carrying their medial spheres in props "
            "(medial_spheres (N, K, 4), medial_count; read by overlap_refine and cull)",
        ),
        "stats": Out(Table, "per element: sphere count and how well their union fits the mesh"),
    },
    params={
        "sphere_tolerance": Param(
            float,
            0.02,
            "medial spheres must touch the surface within this share of the element length",
            range=(0.001, 0.5),
        ),
        "max_spheres": Param(
            int, 64, "most medial spheres per element (the refine cost grows linearly with it)", range=(1, 4096)
        ),
    },
)
def carry_medial_spheres(ctx, library, *, sphere_tolerance, max_spheres):
    """Voronoi inner poles + greedy cover per mesh, stored with the library so no later node recomputes them."""
    from .element_templates import FIT_KEYS, with_medial_spheres

    carried = with_medial_spheres(library, sphere_tolerance, max_spheres)
    if ctx.rerun.enabled:
        import rerun as rr

        first = carried.props["medial_spheres"][0, : int(carried.props["medial_count"][0])]
        ctx.rerun.log("first_element", rr.Points3D(first[:, :3], radii=first[:, 3]))
    return {
        "library": carried,
        "stats": Table({key: np.asarray(carried.props[f"medial_fit_{key}"]) for key in FIT_KEYS}),
    }
