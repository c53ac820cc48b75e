"""The ``medial_spheres`` node: each element's implicit function, computed once — SPEC §2.5 (S §3.2.2, G eq. 2)."""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Table

from ..values import ElementLibrary


@node(
    "medial_spheres",
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
        # 0: the mesh's own vertices and face centres. A 0.4 mm ice flake meshed with 50 vertices has samples as far
        # apart as it is thick: its poles miss the rims (24 spheres covered 20 % of its volume, the union 0.14 L short
        # of the surface at worst, so crossed flakes passed the cull); at 0.04, 64 spheres cover 63 %, 0.048 L
        "sample_spacing": Param(
            float,
            0.0,
            "largest spacing of the surface samples whose inner Voronoi poles are the candidate spheres (0: the "
            "mesh's vertices and face centres; > 0: the mesh subdivided to it first, for thin elements)",
            range=(0.0, 0.5),
            units="element lengths",
        ),
    },
)
def carry_medial_spheres(ctx, library, *, sphere_tolerance, max_spheres, sample_spacing):
    """Voronoi inner poles + greedy cover per mesh, stored with the library so no later node recomputes them."""
    from .element_templates import FIT_KEYS, with_medial_spheres

    carried = with_medial_spheres(library, sphere_tolerance, max_spheres, sample_spacing)
    if ctx.rerun.enabled:
        import rerun as rr

        first = carried.props["medial_spheres"][0, : int(carried.props["medial_count"][0])]
        ctx.rerun.log("first_element", rr.Points3D(first[:, :3], radii=first[:, 3]))
    return {
        "library": carried,
        "stats": Table({key: np.asarray(carried.props[f"medial_fit_{key}"]) for key in FIT_KEYS}),
    }
