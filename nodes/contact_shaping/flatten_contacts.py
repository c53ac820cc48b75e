"""The ``flatten_contacts`` node: after the XPBD run, the grains' meshes pressed flat where they meet —
SPEC §3's soft grains at mesh resolution (``contact_flattening``), so the exported meshes do not cut into
each other where the simulation's sphere clusters leave the surface uncovered (issue 17's mesh overlap).
"""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh, Table

from ..values import Aggregate

# what both contact steps take (``flatten_contacts``, ``deform_contacts``): the elements, what they press on, and
# the settings of the dent they share
CONTACT_INPUTS = {
    "aggregate": In(Aggregate, "the relaxed elements whose meshes are dented (xpbd.aggregate)"),
    "neighbours": In(
        Aggregate,
        "other aggregates its elements press on (not moved here: give each this aggregate as its neighbour)",
        optional=True,
        many=True,
    ),
    "colliders": In(
        Mesh,
        "container / ground solids: vertices in a wall go back out (effect 'collider')",
        optional=True,
        many=True,
    ),
    "moulds": In(
        Mesh,
        "shapes the elements stay inside: vertices outside go back in (effect 'collider')",
        optional=True,
        many=True,
    ),
}
CONTACT_PARAMS = {
    # ½: two grains of one kind are equally soft, so the dent lies on the bisector of their overlap
    "share": Param(
        float,
        0.5,
        "share of a contact's depth this aggregate's element gives way (½ each within the aggregate; against "
        "a neighbour aggregate set the two nodes' shares to sum to 1)",
        range=(0.0, 1.0),
    ),
    # 0.005 L ≈ 0.03 mm on rice: below the measure's contact distance (0.02 L), so dented grains still touch
    "clearance": Param(float, 0.005, "gap left between dented surfaces", range=(0.0, 0.1), units="element lengths"),
    # ½ thickness: a vertex never passes its grain's middle, whatever the overlap the simulation left
    "cap": Param(float, 0.5, "longest move of a vertex", range=(0.0, 2.0), units="element thicknesses"),
    # 256: the walls to ≈ 0.35 mm in the main job's 84 mm bowl; the field costs ∝ cells³ (a draft uses fewer)
    "wall_cells": Param(
        int, 256, "cells along the longest side of the walls' distance field (effect 'collider')", range=(16, 1024)
    ),
}


def wall_field(ctx, aggregate, colliders, moulds, wall_cells):
    """The walls' free-space field around the aggregate and its walls (effect 'collider'), None without walls."""
    import numpy as np

    from ..simulation.collider import free_space_field

    if "collider" not in ctx.effects or not (colliders or moulds) or not len(aggregate.placement):
        return None
    shapes = colliders + moulds
    points = aggregate.placement.positions
    lo = np.min([s.bounds[0] for s in shapes] + [points.min(axis=0)], axis=0)
    hi = np.max([s.bounds[1] for s in shapes] + [points.max(axis=0)], axis=0)
    pad = 0.05 * float((hi - lo).max())
    return free_space_field(colliders, moulds, lo - pad, hi + pad, float((hi - lo).max()) / wall_cells)


def dented_outputs(aggregate, dents, figures) -> dict:
    """The node outputs: the aggregate with its dents merged in (unchanged without dents) and the one-row table."""
    import dataclasses

    import numpy as np

    from ..simulation.aggregate import DeformedAggregate
    from .contact_flattening import merged_dents

    fields = {f.name: getattr(aggregate, f.name) for f in dataclasses.fields(aggregate)}
    if dents is not None:
        fields |= merged_dents(aggregate, dents)
    return {"aggregate": DeformedAggregate(**fields), "table": Table({k: np.array([v]) for k, v in figures.items()})}


@node(
    "flatten_contacts",
    inputs=CONTACT_INPUTS,
    outputs={
        "aggregate": Out(Aggregate, "the same elements, each mesh flattened where it pressed into another"),
        "table": Out(Table, "one row: dented elements, moved vertices, dent depth p50/p95/max (element lengths)"),
    },
    params=CONTACT_PARAMS,
    effects=("contact", "collider"),
)
def flatten_contacts(
    ctx, aggregate, neighbours=None, colliders=None, moulds=None, *, share, clearance, cap, wall_cells
):
    """Dents by ``contact_flattening.flatten`` (effect 'contact': between elements; 'collider': against walls
    and moulds); without either the aggregate passes through unchanged."""
    from .contact_flattening import flatten

    colliders, moulds = list(colliders or []), list(moulds or [])
    others = list(neighbours or []) if "contact" in ctx.effects else []
    walls = wall_field(ctx, aggregate, colliders, moulds, wall_cells)
    if "contact" not in ctx.effects and walls is None:
        return dented_outputs(aggregate, None, {"elements": len(aggregate.placement)})
    dents, figures = flatten(aggregate, others, walls, clearance, share, cap, contacts="contact" in ctx.effects)
    return dented_outputs(aggregate, dents, figures)
