"""The ``deform_contacts`` node: after the XPBD run, the grains' meshes dented smoothly where they press on each
other, each grain keeping its volume by bulging where it is free (``contact_deformation``; issue 25), so the
exported meshes touch without cutting into each other where the simulation's sphere clusters leave the surface
uncovered (issue 17), and without the folds, creases and lost volume of pressing them flat.
"""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh, Table

from ..values import Aggregate


@node(
    "deform_contacts",
    inputs={
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
    },
    outputs={
        "aggregate": Out(Aggregate, "the same elements, each mesh dented where it pressed into another"),
        "table": Out(
            Table,
            "one row: dented elements, moved vertices, dent depth p50/p95/max (element lengths), volume error, folds",
        ),
    },
    params={
        # ½: two grains of one kind are equally soft, so the contact lies on the bisector of their overlap
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
        # 0.1 thickness ≈ 0.2 mm on rice: a dent fades over a few edges of the grain mesh, no crease at its rim
        "spread": Param(
            float,
            0.1,
            "how far a dent fades into the surface around it",
            range=(0.01, 1.0),
            units="element thicknesses",
        ),
        # 20 sweeps reach ≈ 20 edges: past the spread's fade, so more change the dents by less than the clearance
        "sweeps": Param(int, 20, "relaxation sweeps per solve (projected Gauss–Seidel)", range=(1, 200)),
        # 5: dent, then four bulges of at most a fifth of an edge each (the fold guard), each followed by a dent;
        # on the reduced rice bowl (81 grains losing up to 25 % to their dents) volume error p95 2.2 % (3 rounds: 9 %)
        "rounds": Param(int, 5, "dent–bulge rounds (1: dents only, the volume is not given back)", range=(1, 10)),
        # off: on the full main job the guard shortened the moves of many grains (their bumpy skin folds a pit or
        # two when pressed) and left overlap p95 0.068 L by both inside tests (docs/contact.md)
        "fold_guard": Param(
            bool, False, "shorten an element's whole move, halving, until no two adjacent faces fold past 150°"
        ),
        # 256: the walls to ≈ 0.35 mm in the main job's 84 mm bowl; the field costs ∝ cells³ (a draft uses fewer)
        "wall_cells": Param(
            int, 256, "cells along the longest side of the walls' distance field (effect 'collider')", range=(16, 1024)
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
    spread,
    sweeps,
    rounds,
    fold_guard,
    wall_cells,
):
    """Dents by ``contact_deformation.deform`` (effect 'contact': between elements; 'collider': against walls
    and moulds); without either the aggregate passes through unchanged."""
    import dataclasses

    import numpy as np

    from .aggregate import DeformedAggregate
    from .collider import free_space_field
    from .contact_deformation import deform
    from .contact_flattening import merged_dents

    colliders, moulds = list(colliders or []), list(moulds or [])
    others = list(neighbours or []) if "contact" in ctx.effects else []
    walls = None
    if "collider" in ctx.effects and (colliders or moulds) and len(aggregate.placement):
        shapes = colliders + moulds
        points = aggregate.placement.positions
        lo = np.min([s.bounds[0] for s in shapes] + [points.min(axis=0)], axis=0)
        hi = np.max([s.bounds[1] for s in shapes] + [points.max(axis=0)], axis=0)
        pad = 0.05 * float((hi - lo).max())
        walls = free_space_field(colliders, moulds, lo - pad, hi + pad, float((hi - lo).max()) / wall_cells)
    if "contact" not in ctx.effects and walls is None:
        dents, figures = None, {"elements": len(aggregate.placement)}
    else:
        settings = {"clearance": clearance, "share": share, "cap": cap, "spread": spread, "sweeps": sweeps}
        dents, figures = deform(
            aggregate, others, walls, settings | {"rounds": rounds, "guard": fold_guard}, "contact" in ctx.effects
        )
    fields = {f.name: getattr(aggregate, f.name) for f in dataclasses.fields(aggregate)}
    if dents is not None:
        fields |= merged_dents(aggregate, dents)
    out = DeformedAggregate(**fields)
    return {"aggregate": out, "table": Table({k: np.array([v]) for k, v in figures.items()})}
