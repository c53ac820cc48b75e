"""Node ``remesh``: level-set surface of the field — SPEC §1.6 (G §3.1.1, marching cubes)."""

from __future__ import annotations

from nodegraph import In, Out, Param, node
from nodegraph.cost import Cost, estimated_by
from nodegraph.values import Mesh

from ..values import DistanceField
from .element_values import GrainMesh


def _cost(q) -> Cost:
    """Its faces, the field's smallest inscribed radius less ``level`` and its volume (what a placement whose r
    comes from the elements reads; None where the field's is not known)."""
    inscribed = q.inscribed("field")
    return Cost(
        faces=q.params["target_faces"],
        inscribed=None if inscribed is None else max(inscribed - q.params["level"], 0.0),
        volume=q.volume("field"),
        elongation=q.elongation("field"),
    )


@estimated_by(_cost)
@node(
    "remesh",
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
        "blur": Param(
            float,
            0.0,
            "Gaussian σ of the field before marching cubes, level moved to keep the volume: rounds the creases "
            "where porosity spheres meet the skin and the facets of the cells (0.3 with sphere_scatter sink 0.6: "
            "japonica library's skin score 0.31–0.34 → 0.04–0.05 mean, nodes/quality/skin.py)",
            range=(0.0, 100.0),
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
def remesh(ctx, field, *, level, blur, smoothing, target_faces):
    """Marching cubes at ``level`` (of the blurred field when ``blur`` > 0), optional smoothing and triangle budget;
    checked watertight and outward.

    Internal cavity shells are dropped (the outer shell is the element). The budget uses quadric
    decimation, or a coarser marching-cubes sampling where decimation would pinch the surface.
    """
    import numpy as np

    from .level_set_mesh import blurred_field, centred, grain_surface

    data = np.asarray(field.data)
    if blur > 0.0:
        data, level = blurred_field(data, field.voxel_size, level, blur)
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
