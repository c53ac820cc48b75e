"""The ``deform_contacts`` node: after the XPBD run, the grains' meshes dented smoothly where they press on each
other, each grain keeping its volume by bulging where it is free (``contact_deformation``; issue 25), so the
exported meshes touch without cutting into each other where the simulation's sphere clusters leave the surface
uncovered (issue 17), and without the folds, creases and lost volume of pressing them flat.
"""

from __future__ import annotations

from nodegraph.cost import estimated_by, passes
from nodegraph.node import Out, node
from nodegraph.params import Param
from nodegraph.values import Table

from ..values import Aggregate
from .flatten_contacts import CONTACT_INPUTS, CONTACT_PARAMS, dented_outputs, wall_field

PLANE_HOLDS = ("everywhere", "near")


@estimated_by(passes("aggregate"))
@node(
    "deform_contacts",
    inputs=CONTACT_INPUTS,
    outputs={
        "aggregate": Out(Aggregate, "the same elements, each mesh dented where it pressed into another"),
        "table": Out(
            Table,
            "one row: dented elements, moved vertices, dent depth p50/p95/max (element lengths), volume error, folds",
        ),
    },
    params=CONTACT_PARAMS
    | {
        # 0.35: a dent's map shears a face by at most a third; with its depth fade (≥ 3 × its push) the map's
        # Jacobian stays ≥ ½, so no face turns over whatever the skin's bumps
        "slope": Param(float, 0.35, "steepest shear of a dent's smooth map", range=(0.05, 0.9)),
        # 0.15 thickness ≈ 0.35 mm on rice: a grain dented 15 % of its volume gets it back over its free half
        "bulge": Param(
            float,
            0.15,
            "longest outward move that gives a dented element its volume back",
            range=(0.0, 0.5),
            units="element thicknesses",
        ),  # fmt: skip
        # 8 at most: an element stops as soon as nothing is left to dent or give back (most after one or two); each
        # bulge is bounded, so a grain that lost half its volume (the onigiri draft's deepest) needs six
        "rounds": Param(
            int, 8, "dent–bulge rounds at most (1: dents only, the volume is not given back)", range=(1, 20)
        ),
        # everywhere: the smoothest skin on convex grains (rice bowl 0.095 against 0.110 with near); near: curled
        # or non-convex elements, which bend across a plane's extension (kakigori: 16 flakes over 2 % of their
        # volume against 278 with everywhere; docs/contact.md)
        "planes": Param(
            str,
            "everywhere",
            "which vertices a contact's plane holds back from bulging: everywhere (every vertex) or near (not "
            "those over the plane far from the neighbour: curled elements)",
            choices=PLANE_HOLDS,
        ),
    },
    effects=("contact", "collider"),
)
def deform_contacts(
    ctx,
    aggregate,
    neighbours=None,
    colliders=None,
    moulds=None,
    *,
    share,
    clearance,
    cap,
    slope,
    bulge,
    rounds,
    planes,
    wall_cells,
):
    """Dents by ``contact_deformation.deform`` (effect 'contact': between elements; 'collider': against walls
    and moulds); without either the aggregate passes through unchanged."""
    from .contact_deformation import deform

    colliders, moulds = list(colliders or []), list(moulds or [])
    others = list(neighbours or []) if "contact" in ctx.effects else []
    walls = wall_field(ctx, aggregate, colliders, moulds, wall_cells)
    if "contact" not in ctx.effects and walls is None:
        return dented_outputs(aggregate, None, {"elements": len(aggregate.placement)})
    settings = {"clearance": clearance, "share": share, "cap": cap, "slope": slope, "bulge": bulge, "rounds": rounds}
    settings["near"] = planes == "near"
    dents, figures = deform(aggregate, others, walls, settings, "contact" in ctx.effects)
    return dented_outputs(aggregate, dents, figures)
