"""The ``rotate`` node: random rotation per P_num in a local uvw frame — SPEC §2.3 (G §3.2.2.2, S §5 vector field)."""

from __future__ import annotations

import dataclasses

import numpy as np

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.params import Param

from ..values import Placement

FIELDS = ("none", "flow", "radial")


@estimated_by(passes("placement"))
@node(
    "rotate",
    inputs={"placement": In(Placement, "placed points with normals")},
    outputs={"placement": Out(Placement, "the same points with rotations")},
    params={
        "angles": Param(
            tuple[float, float, float],
            (180.0, 180.0, 180.0),
            "random angle ranges ±(u, v, w) about the local axes",
            range=(0.0, 180.0),
            units="degrees",
        ),
        "field": Param(
            str,
            "none",
            "orientation field for the element's long axis u: none (any tangent), flow (a direction projected on "
            "the tangent plane), radial (away from the origin, projected)",
            choices=FIELDS,
        ),
        "flow": Param(tuple[float, float, float], (0.0, 0.0, 1.0), "direction for field=flow"),
    },
    random=True,
)
def rotate(ctx, placement, *, angles, field, flow):
    """R = [u v w]·R_zyx(γ, β, α): w = normal, u = field direction in the tangent plane; angles drawn per P_num."""
    from .frames import local_frames, random_rotations

    if field == "flow" and not np.any(flow):
        raise ValueError("flow: the flow direction must not be the zero vector")
    directions = {
        "none": None,
        "flow": np.broadcast_to(np.asarray(flow, float), placement.positions.shape),
        "radial": placement.positions,
    }[field]
    frames = local_frames(placement.normals, directions)
    local = random_rotations(ctx.rng, placement.p_num, np.radians(angles))
    rotations = np.einsum("nij,njk->nik", frames, local)
    out = dataclasses.replace(placement, rotations=rotations)
    if ctx.rerun.enabled and len(out):
        import rerun as rr

        ctx.rerun.log("long_axes", rr.Arrows3D(origins=out.positions, vectors=rotations[:, :, 0]))
    return out
