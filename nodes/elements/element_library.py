"""Node ``element_library``: N grain meshes of one kind → ElementLibrary — SPEC §1.6, §2 (consumers)."""

from __future__ import annotations

from nodegraph import In, Out, Param, node
from nodegraph.cost import Cost, CostQuery, estimated_by
from nodegraph.values import Mesh

from ..values import ElementLibrary, RiceVariety


def _cost(q: CostQuery) -> Cost:
    """The library's meshes (one per variant of each node wired in: what ``check`` counts as the elements of a
    recipe that makes only libraries), their smallest inscribed radius, mean volume and faces."""
    wires = q.nodes[q.node_id].inputs.get("meshes") or []
    return Cost(
        elements=sum(q.nodes[w.node].family or 1 for w in wires) or None,
        inscribed=q.inscribed("meshes"),
        volume=q.volume("meshes"),
        elongation=q.elongation("meshes"),
        faces=q.faces("meshes"),
        kinds=(q.params["kind"],) if q.params["kind"] else (),
    )


@estimated_by(_cost)
@node(
    "element_library",
    inputs={
        "meshes": In(Mesh, "element meshes (every variant of a family, or a list of wires)", many=True),
        "variety": In(RiceVariety, "rice: the variety, whose name is the element kind", optional=True),
    },
    outputs={"library": Out(ElementLibrary, "meshes plus per-element props")},
    params={
        "kind": Param(
            str,
            None,
            "name of the element kind (e.g. ikura); unset: the wired variety's name, else 'grain'",
            nullable=True,
        ),
        "refine_range": Param(
            float,
            1.0,
            "overlap-refine search range as a fraction of the circumradius (S: rice 1, chestnut 0.1; SPEC §2.6)",
            range=(0.0, 10.0),
        ),
    },
)
def element_library(ctx, meshes, variety=None, *, kind, refine_range):
    """Gather element meshes, checking each is closed and outward, with props per element.

    props: expansion (P), volume (mm³), circumradius and inradius (mm, about the centroid),
    length / width / thickness (mm, extents along x, y, z).
    """
    from .library_props import element_props

    if not meshes:
        raise ValueError("element_library needs at least one mesh")
    if variety is not None and kind is not None:
        raise ValueError(
            f"kind '{kind}' is given and so is the variety '{variety.name}', which names the kind: "
            "leave the parameter kind unset"
        )
    kind = variety.name if variety is not None else kind or "grain"
    props = element_props(list(meshes))
    return ElementLibrary(kind, tuple(meshes), props, refine_range)
