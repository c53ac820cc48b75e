"""The ``poisson_place`` node: maximal Poisson-sphere placement on or in a shape — SPEC §2.1–2.2
(S §3.1, G §3.2.2.1)."""

from __future__ import annotations

import numpy as np

from nodegraph.cost import Cost, CostQuery, estimated_by
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


# Placed points per r³ of the filled volume, which a shell of 0.64 r round the surface widens (a point may lie on
# it) and an inset narrows: count = 0.068 · (V + 0.64·A·r − A·inset) / r³, fitted to the placements of the rice bowl,
# the ikura don's rice and eggs and the onigiri, each at full size and as its draft (8 shapes of 2,700–172,000 mm³;
# each within 4 %: `python benchmarks/bench_cost.py --placements`, benchmarks/measured/cost.jsonl); per r² of a
# surface: discs of radius r jam at 0.547 of a plane (random sequential adsorption), 0.547 / π = 0.17.
VOLUME_DENSITY = 0.068
SURFACE_SHELL = 0.64
SURFACE_DENSITY = 0.17
# Elements a run places without being asked (--yes): 20× the rice bowl's 2,473, whose cold run takes 36 s on two
# cores; at r = 0.4 the bowl would get ≈ 160,000 and sit in the refine's neighbour search for many minutes.
MAX_ELEMENTS = 50_000


def estimate_placed(mode: str, area: float, volume: float, r: float, inset: float = 0.0) -> int:
    """Points a placement at ``r`` puts on (surface) or in (volume) a shape of this area and volume, ``inset`` off
    its surface."""
    if mode == "surface":
        return int(SURFACE_DENSITY * area / r**2)
    return int(VOLUME_DENSITY * max(volume + (SURFACE_SHELL * r - inset) * area, 0.0) / r**3)


# shapes made at check time from their parameters and inputs (milliseconds each: a boolean of the ikura bowl 30 ms,
# a vessel region 10 ms), so that a placement in a derived shape (a region of a bowl, a difference of two) is weighed
# as one in a plain shape is
MADE_AT_CHECK = ("shape", "vessel_region", "boolean", "mesh_file")  # a mesh file: read (the bunny: ≈ 0.1 s)


def _target(node_id: str, nodes):
    """(source node id, its kind, trimesh) of the shape a placement fills, when the nodes that make it are all of
    ``MADE_AT_CHECK`` (made now, ≈ 0.1 s once their modules are loaded); None when only running the recipe would
    tell."""
    wires = nodes[node_id].inputs.get("shape") or []
    if len(wires) != 1:
        return None
    made = _made(wires[0], nodes)
    if made is None:
        return None
    source = nodes[wires[0].node]
    kind = source.params["kind"] if source.spec.type_name == "shape" else source.spec.type_name
    from nodes.shapes.closed_mesh import as_trimesh

    return wires[0].node, kind, as_trimesh(made, "shape")


def _made(wire, nodes):
    """The value a wire carries, made now when its node and every node before it are of ``MADE_AT_CHECK``; else
    None. What each node made is kept, by what makes it (a recipe asks twice, a watch on every save; the ikura
    don's two derived shapes read one bowl), the last ``KEPT_SHAPES`` of them."""
    key = _recipe_of(wire, nodes)
    if key is None:
        return None
    made = _make(key[:3], wire.node, nodes)
    return made[key[3]] if isinstance(made, dict) else made


def _recipe_of(wire, nodes):
    """What makes a wire's value, as a hashable key (the node's type, parameters and inputs' keys, and the port);
    None when a node on the way is not one of ``MADE_AT_CHECK`` or an input is not one wire."""
    source = nodes.get(wire.node)
    if source is None or source.spec.type_name not in MADE_AT_CHECK:
        return None
    inputs = []
    for port, wires in sorted(source.inputs.items()):
        if len(wires) != 1:
            return None
        upstream = _recipe_of(wires[0], nodes)
        if upstream is None:
            return None
        inputs.append((port, upstream))
    port = wire.port or next(iter(source.spec.outputs))
    return (source.spec.type_name, repr(sorted(source.params.items())), tuple(inputs), port)


KEPT_SHAPES = 16
_SHAPES: dict[tuple, object] = {}  # what a node made for a check, by what makes it (``_recipe_of`` less the port)


def _make(key, node_id, nodes):
    """The node's outputs, made from its inputs' (each made once, ``_made``)."""
    if key not in _SHAPES:
        source = nodes[node_id]
        inputs = {port: _made(wires[0], nodes) for port, wires in source.inputs.items()}
        if len(_SHAPES) >= KEPT_SHAPES:
            _SHAPES.clear()
        _SHAPES[key] = source.spec.call(**source.params, **inputs)
    return _SHAPES[key]


def _fits_shape(node_id: str, nodes) -> list[tuple[str, str, bool]]:
    """r against the shape it fills, before any work: points 2r apart in a shape narrower than 2r find none (the
    run said so only after its search for an r that fits, minutes at a small shape). Refused, --yes or not."""
    r = nodes[node_id].params["r"]
    target = _target(node_id, nodes) if r is not None else None
    if target is None:
        return []
    source, kind, solid = target
    extent = float(np.ptp(solid.vertices, axis=0).max())
    if 2.0 * r <= extent:
        return []
    return [
        (
            "r",
            f"{r:g} is larger than the shape '{source}' ({kind}) it fills: points are placed 2r = {2 * r:g} apart "
            f"and the shape spans {extent:.3g} mm; allowed: r < {extent / 2:.3g} (in volume mode a thin shape fits "
            "a smaller one still)",
            False,
        )
    ]


def _least(fits, given: float) -> float:
    """The least value above ``given``, at 2 significant digits, for which ``fits`` holds (it holds for all larger)."""
    lo, hi = given, 2.0 * given
    while not fits(hi):
        lo, hi = hi, 2.0 * hi
    for _ in range(40):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if fits(mid) else (mid, hi)
    digits = 1 - int(np.floor(np.log10(hi)))
    least = float(np.ceil(hi * 10**digits) / 10**digits)
    return least if fits(least) else hi


def _cost(q: CostQuery) -> Cost:
    """The elements the placement makes and its candidates' memory, from the shape's size and r (given, or from the
    elements' inscribed radius or volume) before any work; more than ``MAX_ELEMENTS`` is refused unless --yes, more
    candidates than ``max_candidates`` (which the run refuses) always."""
    from .candidates import BYTES_PER_CANDIDATE, estimate_candidates

    p = q.params
    r, name = p["r"], "r"
    if r is None:  # S §3.1.2: half the elements' smallest inscribed radius (or a sphere of their volume), × r_scale
        if p["r_from"] == "volume":
            volume = q.volume("elements")
            base = None if volume is None else sphere_radius(volume)
        else:
            inscribed = q.inscribed("elements")
            base = None if inscribed is None else 0.5 * inscribed
        r, name = (None, "") if base is None else (p["r_scale"] * base, "r_scale")
    target = _target(q.node_id, q.nodes) if r is not None else None
    if target is None:
        return Cost()
    source, kind, solid = target
    mode, area, volume = p["mode"], float(solid.area), float(solid.volume)
    count = estimate_placed(mode, area, volume, r, p["inset"])
    candidates = estimate_candidates(mode, area, volume, p["candidate_spacing"] * r)
    given = p[name]  # the parameter to change: r, or r_scale where r comes from the elements
    derived = "" if name == "r" else f" (r = {r:.3g} mm from the elements)"
    size = f"{area:,.0f} mm² / r²" if mode == "surface" else f"{volume:,.0f} mm³ / r³"
    over = []
    if count > MAX_ELEMENTS:
        scale = r / given  # r per unit of the parameter named (1, or half the inscribed radius)
        least = _least(lambda x: estimate_placed(mode, area, volume, x * scale, p["inset"]) <= MAX_ELEMENTS, given)
        over.append(
            (
                name,
                f"{given:g}{derived} would place ≈ {count:,} elements in '{source}' ({kind}: {size}), over the "
                f"{MAX_ELEMENTS:,} a run places unasked; {name} ≥ {least:g} stays under",
                True,
            )
        )
    if candidates > p["max_candidates"]:
        least = given * (candidates / p["max_candidates"]) ** (1 / 3 if mode == "volume" else 1 / 2)
        over.append(
            (
                name,
                f"{given:g}{derived} would make ≈ {candidates:,} candidates in '{source}' "
                f"(≈ {candidates * BYTES_PER_CANDIDATE / 2**20:,.0f} MiB), over max_candidates "
                f"{p['max_candidates']:,}; allowed: {name} ≥ {least:.2g} (or a larger candidate_spacing, or "
                "max_candidates if the memory is there)",
                False,
            )
        )
    return Cost(elements=count, made=count, memory=candidates * BYTES_PER_CANDIDATE, over=tuple(over))


@estimated_by(_cost)
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
        "r_from": Param(
            str,
            "inscribed",
            "what r comes from when it is not given: inscribed (S: half the elements' smallest inscribed radius); "
            "volume (the radius of a sphere of their mean volume: a grain twice as long gets r × 2^(1/3), the same "
            "share of the shape filled, where its inscribed radius, set by its thickness, does not change)",
            choices=("inscribed", "volume"),
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
    check_work=_fits_shape,
)
def poisson_place(
    ctx, shape, elements=None, *, mode, r, r_from, r_scale, candidates, candidate_spacing, inset, max_candidates
):
    """Dart throwing over dense candidates (random order, flags) until none is free; maximal over them."""
    from nodes.shapes.closed_mesh import as_trimesh

    from .candidates import BYTES_PER_CANDIDATE, estimate_candidates, surface_candidates, volume_candidates
    from .dart_throw import dart_throw, min_distance_ratio

    solid = as_trimesh(shape, "poisson_place shape")
    if r is None:
        r = r_scale * _radius_from_elements(elements, r_from)
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
    placement = Placement(points[placed], normals[placed], spacing=float(r))
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


def _radius_from_elements(elements, r_from: str = "inscribed") -> float:
    """r from the elements (r_scale 1): S §3.1.2, half the radius of the largest sphere inscribed in the element
    (smallest over all meshes); or ``volume``: the radius of the sphere of the meshes' mean volume.

    An element of several parts (an ikura egg: membrane 0 around its yolk 1) is measured by its outer part 0
    alone: the yolk inside is not a wall the sphere must stay clear of."""
    from .medial_spheres import largest_inscribed_radius

    meshes = [mesh for library in (elements or ()) for mesh in library.meshes]
    if not meshes:
        raise ValueError("r: give r, or connect elements so r can be derived from them")
    if r_from == "volume":
        from nodes.elements.grain_shapes import volume_centroid

        volumes = [volume_centroid(*(np.asarray(a) for a in _outer_part(m)))[0] for m in meshes]
        return sphere_radius(float(np.mean(volumes)))
    return 0.5 * min(largest_inscribed_radius(*_outer_part(m)) for m in meshes)


def sphere_radius(volume: float) -> float:
    """The radius of a sphere of this volume."""
    return (3.0 * volume / (4.0 * np.pi)) ** (1.0 / 3.0)


def _outer_part(mesh) -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of part 0 of a multi-part mesh (``mesh_overlap.outer_shell``); the mesh itself otherwise."""
    from nodes.quality.mesh_overlap import outer_shell

    parts = getattr(mesh, "parts", None)
    used, faces = outer_shell(np.asarray(mesh.faces), None if parts is None else np.asarray(parts))
    return (mesh.vertices, mesh.faces) if used is None else (np.asarray(mesh.vertices)[used], faces)
