"""Node ``remesh``: level-set surface of the field — SPEC §1.6 (G §3.1.1, marching cubes)."""

from __future__ import annotations

from nodegraph import In, Out, Param, node
from nodegraph.values import Mesh

from ..values import DistanceField
from .element_values import GrainMesh


@node(
    "remesh",
    version=1,
    inputs={"field": In(DistanceField, "signed distance field (positive inside)")},
    outputs={"mesh": Out(Mesh, "watertight outward grain, centred at its volume centroid (GrainMesh)")},
    params={
        "level": Param(
            float,
            0.0,
            "iso-level; > 0 shrinks the surface inward by that distance, < 0 grows it",
            range=(-100.0, 100.0),
            units="mm",
        ),
        "smoothing": Param(
            int,
            0,
            "Taubin smoothing iterations (volume-preserving; softens stair steps of the binary routes)",
            range=(0, 200),
        ),
        "target_faces": Param(
            int, None, "decimate to at most this many triangles (quadric)", range=(100, 10_000_000), nullable=True
        ),
    },
)
def remesh(ctx, field, *, level, smoothing, target_faces):
    """Marching cubes at ``level``, optional smoothing and triangle budget; checked watertight and outward.

    Internal cavity shells are dropped (the outer shell is the element). The budget uses quadric
    decimation, or a coarser marching-cubes sampling where decimation would pinch the surface.
    """
    import numpy as np

    from .level_set_mesh import centred, grain_surface

    data = np.asarray(field.data)
    vertices, faces = grain_surface(data, field.origin, field.voxel_size, level, smoothing, target_faces)
    vertices, normals = centred(vertices, faces)
    name = ctx.node_id if ctx.variant is None else f"{ctx.node_id}[{ctx.variant}]"
    return GrainMesh(
        vertices,
        faces,
        normals=normals,
        name=name,
        expansion=float(getattr(field, "expansion", 1.0)),
        inradius=max(float(data.max()) - level, 0.0),
    )
