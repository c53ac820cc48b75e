"""The ``cull`` node: remove elements still overlapping deeper than D — SPEC §2.7 (G eq. 3, reading: depth > D)."""

from __future__ import annotations

import dataclasses

import numpy as np

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.params import Param

from ..values import Aggregate, ElementLibrary, Placement
from .element_templates import template_params

# the share of the refined elements a cull keeps, for the cost estimate before any work (``nodegraph.cost``): the
# grains that reach the scene against those the placement's estimate places, at D = 1 mm: the ikura don 1,551 of
# 1,639 (0.95), its draft 707 of 753 (0.94), the rice bowl 1,054 of 1,127 (0.94), the onigiri 1,846 of 1,869 (0.99),
# the lying onigiri 3,704 of 3,803 (0.97), sushi 320 of 356 (0.90): 0.95 is each within 6 % (the scene table,
# benchmarks/measured/scenes.jsonl; the draft's from its cached cull). A run's measure.csv counts those kept.
KEPT = 0.95
# the kinds a cull keeps a smaller share of: ice shavings (thin curled plates, tilted at random, cross deeper than
# grains) at the kakigori's D = 0.05 mm kept 12,787 of 19,297 placed (0.66) and its draft 1,712 of 2,476 (0.69)
KEPT_OF = {"ice_flake": 0.68}
# a cull that keeps under this share of KEPT says why (the count fell further than the estimate said: rice_chestnut at
# ratios [10, 1] kept 94 of 203, its chestnut pieces each taking the room of several grains)
SAID = 0.8


def kept_share(kinds) -> float:
    """The share of its elements a cull of these element kinds is estimated to keep (the least of theirs)."""
    return min((KEPT_OF.get(kind, KEPT) for kind in kinds), default=KEPT)


def _why_so_few(node_id, placement, keep, libraries, threshold, priority) -> str:
    """Why a cull kept far fewer than the estimate's share: what went of each kind, which kind gives way, and how
    much larger than the smallest kind each kind is (a piece of a larger kind takes the room of several)."""
    from nodes.elements.grain_shapes import volume_centroid

    volumes = [
        float(np.mean([abs(volume_centroid(np.asarray(m.vertices), np.asarray(m.faces))[0]) for m in lib.meshes]))
        for lib in libraries
    ]
    names = [lib.kind for lib in libraries]
    went = [
        f"{int((~keep & (placement.kinds == k)).sum()):,} of {int((placement.kinds == k).sum()):,} {name}"
        for k, name in enumerate(names)
    ]
    message = (
        f"{node_id}: kept {int(keep.sum()):,} of {len(keep):,} elements ({keep.mean():.0%}; the estimate assumes "
        f"{kept_share(names):.0%}): {', '.join(went)} overlapped deeper than threshold {threshold:g} mm and went"
    )
    if len(libraries) > 1:
        smallest = min(volumes)
        least = names[volumes.index(smallest)]
        larger = [
            f"a {n} is {v / smallest:.0f}× a {least}'s volume" for n, v in zip(names, volumes) if v > 1.5 * smallest
        ]
        order = "deepest first" if priority is None else f"by priority {list(priority)}, the lower first"
        message += f" ({order})"
        if larger:
            message += (
                f"; every element is placed at the smallest kind's spacing and {', '.join(larger)}: the larger the "
                "share of the larger kinds (ratios), the fewer elements fit"
            )
    return message


@estimated_by(passes("placement", kept_share))
@node(
    "cull",
    inputs={
        "placement": In(Placement, "refined elements"),
        "libraries": In(ElementLibrary, "element libraries in the placement's kind order", many=True),
    },
    outputs={
        "placement": Out(Placement, "the elements kept (overlap = depth with the kept neighbours)"),
        "culled": Out(Placement, "the elements removed, with the depth that removed them"),
        "aggregate": Out(Aggregate, "kept placement with its libraries"),
    },
    params={
        "threshold": Param(
            float,
            0.0,
            "D: remove an element whose overlap depth exceeds this (0: touching only)",
            range=(0.0, 1e4),
            units="mm",
        ),
        "offset": Param(
            float, 0.0, "T of G eq. 2 (use the value given to overlap_refine)", range=(0.0, 1e3), units="mm"
        ),
        "priority": Param(
            list[int],
            None,
            "per kind (the placement's kind order): where kinds overlap the lower goes first, so a piece keeps its "
            "place and the grains over it give way; deepest first within a priority (empty: deepest first over all)",
            nullable=True,
        ),
        **template_params(),
    },
)
def cull(ctx, placement, libraries, *, threshold, offset, priority, sphere_tolerance, max_spheres, cost_points):
    """Deepest first (lowest priority first), an element goes while its depth against the kept neighbours
    exceeds D.

    Never culls everything: the last element of an overlapping group has no live neighbour left.
    """
    from .element_templates import build_templates, matching_libraries, with_kind_names
    from .refine import cull_placement

    libraries = matching_libraries(placement, libraries)
    if len(placement) == 0:
        return {"placement": placement, "culled": placement, "aggregate": Aggregate(placement, libraries)}
    placement = with_kind_names(placement, libraries)
    templates = build_templates(libraries, sphere_tolerance, max_spheres, cost_points)
    if priority is not None and len(priority) != len(libraries):
        raise ValueError(f"priority: {len(priority)} values for {len(libraries)} kinds")
    ranks = None if priority is None else np.asarray(priority, np.int64)[placement.kinds]
    keep, depth = cull_placement(placement, templates, threshold, offset, ranks)
    with_depth = dataclasses.replace(placement, overlap=depth)
    kept, culled = with_depth.subset(keep), with_depth.subset(~keep)
    if (
        ctx.reporter is not None
        and len(placement)
        and len(kept) < SAID * kept_share([lib.kind for lib in libraries]) * len(placement)
    ):
        ctx.reporter.info(_why_so_few(ctx.node_id or "cull", placement, keep, libraries, threshold, priority))
    if ctx.rerun.enabled:
        import rerun as rr

        ctx.rerun.log(
            "culled",
            rr.Points3D(
                culled.positions,
                radii=0.3 * float(templates.inscribed.min()),
                colors=np.tile([230, 40, 40], (len(culled), 1)),
            ),
        )
    return {"placement": kept, "culled": culled, "aggregate": Aggregate(kept, libraries)}
