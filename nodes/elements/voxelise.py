"""Node ``voxelise``: mesh ∪ spheres → occupancy volume M — SPEC §1.3 (G §3.1.1, binvox in G)."""

from __future__ import annotations

import numpy as np

from nodegraph import In, Out, Param, node
from nodegraph.cost import estimated_by, passes
from nodegraph.values import Mesh

from ..values import SphereSet, Volume

#: Default from benchmarks/bench_elements.py (exact route): at 64 cells the mean surface error is
#: 0.04 % of the grain length (0.02 voxel), volume −0.2 %, 16 grains 0.7–1.1 s on 2 shared cores;
#: 96 halves the error at ~1.8× the time per grain, far below what a simulated grain can show.
DEFAULT_RESOLUTION = 64


# the shape it carries on: its input's smallest inscribed radius (the spheres sink into the skin, no deeper)
@estimated_by(passes("mesh"))
@node(
    "voxelise",
    inputs={
        "mesh": In(Mesh, "closed element mesh", optional=True),
        "spheres": In(SphereSet, "spheres added to the mesh", optional=True),
    },
    outputs={"volume": Out(Volume, "occupancy (bool): cell centre inside the mesh or a sphere")},
    params={
        "resolution": Param(
            int,
            DEFAULT_RESOLUTION,
            "cells along the longest side, padding included "
            "(64: see the resolution sweep in benchmarks/bench_elements.py); at most 406, so any shape's grid "
            "fits the 2^26-cell limit (finer: voxel_size)",
            range=(8, 406),
        ),
        "voxel_size": Param(
            float, None, "cell size; overrides resolution when given", range=(1e-4, 100.0), units="mm", nullable=True
        ),
        "padding": Param(int, 3, "empty cells around the geometry (room for level offsets)", range=(1, 32)),
    },
)
def voxelise(ctx, mesh=None, spheres=None, *, resolution, voxel_size, padding):
    """Occupancy of mesh ∪ spheres on a grid around both; refuses an empty or split volume.

    Cell centres are classified exactly (column winding count for the mesh, distance for spheres).
    """
    from . import voxel_grid

    vertices, faces, centers, radii = voxel_grid.element_geometry(mesh, spheres)
    lo, hi = voxel_grid.geometry_bounds(vertices, centers, radii)
    grid = voxel_grid.grid_for(lo, hi, resolution, voxel_size, padding)
    inside = voxel_grid.occupancy(grid, vertices, faces, centers, radii)
    return Volume(inside, np.asarray(grid.origin), grid.voxel_size)
