"""Node ``expand``: the cooked grain's swelling [x, y, z] = P·[r, s, t] — SPEC §1.5 (G eq. 6)."""

from __future__ import annotations

from nodegraph import In, Moved, Out, Param, node

from ..values import DistanceField, RiceVariety
from .element_values import ExpandedField


def _check(p: dict) -> list[tuple[str, str]]:
    lo, hi = p["expansion"]
    return [("expansion", f"low {lo} must not exceed high {hi}")] if lo > hi else []


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
    },
    random=True,
    check=_check,
    moved={"variety": Moved("variety", "variety", "rice_variety")},
)
def expand(ctx, field, variety=None, *, expansion):
    """Scale the grain by P about its centroid (G eq. 6); P per element from ``expansion`` or the variety.

    The grid and the distances are scaled together, exactly: no resampling.
    """
    from .level_set_mesh import expand_field

    if variety is not None:
        p = variety.expansion
    else:
        lo, hi = expansion
        p = float(ctx.rng.uniform(lo, hi)) if hi > lo else float(lo)
    data, origin, voxel_size = expand_field(field.data, field.origin, field.voxel_size, p)
    return ExpandedField(data, origin, voxel_size, metric=field.metric, signed=field.signed, expansion=p)
