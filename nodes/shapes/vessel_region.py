"""The ``vessel_region`` node: a region derived from a vessel, so it follows the vessel — SPEC §2 inputs.

A bowl's rice layers, its static core and the layer its eggs start in are bowls of their own (a cavity to a
fill plane plus a mound) whose numbers all follow from the vessel's: the same rim and depth (or the
container's outer surface, so that regions subtracted from one another share no walls), the fill plane
moved by a few millimetres, the rim pulled in. Stated as offsets of the vessel, ``--set bowl.size=30`` gives a
smaller don whose regions still sit in its bowl.
"""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh

from ..values import Vessel

SURFACES = ("cavity", "outer")


@node(
    "vessel_region",
    inputs={"vessel": In(Vessel, "the bowl the region belongs to (a shape node's vessel output)")},
    outputs={"mesh": Out(Mesh, "the closed region: the vessel's cavity to the fill plane plus a mound")},
    params={
        "surface": Param(
            str,
            "cavity",
            "cavity: the bowl's inside; outer: the container's outer surface (rim radius + wall, depth + wall), "
            "for a region another is cut from (they then share no wall)",
            choices=SURFACES,
        ),
        "fill": Param(
            float,
            None,
            "fill height as a share of the vessel's depth; unset: the vessel's fill",
            range=(0.0, 1.0),
            nullable=True,
        ),
        "lower": Param(
            float, 0.0, "lowers the fill plane by this much (a core under a layer)", range=(-1e4, 1e4), units="mm"
        ),
        "mound": Param(
            float,
            None,
            "mound height above the fill plane; unset: the vessel's mound",
            range=(0.0, 1e4),
            units="mm",
            nullable=True,
        ),
        "inset": Param(
            float, 0.0, "rim radius pulled in by this much (keeps elements off the rim)", range=(0.0, 1e4), units="mm"
        ),
        "inset_share": Param(
            float,
            0.0,
            "rim radius pulled in further by this share of the vessel's own (a heap in the middle that keeps its "
            "proportion in a bigger or smaller bowl: the rice showing round a donburi's ikura)",
            range=(0.0, 0.95),
        ),
    },
)
def vessel_region(ctx, vessel, *, surface, fill, lower, mound, inset, inset_share):
    """A region derived from a bowl (fill plane, mound, rim and wall as offsets of it), so it follows the bowl
    (``solids.bowl``)."""
    from . import solids

    if vessel.kind != "bowl":
        raise ValueError(f"vessel: a region is derived from a bowl, got a shape of kind '{vessel.kind}'")
    grow = vessel.wall if surface == "outer" else 0.0
    radius, depth = vessel.radius + grow - inset - inset_share * vessel.radius, vessel.depth + grow
    if radius <= 0:
        raise ValueError(
            f"inset: {inset} mm and inset_share {inset_share:g} leave no rim (the {surface}'s rim radius is "
            f"{vessel.radius + grow} mm)"
        )
    fill_z = -vessel.depth + (vessel.fill if fill is None else fill) * vessel.depth - lower  # below the rim
    share = (fill_z + depth) / depth
    if not 0.0 < share <= 1.0:
        raise ValueError(
            f"lower: the fill plane at z = {fill_z:g} mm lies outside the {surface} (depth {depth:g} mm below the rim)"
        )
    region, _ = solids.bowl(
        radius,
        depth,
        vessel.wall,
        share,
        vessel.mound if mound is None else mound,
        segments=12 * 2 ** (vessel.resolution - 1),
        rings=4 * 2 ** (vessel.resolution - 1),
    )
    if any(vessel.offset):
        region.apply_translation(vessel.offset)
    return Mesh.from_trimesh(region, name=f"{surface}_region")
