"""The ``measure`` node: a result's quality as a Table, from the element meshes a renderer receives —
mesh interpenetration over touching pairs (p50 / p95 / max in element lengths), contacts per element,
packing fraction and fill height (issue 17's targets: p95 ≤ 3 %, max ≤ 10 % after relaxation), and how many
elements ended outside their vessel (a warning names them: a region that does not fit its bowl).
"""

from __future__ import annotations

from functools import partial

from nodegraph.cost import estimated_by, passes
from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Table

from ..values import Aggregate, Vessel

# the table's columns, in its order (a sweep's metric naming one is checked before any work)
COLUMNS = (
    "elements",
    "sampled",
    "overlap_p50",
    "overlap_p95",
    "overlap_max",
    "touching_pairs",
    "deeper_than_1pct",
    "contacts_per_element",
    "packing_fraction",
    "fill_height",
    "outside_vessel",
    "skin",
)


@estimated_by(passes("aggregates"))
@node(
    "measure",
    random=True,
    inputs={
        "aggregates": In(Aggregate, "the final aggregates (their element meshes are measured)", many=True),
        "vessels": In(
            Vessel,
            "the bowls the elements belong in (a shape node's vessel output): elements whose centre ends past "
            "the outer surface of every one are counted and warned about",
            optional=True,
            many=True,
        ),
    },
    outputs={
        "table": Out(
            Table,
            "one row: elements, overlap p50/p95/max over touching pairs (element lengths), share deeper than 1 %, "
            "contacts per element, packing fraction (element volume / hull), fill height, elements outside the "
            "vessels (0 without vessels), skin: mean skin score of the sampled elements (concave share of edge "
            "curvature, nodes/quality/skin.py: 0 convex, ≤ 0.10 cooked rice)",
            columns=COLUMNS,
        )
    },
    params={
        "sample": Param(
            int, 300, "elements whose vertices are tested against their neighbours (all if fewer)", range=(1, 1_000_000)
        ),
        "contact": Param(
            float, 0.02, "two elements touch when closer than this", range=(0.0, 1.0), units="element lengths"
        ),
    },
)
def measure(ctx, aggregates, vessels=None, *, sample, contact):
    """Mesh-level quality of the aggregates together (elements of one may touch another's); a warning when
    elements end outside their vessels."""
    import numpy as np

    from .mesh_overlap import outer_shell, overlap_plan
    from .skin import interior_edges

    meshes, keys, bounds, centres, radii = [], [], [], [], []
    for aggregate in aggregates:
        p = aggregate.placement
        shapes = aggregate.without_normals()  # the vertices alone: no normals are measured
        shells, lengths = {}, {}  # per library mesh (kind, variant): its outer shell's faces, its length
        for i in range(len(p)):
            mesh = shapes.element_mesh(i)
            key = (id(aggregate), int(p.kinds[i]), int(p.variants[i]) % len(aggregate.libraries[p.kinds[i]]))
            if key not in shells:  # every element of a library mesh shares its faces and parts
                shells[key] = outer_shell(mesh.faces, mesh.parts)
                own = aggregate.libraries[key[1]].meshes[key[2]]
                lengths[key] = float(np.ptp(own.vertices, axis=0).max())  # the element's length in its own frame
            used, faces = shells[key]
            vertices = mesh.vertices if used is None else mesh.vertices[used]
            lo, hi = vertices.min(axis=0), vertices.max(axis=0)
            centre = 0.5 * (lo + hi)
            meshes.append((vertices, faces, lengths[key]))
            keys.append(key)
            bounds.append((lo, hi))
            centres.append(centre)
            radii.append(float(np.linalg.norm(vertices - centre, axis=1).max()))
    if not meshes:
        raise ValueError("aggregates: no elements to measure")
    n = len(meshes)
    picked = np.sort(ctx.rng.choice(n, size=min(sample, n), replace=False))
    bounds = np.array(bounds)
    plan = overlap_plan(meshes, np.array(centres), np.array(radii), picked, contact, bounds)
    # The libigl calls, the volumes, the hull and the skin scores, in one thread: libigl holds the GIL, and this node
    # runs beside the preview (executor.Beside), which keeps both cores busy (nodegraph/runtime.py)
    edges = {}  # per library mesh: its interior edges (the skin score's topology)
    for i in picked.tolist():
        if keys[i] not in edges:
            edges[keys[i]] = interior_edges(meshes[i][1], len(meshes[i][0]))
    chunks = [range(c, min(c + VOLUMES_PER_TASK, n)) for c in range(0, n, VOLUMES_PER_TASK)]
    skins = [picked[c : c + SKINS_PER_TASK].tolist() for c in range(0, len(picked), SKINS_PER_TASK)]
    tasks = [
        *plan.tasks,
        *(partial(_volumes, meshes, chunk) for chunk in chunks),
        *(partial(_skins, meshes, keys, edges, part) for part in skins),
        partial(_hull_volume, meshes),
    ]
    results = [task() for task in tasks]
    stats = plan.stats(results[: len(plan.tasks)])
    volumes = [v for part in results[len(plan.tasks) : len(plan.tasks) + len(chunks)] for v in part]
    scores = [s for part in results[len(plan.tasks) + len(chunks) : -1] for s in part]
    hull = results[-1]
    depth = stats.pair_depth if len(stats.pair_depth) else np.zeros(1)
    columns = {
        "elements": np.array([n]),
        "sampled": np.array([len(picked)]),
        "overlap_p50": np.array([np.percentile(depth, 50)]),
        "overlap_p95": np.array([np.percentile(depth, 95)]),
        "overlap_max": np.array([depth.max()]),
        "touching_pairs": np.array([len(stats.pair_depth)]),
        "deeper_than_1pct": np.array([np.mean(depth > 0.01)]),
        "contacts_per_element": np.array([stats.contacts.mean()]),
        "packing_fraction": np.array([sum(volumes) / hull]),
        "fill_height": np.array([np.percentile(bounds[:, 1, 2], 95) - bounds[:, 0, 2].min()]),
        "outside_vessel": np.array([_outside_vessels(ctx, np.array(centres), vessels or [])]),
        "skin": np.array([np.mean(scores)]),
    }
    return Table(columns)


VOLUMES_PER_TASK = 256  # elements whose volumes one task sums (≈ 30 ms)
SKINS_PER_TASK = 32  # sampled elements whose skin one task scores (≈ 20 ms)


def _volumes(meshes: list, elements: range) -> list[float]:
    """The volumes the elements' outer shells enclose."""
    from .mesh_overlap import volume

    return [abs(volume(meshes[i][0], meshes[i][1])) for i in elements]


def _skins(meshes: list, keys: list, edges: dict, elements: list[int]) -> list[float]:
    """The elements' skin scores (their library mesh's interior edges in ``edges``)."""
    from .skin import skin_score

    return [skin_score(meshes[i][0], meshes[i][1], edges[keys[i]]) for i in elements]


def _hull_volume(meshes: list) -> float:
    """The volume of the convex hull of every element's vertices (of at most ≈ 200,000 of them, evenly strided)."""
    import numpy as np
    import trimesh

    points = np.concatenate([m[0] for m in meshes])
    return trimesh.convex.convex_hull(points[:: max(1, len(points) // 200_000)]).volume


def _outside_vessels(ctx, centres, vessels) -> int:
    """How many element centres lie outside every bowl in ``vessels``: past its wall's outer surface (a grain on
    the rim's lip is in the bowl; ``Vessel.outside``); warns when any do."""
    import warnings

    import numpy as np

    bowls = [v for v in vessels if v.kind == "bowl"]
    if not bowls:
        return 0
    outside = np.logical_and.reduce([v.outside(centres, margin=v.wall) for v in bowls])  # past the wall's outside
    count = int(outside.sum())
    if count:
        v = bowls[0]
        message = (
            f"{ctx.node_id or 'measure'}: {count} of {len(centres)} elements ended outside their vessel (rim radius "
            f"{v.radius:g} mm, depth {v.depth:g} mm): either they started inside one another and the contacts threw "
            "them out (a placement's r below the elements' size: raise it with the elements), or a region they were "
            "placed in does not fit the bowl (derive it from the vessel: vessel_region)"
        )
        if ctx.reporter is not None:
            ctx.reporter.warn(message)
        else:
            warnings.warn(message, stacklevel=2)
    return count
