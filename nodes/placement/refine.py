"""Overlap refine, depth measurement and culling of a placement — SPEC §2.6–2.7 (S eq. 2, G eq. 1 and 3).

Pure functions over ``Placement`` + ``ElementTemplates``; the nodes and the benchmark call these.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..kernel_arrays import kernel_array
from ..values import Placement
from .element_templates import ElementTemplates
from .protrusion import ShapeBound, offset_caps, settle_inside

COSTS = ("sakurai", "gan")


@dataclass(frozen=True)
class RefineSettings:
    """S eq. 2: slope a (0.1), range b = range_scale·refine_range·circumradius; G eq. 1: range r·C_refine."""

    cost: str = "sakurai"
    slope: float = 0.1
    range_scale: float = 1.0
    spacing: float = 0.0  # G's r (Poisson radius); needed by the gan cost
    c_refine: float = 2.0
    offset: float = 0.0  # T of G eq. 2
    tolerance: float = 0.01  # golden-section bracket at the end, as a share of the search range


def golden_iterations(tolerance: float) -> int:
    """Golden-section steps that shrink the bracket to ``tolerance`` of its width."""
    return max(1, int(np.ceil(np.log(tolerance) / np.log((np.sqrt(5.0) - 1.0) / 2.0))))


def _search_ranges(
    placement: Placement,
    templates: ElementTemplates,
    tmpl: np.ndarray,
    refine_ranges: np.ndarray,
    settings: RefineSettings,
):
    scale = refine_ranges[placement.kinds]
    if settings.cost == "sakurai":
        b = settings.range_scale * scale * templates.circumradius[tmpl]
        return -b, b
    return np.zeros(len(placement)), settings.spacing * settings.c_refine * scale


def neighbours(positions: np.ndarray, templates: ElementTemplates, tmpl: np.ndarray, travel: np.ndarray):
    """Pairs that can touch: centre distance < bound_i + travel_i + bound_j + travel_j (grid search)."""
    from .refine_kernels import Neighbours, neighbour_lists

    if len(positions) == 0:
        return Neighbours(np.zeros(1, np.int64), np.zeros(0, np.int64))
    reach = np.maximum(templates.bound[tmpl], templates.circumradius[tmpl]) + travel
    return Neighbours(*neighbour_lists(kernel_array(positions), kernel_array(reach)))


def _frames(positions, placement: Placement, tmpl: np.ndarray):
    """The kernels' ``ElementFrames`` of the placement's elements at ``positions`` (moved in place by the refine)."""
    from .refine_kernels import ElementFrames

    return ElementFrames(
        positions,
        np.ascontiguousarray(placement.rotations),
        np.ascontiguousarray(placement.normals),
        np.ascontiguousarray(tmpl, np.int64),
    )


def _shapes(templates: ElementTemplates):
    """The kernels' ``TemplateShapes``: the arrays of ``templates`` they read."""
    from .refine_kernels import TemplateShapes

    t = templates
    return TemplateShapes(t.pts_start, t.cost_end, t.pts, t.sph_start, t.centers, t.radii, t.bound, t.circumradius)


def refine_placement(
    placement: Placement,
    templates: ElementTemplates,
    refine_ranges: np.ndarray,
    settings: RefineSettings,
    orders,
    bound: ShapeBound | None = None,
) -> Placement:
    """Move each element along its normal to the golden-section minimum of the cost, once per pass.

    ``orders``: one permutation per pass (S: a single pass). Later passes search the same range about
    the surface point and charge the travel from it, so passes only re-balance, never drift outward.
    ``bound``: the shape the elements fill; the search stops each element where it would reach out of it by
    more than ``bound.share`` of its size, and one still over after the passes is moved in along the shape's
    inward normal (``protrusion.settle_inside``); its offset then counts that move's part along its normal.
    """
    import numba

    from .refine_kernels import GAN, SAKURAI, RefineCost, SearchRange, colour_in_order, overlap_depths, refine_offsets

    n = len(placement)
    if n == 0:
        return placement
    tmpl = templates.index(placement.kinds, placement.variants)
    lo, hi = _search_ranges(placement, templates, tmpl, refine_ranges, settings)
    if bound is not None:
        hi = np.minimum(hi, offset_caps(placement, tmpl, bound))
        lo = np.minimum(lo, hi)  # one already out too far searches only where it is back within the bound
    travel = np.maximum(np.abs(lo), np.abs(hi))
    frames = _frames(placement.positions.copy(), placement, tmpl)
    shapes = _shapes(templates)
    cost = RefineCost(
        SAKURAI if settings.cost == "sakurai" else GAN,
        float(settings.slope),
        float(settings.spacing * settings.c_refine),
        float(settings.offset),
        golden_iterations(settings.tolerance),
    )
    travelled = np.zeros(n)
    for order in orders:
        # Neighbours within reach of any move left in this pass, from the current positions.
        near = neighbours(frames.positions, templates, tmpl, travel + np.abs(travelled))
        order = np.asarray(order, np.int64)
        colour = colour_in_order(order, near.start, near.index)
        search = SearchRange(lo - travelled, hi - travelled, travelled)
        travelled += refine_offsets(frames, search, near, colour, order, shapes, cost, 4 * numba.get_num_threads())
    if bound is not None:
        moved = settle_inside(frames.positions, frames.rotations, tmpl, bound)
        travelled += np.einsum("ij,ij->i", moved, placement.normals)
    near = neighbours(frames.positions, templates, tmpl, np.zeros(n))
    depth = overlap_depths(frames, near, np.ones(n, np.bool_), shapes, cost.offset)
    return dataclasses.replace(
        placement,
        positions=frames.positions,
        rotations=frames.rotations,
        offsets=placement.offsets + travelled,
        overlap=depth,
    )


def cull_placement(
    placement: Placement, templates: ElementTemplates, threshold: float, offset: float, ranks=None
) -> tuple[np.ndarray, np.ndarray]:
    """(keep mask, depth): deepest first, an element goes while its depth with live neighbours > D.

    ``ranks``: per element priority; the elements over D are visited lowest rank first (deepest first within a
    rank), so where a low and a high rank overlap the low one goes. ``depth`` is, for kept elements, the depth
    against the kept neighbours; for culled ones the depth they had before culling.
    """
    from .refine_kernels import cull_deepest, overlap_depths

    n = len(placement)
    if n == 0:
        return np.zeros(0, bool), np.zeros(0)
    tmpl = templates.index(placement.kinds, placement.variants)
    frames = _frames(placement.positions.copy(), placement, tmpl)  # writable, as in refine_placement: one kernel kind
    shapes = _shapes(templates)
    near = neighbours(frames.positions, templates, tmpl, np.zeros(n))
    offset = float(offset)
    depth = overlap_depths(frames, near, np.ones(n, np.bool_), shapes, offset)
    order_key = depth
    if ranks is not None and len(ranks):
        # the kernel visits by descending key and stops at the first ≤ D: lift the elements over D by their rank
        lift = (ranks.max() - ranks + 1) * (depth.max() + 1.0)
        order_key = np.where(depth > threshold, depth + lift, depth)
    keep = cull_deepest(order_key, float(threshold), frames, near, shapes, offset)
    after = overlap_depths(frames, near, keep, shapes, offset)
    return keep, np.where(keep, after, depth)
