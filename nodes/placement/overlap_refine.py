"""The ``overlap_refine`` node: one golden-section move per element along its normal — SPEC §2.5–2.6
(S eq. 2, G eq. 1)."""

from __future__ import annotations

import numpy as np

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh, Table

from ..values import Aggregate, ElementLibrary, Placement
from .element_templates import template_params


def _placed_by_poisson(node_id: str, nodes) -> bool:
    """Whether the placement into ``node_id`` comes, through nodes that pass a placement on (rotate, mix_ratio,
    another refine), from a ``poisson_place``: its r (``Placement.spacing``) is the gan range's."""
    current, seen = node_id, set()
    while current not in seen:
        seen.add(current)
        wires = nodes[current].inputs.get("placement") or []
        if len(wires) != 1:
            return False
        current = wires[0].node
        if nodes[current].spec.type_name == "poisson_place":
            return True
    return False


def _check_recipe(node_id: str, nodes) -> list[tuple[str, str]]:
    """The gan cost needs r: given, or the one the placement was made at (refused by ``check``, before any work)."""
    params = nodes[node_id].params
    if params["cost"] != "gan" or params["r"] is not None or _placed_by_poisson(node_id, nodes):
        return []
    return [
        (
            "r",
            "the gan cost (G eq. 1) searches t in [0, r·C_refine]: give r, or refine a placement made by "
            "poisson_place (its r is used)",
        )
    ]


@estimated_by(passes("placement"))
@node(
    "overlap_refine",
    inputs={
        "placement": In(Placement, "placed, rotated, mixed elements"),
        "libraries": In(ElementLibrary, "element libraries in the placement's kind order", many=True),
        "shape": In(
            Mesh,
            "the closed shape the elements fill (poisson_place's): none reaches out of it by more than protrusion",
            optional=True,
        ),
    },
    outputs={
        "placement": Out(Placement, "moved elements: offsets t and residual overlap depth filled"),
        "aggregate": Out(Aggregate, "placement with its libraries"),
        "stats": Out(Table, "per element variant: medial spheres and how well their union fits the mesh"),
    },
    params={
        "cost": Param(
            str,
            "sakurai",
            "sakurai: S eq. 2 (Σ f + a|t|, t ∈ [−b, b]); gan: G eq. 1 (max f + penalty, t ∈ [0, r·C_refine])",
            choices=("sakurai", "gan"),
        ),
        "slope": Param(
            float, 0.1, "a of S eq. 2: cost per unit of travel, keeps elements near the surface", range=(0.0, 1e3)
        ),
        "range_scale": Param(
            float, 1.0, "b = range_scale × kind refine_range × element circumradius (S: 1)", range=(0.0, 10.0)
        ),
        "r": Param(
            float,
            None,
            "Poisson radius r of G eq. 1 (gan cost only; empty: the r poisson_place placed the points at)",
            range=(1e-6, 1e5),
            units="mm",
            nullable=True,
        ),
        "c_refine": Param(float, 2.0, "C_refine of G eq. 1: range and penalty r·C_refine", range=(0.0, 100.0)),
        "offset": Param(
            float,
            0.0,
            "T of G eq. 2: overlap tolerated before the implicit function turns positive",
            range=(0.0, 1e3),
            units="mm",
        ),
        "protrusion": Param(
            list[float],
            [0.25],
            "with shape, per kind (one value: every kind): the most of an element's own extent along the shape's "
            "normal that may stand outside the shape; the refine stops it there, and one still beyond is moved in "
            "along the inward normal. 0: wholly inside; 0.5: its centre within (nothing hangs out by more than "
            "half); 1: none wholly outside. A share of each element's size: a piece 3× a grain may reach 3× as far",
            range=(0.0, 1.0),
        ),
        "passes": Param(
            int,
            1,
            "refine sweeps, each in a fresh random order (S: 1); later sweeps re-balance within the same range "
            "about the surface",
            range=(1, 64),
        ),
        "tolerance": Param(float, 0.01, "golden-section end bracket as a share of the search range", range=(1e-6, 0.5)),
        **template_params(),
    },
    random=True,
    check_recipe=_check_recipe,
)
def overlap_refine(
    ctx,
    placement,
    libraries,
    shape=None,
    *,
    cost,
    slope,
    range_scale,
    r,
    c_refine,
    offset,
    protrusion,
    passes,
    tolerance,
    sphere_tolerance,
    max_spheres,
    cost_points,
):
    """Medial-sphere implicit functions per variant, then each element once per pass in random order (colour
    classes in parallel)."""
    from .element_templates import FIT_KEYS, build_templates, matching_libraries, with_kind_names
    from .refine import RefineSettings, refine_placement

    libraries = matching_libraries(placement, libraries)
    if len(placement) == 0:
        empty = {key: np.zeros(0) for key in FIT_KEYS}
        return {"placement": placement, "aggregate": Aggregate(placement, libraries), "stats": Table(empty)}
    placement = with_kind_names(placement, libraries)
    r = r or placement.spacing
    if cost == "gan" and not r:
        raise ValueError(
            "r: the gan cost (G eq. 1) searches t in [0, r·C_refine]: give r, or refine a placement "
            "made by poisson_place (its r is used)"
        )
    templates = build_templates(libraries, sphere_tolerance, max_spheres, cost_points, measure_fit=True)
    settings = RefineSettings(
        cost=cost,
        slope=slope,
        range_scale=range_scale,
        spacing=r,
        c_refine=c_refine,
        offset=offset,
        tolerance=tolerance,
    )
    ranges = np.array([lib.refine_range for lib in libraries])
    orders = [ctx.rng.permutation(len(placement)) for _ in range(passes)]
    bound = None
    if shape is not None:
        from nodes.shapes.closed_mesh import as_trimesh

        from .protrusion import ShapeBound

        solid = as_trimesh(shape, "overlap_refine shape")
        points = tuple(np.asarray(mesh.vertices, np.float64) for lib in libraries for mesh in lib.meshes)
        if len(protrusion) not in (1, len(libraries)):
            raise ValueError(f"protrusion: {len(protrusion)} values for {len(libraries)} kinds (one: every kind)")
        shares = np.broadcast_to(np.asarray(protrusion, np.float64), (len(libraries),))
        share = np.repeat(shares, [len(lib) for lib in libraries])
        bound = ShapeBound(np.asarray(solid.vertices, np.float64), np.asarray(solid.faces, np.int64), share, points)
    refined = refine_placement(placement, templates, ranges, settings, orders, bound)
    if ctx.rerun.enabled and len(refined):
        import rerun as rr

        ctx.rerun.log("refined", rr.Points3D(refined.positions, radii=0.25 * float(templates.inscribed.min())))
    fit = {key: np.array([f[key] for f in templates.fit]) for key in FIT_KEYS}
    return {"placement": refined, "aggregate": Aggregate(refined, libraries), "stats": Table(fit)}
