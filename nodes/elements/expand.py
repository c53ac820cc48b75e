"""Node ``expand``: the cooked grain's swelling [x, y, z] = P·[r, s, t] — SPEC §1.5 (G eq. 6)."""

from __future__ import annotations

from nodegraph import In, Moved, Out, Param, node
from nodegraph.cost import Cost, CostQuery, estimated_by

from ..values import DistanceField, RiceVariety
from .element_values import ExpandedField


def _check(p: dict) -> list[tuple[str, str]]:
    lo, hi = p["expansion"]
    issues = [("expansion", f"low {lo} must not exceed high {hi}")] if lo > hi else []
    lo, hi = p["broken_length"]
    if lo > hi:
        issues.append(("broken_length", f"low {lo} must not exceed high {hi}"))
    return issues


def is_broken(variant: int | None, share: float) -> bool:
    """Whether variant ``variant`` of a family is a broken grain, so that the first n variants hold
    round-down(n·share) broken ones, evenly spread (variant v is broken when ⌊(v+1)·share⌋ > ⌊v·share⌋); a node
    outside a family (no variant) counts as variant 0."""
    v = variant or 0
    return int((v + 1) * share + 1e-9) > int(v * share + 1e-9)


def _cost(q: CostQuery) -> Cost:
    """The field's smallest inscribed radius × the smallest P: the wired rice variety's (``RICE_VARIETIES``, when the
    wire comes straight from a rice_variety node), else ``expansion``'s low end (a broken grain is cut across its
    length, not its thickness); nothing when a variety is wired from elsewhere."""
    from .grain_shapes import RICE_VARIETIES

    inscribed = q.inscribed("field")
    wires = [w for w in q.nodes[q.node_id].inputs.get("variety") or []]
    if inscribed is None:
        return Cost()
    if not wires:
        return Cost(inscribed=inscribed * q.params["expansion"][0])
    source = q.nodes.get(wires[0].node)
    if source is None or source.spec.type_name != "rice_variety":
        return Cost()
    return Cost(inscribed=inscribed * RICE_VARIETIES[source.params["variety"]].expansion)


@estimated_by(_cost)
@node(
    "expand",
    inputs={
        "field": In(DistanceField, "signed distance field of the grain"),
        "variety": In(
            RiceVariety,
            "when wired, P is the variety's (indica 1.2, japonica 1.5, aromatic 1.5; SPEC §1.1) "
            "instead of the range 'expansion'",
            optional=True,
        ),
    },
    outputs={"field": Out(DistanceField, "the field scaled by P about the grain centroid (ExpandedField)")},
    params={
        "expansion": Param(
            tuple[float, float],
            (1.0, 1.5),
            "P drawn uniformly per element in [low, high] (G: 1–1.5); low = high fixes P",
            range=(0.1, 10.0),
        ),
        "broken": Param(
            float,
            0.0,
            "share of the variants that are broken grains (variant v is broken when ⌊(v+1)·share⌋ > ⌊v·share⌋, so "
            "16 variants realise shares in steps of 1/16); retail grades allow a few percent, docs/sizes.md",
            range=(0.0, 1.0),
        ),
        "broken_length": Param(
            tuple[float, float],
            (0.5, 0.75),
            "a broken grain keeps this share of its length, drawn uniformly (a broken kernel is one under 3/4 of a "
            "whole one, USDA); cut square across its long axis x",
            range=(0.05, 1.0),
        ),
    },
    random=True,
    check=_check,
    moved={"variety": Moved("variety", "variety", "rice_variety")},
)
def expand(ctx, field, variety=None, *, expansion, broken, broken_length):
    """Scale the grain by P about its centroid (G eq. 6); P per element from ``expansion`` or the variety.

    The grid and the distances are scaled together, exactly: no resampling. A broken variant (``broken``) is
    then cut square across x, keeping a share of its length drawn from ``broken_length``: the field is
    intersected with the half-space behind the cut (min of the two, positive inside), still a distance bound.
    """
    import numpy as np

    from .level_set_mesh import break_field, expand_field

    if variety is not None:
        p = variety.expansion
    else:
        lo, hi = expansion
        p = float(ctx.rng.uniform(lo, hi)) if hi > lo else float(lo)
    data, origin, voxel_size = expand_field(field.data, field.origin, field.voxel_size, p)
    if broken > 0 and is_broken(ctx.variant, broken):
        keep = float(ctx.rng.uniform(*broken_length))
        data = break_field(np.asarray(data), np.asarray(origin), voxel_size, keep)
    return ExpandedField(data, origin, voxel_size, metric=field.metric, signed=field.signed, expansion=p)
