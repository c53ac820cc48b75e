"""Node ``expand``: the cooked grain's swelling [x, y, z] = P·[r, s, t] — SPEC §1.5 (G eq. 6)."""

from __future__ import annotations

from nodegraph import In, Moved, Out, Param, node
from nodegraph.cost import Cost, CostQuery, estimated_by

from ..values import DistanceField, RiceVariety
from .element_values import ExpandedField

# radians: the most a broken grain's fracture plane turns from square across its length (drawn uniformly in ±);
# chosen, no published angle (docs/sizes.md): cut square, the piece read as a short whole grain with a flat end
BREAK_TILT = 0.4


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
    """The field's smallest inscribed radius × the smallest growth, P·e^(−1/3) across the grain (P·e^(2/3) along it
    when e < 1), P the wired rice variety's (``RICE_VARIETIES``, when the wire comes straight from a rice_variety
    node), else ``expansion``'s low end (a broken grain is cut across its length, not its thickness); its volume ×
    the mean P³ (e keeps the volume), less what the broken grains lose; nothing when a variety is wired from
    elsewhere."""
    from .grain_shapes import RICE_VARIETIES

    inscribed, volume, elongation = q.inscribed("field"), q.volume("field"), q.elongation("field")
    wires = [w for w in q.nodes[q.node_id].inputs.get("variety") or []]
    if inscribed is None:
        return Cost()
    lo, hi = q.params["expansion"]
    if wires:
        source = q.nodes.get(wires[0].node)
        if source is None or source.spec.type_name != "rice_variety":
            return Cost()
        lo = hi = RICE_VARIETIES[source.params["variety"]].expansion
    cubed = lo**3 if hi == lo else (hi**4 - lo**4) / (4.0 * (hi - lo))  # the mean of P³, P uniform in [lo, hi]
    kept = 1.0 - q.params["broken"] * (1.0 - sum(q.params["broken_length"]) / 2.0)
    grown = None if volume is None else volume * cubed * kept
    e = q.params["elongation"]  # the length grows by P·e^(2/3), the width by P·e^(−1/3): length over width by e
    return Cost(
        inscribed=inscribed * lo * _least_growth(e),
        volume=grown,
        elongation=None if elongation is None else elongation * e,
    )


def _least_growth(elongation: float) -> float:
    """The smaller of the growths along (e^(2/3)) and across (e^(−1/3)) the grain, per unit P."""
    return min(elongation ** (2.0 / 3.0), elongation ** (-1.0 / 3.0))


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
        "elongation": Param(
            float,
            1.0,
            "cooking's elongation e, the length's growth over the width's: length × P·e^(2/3), width and thickness × "
            "P·e^(−1/3), so the volume still grows P³ (G eq. 6); 1: G's isotropic growth; japonica's, from its raw "
            "and cooked length/width: docs/sizes.md",
            range=(0.5, 3.0),
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
            "whole one, USDA); cut across its long axis x, the fracture turned up to ±23° from square",
            range=(0.05, 1.0),
        ),
    },
    random=True,
    check=_check,
    moved={"variety": Moved("variety", "variety", "rice_variety")},
)
def expand(ctx, field, variety=None, *, expansion, elongation, broken, broken_length):
    """Grow the grain by P about its centroid (G eq. 6), longer than wide by ``elongation`` (cooking lengthens a
    grain more than it widens it); P per element from ``expansion`` or the variety.

    With no elongation the grid and the distances are scaled together, exactly: no resampling. A broken variant
    (``broken``) is then cut across x, keeping a share of its length drawn from ``broken_length``, the plane turned
    by up to ``BREAK_TILT``: the field is intersected with the half-space behind the cut (min of the two, positive
    inside), still a distance bound.
    """
    import numpy as np

    from .level_set_mesh import break_field, expand_field

    if variety is not None:
        p = variety.expansion
    else:
        lo, hi = expansion
        p = float(ctx.rng.uniform(lo, hi)) if hi > lo else float(lo)
    data, origin, voxel_size = expand_field(field.data, field.origin, field.voxel_size, p, elongation)
    if broken > 0 and is_broken(ctx.variant, broken):
        keep = float(ctx.rng.uniform(*broken_length))
        tilt = float(ctx.rng.uniform(-BREAK_TILT, BREAK_TILT))
        data = break_field(np.asarray(data), np.asarray(origin), voxel_size, keep, tilt)
    return ExpandedField(data, origin, voxel_size, metric=field.metric, signed=field.signed, expansion=p)
