"""The ``deform_contacts`` node: after the XPBD run, the grains' meshes dented smoothly where they press on each
other, each grain keeping its volume by bulging where it is free (``contact_deformation``; issue 25), so the
exported meshes touch without cutting into each other where the simulation's sphere clusters leave the surface
uncovered (issue 17), and without the folds, creases and lost volume of pressing them flat.
"""

from __future__ import annotations

from nodegraph.node import Out, node
from nodegraph.params import Param
from nodegraph.values import Table

from ..values import Aggregate
from .flatten_contacts import CONTACT_INPUTS, CONTACT_PARAMS, dented_outputs, wall_field


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
    from .contact_deformation import deform

    colliders, moulds = list(colliders or []), list(moulds or [])
    others = list(neighbours or []) if "contact" in ctx.effects else []
    walls = wall_field(ctx, aggregate, colliders, moulds, wall_cells)
    if "contact" not in ctx.effects and walls is None:
        return dented_outputs(aggregate, None, {"elements": len(aggregate.placement)})
    settings = {"clearance": clearance, "share": share, "cap": cap, "spread": spread, "sweeps": sweeps}
    dents, figures = deform(
        aggregate, others, walls, settings | {"rounds": rounds, "guard": fold_guard}, "contact" in ctx.effects
    )
    return dented_outputs(aggregate, dents, figures)
