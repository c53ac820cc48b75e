"""The ``poisson_place`` node: maximal Poisson-sphere placement on or in a shape — SPEC §2.1–2.2
(S §3.1, G §3.2.2.1)."""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh, Table

from ..values import ElementLibrary, Placement


def _has_candidates(mode, vertices, faces, r, candidate_spacing, inset) -> bool:
    """Whether ``r`` leaves at least one candidate point (a fixed probe seed: only the count matters)."""
    from .candidates import volume_candidates

    if mode == "surface":
        return True
    points, _ = volume_candidates(vertices, faces, candidate_spacing * r, np.random.default_rng(0))
    if inset > 0 and len(points):
        import igl

        depth = -igl.signed_distance(points, vertices, faces, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER)[0]
        points = points[depth >= inset]
    return len(points) > 0


def _fitting_r_hint(mode, vertices, faces, r_fails, candidate_spacing, inset) -> str:
    """A hint that is true: the largest r (within 5 %) below ``r_fails`` that finds candidate points in this
    shape, found by halving and then bisecting (a thin shape in volume mode fits a far smaller r than its
    extent suggests)."""
    lo, hi = None, r_fails
    for _ in range(16):
        if _has_candidates(mode, vertices, faces, hi / 2, candidate_spacing, inset):
            lo, hi = hi / 2, hi
            break
        hi /= 2
    if lo is None:
        return "lower r, or use mode: surface (the shape may be too thin to hold a candidate grid)"
    while hi - lo > 0.05 * lo:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if _has_candidates(mode, vertices, faces, mid, candidate_spacing, inset) else (lo, mid)
    return f"r ≤ {lo:.3g} finds candidate points in this shape (or lower candidate_spacing)"


@node(
    "poisson_place",
    inputs={
        "shape": In(Mesh, "closed target shape (outward normals)"),
        "elements": In(
            ElementLibrary,
            "elements that set r when r is not given (S: half the largest inscribed sphere radius)",
            optional=True,
            many=True,
        ),
    },
    outputs={
        "placement": Out(Placement, "placed points: position, normal (volume: local up +z), P_num in placing order"),
        "stats": Out(Table, "candidates, placed, r, min-distance ratio"),
    },
    params={
        "mode": Param(
            str,
            "surface",
            "surface: a shell on the shape (S); volume: fill the inside (G)",
            choices=("surface", "volume"),
        ),
        "r": Param(
            float,
            None,
            "exclusion radius; placed points are ≥ 2r apart (empty: from the elements)",
            range=(1e-6, 1e5),
            units="mm",
            nullable=True,
        ),
        "r_scale": Param(
            float,
            1.0,
            "factor on r derived from the elements (S: 1, neighbours always overlap; 2: r = the inscribed radius, "
            "a thinner shell that refines with little overlap)",
            range=(0.05, 20.0),
        ),
        "candidates": Param(
            str,
            "random",
            "surface candidates: random (area-weighted) or subdivide (S)",
            choices=("random", "subdivide"),
        ),
        "candidate_spacing": Param(
            float, 1.0, "candidate spacing as a share of r (S: edges ≤ r, i.e. 1)", range=(0.05, 4.0)
        ),
        # the shape's surface is often a container's inner wall: a grain centred on it lies half in the wall,
        # where the simulation's collider may push it out through the far side
        "inset": Param(
            float,
            0.0,
            "volume: drop candidates closer than this to the shape's surface (e.g. half the element's thickness)",
            range=(0.0, 1e4),
            units="mm",
        ),
        "max_candidates": Param(
            int, 5_000_000, "refuse when more candidates than this would be made (memory guard)", range=(1, 500_000_000)
        ),
    },
    random=True,
)
def poisson_place(ctx, shape, elements=None, *, mode, r, r_scale, candidates, candidate_spacing, inset, max_candidates):
    """Dart throwing over dense candidates (random order, flags) until none is free; maximal over them."""
    from nodes.shapes.closed_mesh import as_trimesh

    from .candidates import BYTES_PER_CANDIDATE, estimate_candidates, surface_candidates, volume_candidates
    from .dart_throw import dart_throw, min_distance_ratio

    solid = as_trimesh(shape, "poisson_place shape")
    if r is None:
        r = r_scale * _radius_from_elements(elements)
    extent = float(np.ptp(solid.vertices, axis=0).max())
    vertices, faces = np.asarray(solid.vertices), np.asarray(solid.faces)
    if 2.0 * r > extent:
        raise ValueError(
            f"r: {r:g} is larger than the shape (points must be 2r = {2 * r:g} apart, the shape spans "
            f"{extent:g}); " + _fitting_r_hint(mode, vertices, faces, extent / 2, candidate_spacing, inset)
        )
    spacing = candidate_spacing * r
    estimate = estimate_candidates(mode, solid.area, solid.volume, spacing)
    if estimate > max_candidates:
        raise ValueError(
            f"r: {r:g} with candidate_spacing {candidate_spacing:g} would make ~{estimate:,} candidates "
            f"(~{estimate * BYTES_PER_CANDIDATE / 2**20:,.0f} MiB), over max_candidates {max_candidates:,}; "
            "raise r or candidate_spacing, or max_candidates if the memory is there"
        )
    if mode == "surface":
        points, normals = surface_candidates(vertices, faces, spacing, candidates, ctx.rng)
    else:
        points, normals = volume_candidates(vertices, faces, spacing, ctx.rng)
        if inset > 0 and len(points):
            import igl

            depth = -igl.signed_distance(
                points, vertices, faces, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER
            )[0]
            points, normals = points[depth >= inset], normals[depth >= inset]
    if len(points) == 0:
        raise ValueError(
            f"r: no candidate point fits inside the shape at spacing {spacing:g} (candidate_spacing × r); "
            + _fitting_r_hint(mode, vertices, faces, r, candidate_spacing, inset)
        )
    placed = dart_throw(points, ctx.rng.permutation(len(points)), 2.0 * r)
    placement = Placement(points[placed], normals[placed])
    ratio = min_distance_ratio(placement.positions, 2.0 * r)
    if ctx.rerun.enabled:
        import rerun as rr

        ctx.rerun.log("candidates", rr.Points3D(points, radii=0.1 * r))
        ctx.rerun.log("placed", rr.Points3D(placement.positions, radii=r))
    stats = Table(
        {
            "candidates": np.array([len(points)]),
            "placed": np.array([len(placement)]),
            "r": np.array([r]),
            "min_distance_ratio": np.array([ratio]),
        }
    )
    return {"placement": placement, "stats": stats}


def _radius_from_elements(elements) -> float:
    """S §3.1.2: r = half the radius of the largest sphere inscribed in the element (smallest over all meshes)."""
    from .medial_spheres import largest_inscribed_radius

    meshes = [mesh for library in (elements or ()) for mesh in library.meshes]
    if not meshes:
        raise ValueError("r: give r, or connect elements so r can be derived from them")
    return 0.5 * min(largest_inscribed_radius(m.vertices, m.faces) for m in meshes)
