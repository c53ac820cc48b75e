"""The ``mix_ratio`` node: element kinds and variants by user ratios per P_num — SPEC §2.4
(G §3.2.2.3, S rice : chestnut)."""

from __future__ import annotations

import dataclasses

import numpy as np

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.params import Param

from ..values import Aggregate, ElementLibrary, Placement


def _ratios_per_library(node_id: str, nodes) -> list[tuple[str, str]]:
    """One ratio per library wired, before any work (a ratio short failed the run after its elements were built)."""
    me = nodes[node_id]
    ratios, wired = me.params.get("ratios"), len(me.inputs.get("libraries", ()))
    if ratios is None or not wired or len(ratios) == wired:
        return []
    return [("ratios", f"{len(ratios)} value(s) for the {wired} libraries wired; allowed: {wired} values, or none")]


@estimated_by(passes("placement", faces="libraries"))
@node(
    "mix_ratio",
    inputs={
        "placement": In(Placement, "placed (and rotated) points"),
        "libraries": In(ElementLibrary, "one library per element kind", many=True),
    },
    outputs={
        "placement": Out(Placement, "points with kinds and variants"),
        "aggregate": Out(Aggregate, "placement with its libraries"),
    },
    params={
        "ratios": Param(
            list[float],
            None,
            "relative amounts per library, e.g. [100, 1]; normalised to sum 1 (empty: equal)",
            range=(0.0, None),
            nullable=True,
        )
    },
    random=True,
    check_recipe=_ratios_per_library,
)
def mix_ratio(ctx, placement, libraries, *, ratios):
    """Kind by the cumulative ratios of a uniform draw per P_num; variant uniform within the kind's library."""
    libraries = tuple(libraries)
    if not libraries:
        raise ValueError("libraries: connect at least one element library")
    names = [lib.kind for lib in libraries]
    if len(set(names)) != len(names):
        raise ValueError(f"libraries: kinds must differ, got {names}")
    for lib in libraries:
        if len(lib) == 0:
            raise ValueError(f"libraries: {lib.kind!r} holds no meshes")
    weights = np.ones(len(libraries)) if ratios is None else np.asarray(ratios, float)
    if len(weights) != len(libraries):
        raise ValueError(f"ratios: {len(weights)} values for {len(libraries)} libraries ({names})")
    if weights.sum() <= 0:
        raise ValueError("ratios: at least one ratio must be > 0")
    cumulative = np.cumsum(weights / weights.sum())
    top = int(placement.p_num.max()) + 1 if len(placement) else 0
    draw = ctx.rng.random(top)
    pick = ctx.rng.integers(0, 2**31 - 1, top)
    kinds = np.minimum(np.searchsorted(cumulative, draw[placement.p_num], side="right"), len(libraries) - 1)
    sizes = np.array([len(lib) for lib in libraries])
    variants = pick[placement.p_num] % sizes[kinds]
    out = dataclasses.replace(placement, kinds=kinds, variants=variants, kind_names=tuple(names))
    return {"placement": out, "aggregate": Aggregate(out, libraries)}
