"""The ``shape`` node: a closed target region for an aggregate — SPEC §2 (S fig. 10, G fig. 4.3.1)."""

from __future__ import annotations

import numpy as np

from nodegraph.node import Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh

from ..values import Vessel

KINDS = ("bowl", "onigiri", "sphere", "box", "cylinder", "block", "plate")


def _check(params: dict) -> list[tuple[str, str]]:
    issues = []
    mound, size = params.get("mound", 0), params.get("size", 1)
    if params.get("kind") == "bowl" and mound > 2 * size:
        issues.append(
            (
                "mound",
                f"a mound higher than twice the rim radius is not a bowl of rice; allowed: mound ≤ 2 × size = "
                f"{2 * size:g} mm at size {size:g}, or size ≥ {mound / 2:g} mm for this mound",
            )
        )
    return issues


def _read_ports(nodes) -> set[tuple[str, str]]:
    """Every (node, port) some node's input reads."""
    return {(wire.node, wire.port) for entry in nodes.values() for wires in entry.inputs.values() for wire in wires}


def _region_fits_vessels(node_id: str, nodes) -> list[tuple[str, str]]:
    """A bowl-shaped region stated apart from the recipe's vessel must fit in it (SPEC §2): a region whose rim
    reaches past the vessel's outer surface, or whose bottom lies under it, puts elements outside the bowl. A
    bowl is a vessel when its container or vessel output is read, a region when only its mesh is."""
    read = _read_ports(nodes)
    me = nodes[node_id].params
    if me["kind"] != "bowl" or (node_id, "container") in read or (node_id, "vessel") in read:
        return []
    vessels = {
        other: entry.params
        for other, entry in nodes.items()
        if entry.spec.type_name == "shape"
        and entry.params["kind"] == "bowl"
        and ((other, "container") in read or (other, "vessel") in read)
    }
    problems = []
    for other, v in vessels.items():
        reach, bottom = v["size"] + v["wall"], v["offset"][2] - v["depth"] - v["wall"]
        apart = float(np.hypot(me["offset"][0] - v["offset"][0], me["offset"][1] - v["offset"][1]))
        tolerance = 1e-6 * reach
        if apart + me["size"] <= reach + tolerance and me["offset"][2] - me["depth"] >= bottom - tolerance:
            return []
        problems.append(
            f"the bowl region '{node_id}' (rim radius {me['size']:g} mm, depth {me['depth']:g} mm) does not fit in "
            f"the vessel '{other}' (rim radius {v['size']:g} + wall {v['wall']:g} mm, depth {v['depth']:g} + "
            f"{v['wall']:g} mm): elements placed in it would end outside the bowl; derive the region from the "
            f"vessel instead (type vessel_region, inputs: {{vessel: {other}.vessel}})"
        )
    return [("size", problems[0])] if problems else []


def made_for_check(wires, nodes) -> tuple[str, Mesh] | None:
    """(source node id, mesh) of the shape one input reads (``wires``), when a ``shape`` node's parameters make it
    (made now, milliseconds once its modules are loaded): what a prop or a placement is weighed against before
    any work; None when only running the recipe would tell (a mesh file, a boolean)."""
    if len(wires) != 1:
        return None
    source = nodes[wires[0].node]
    if source.spec.type_name != "shape" or wires[0].port not in ("", "mesh"):
        return None
    key = tuple(sorted(source.params.items()))
    if key not in _MADE:  # a recipe's props ask for the same shape
        _MADE.clear()
        _MADE[key] = source.spec.call(**source.params)["mesh"]
    return wires[0].node, _MADE[key]


_MADE: dict[tuple, Mesh] = {}  # the last shape made for a check, by its parameters


CONTAINERS = ("bowl", "block")  # the kinds whose container output is a mesh; empty for the others


def _outputs_there(node_id: str, nodes) -> list[tuple[str, str]]:
    """What a node reads of this shape must exist for its kind: a container (a collider: an empty one failed the
    simulation deep inside, 'zero-size array to reduction operation minimum') only a bowl or block has, and the
    numbers a vessel_region derives its region from only a bowl has."""
    me = nodes[node_id].params
    for reader, entry in nodes.items():
        for port, wires in entry.inputs.items():
            for wire in wires:
                if wire.node != node_id:
                    continue
                if wire.port == "container" and me["kind"] not in CONTAINERS:
                    return [
                        (
                            "kind",
                            f"a shape of kind '{me['kind']}' has no container, but '{reader}' reads "
                            f"{node_id}.container as its {port}; allowed: {', '.join(CONTAINERS)} (or wire another "
                            "node's mesh there)",
                        )
                    ]
                if wire.port == "vessel" and entry.spec.type_name == "vessel_region" and me["kind"] != "bowl":
                    return [
                        (
                            "kind",
                            f"'{reader}' derives its region from {node_id}.vessel, the numbers of a bowl; a shape of "
                            f"kind '{me['kind']}' has none; allowed: bowl",
                        )
                    ]
    return []


def _recipe_rules(node_id: str, nodes) -> list[tuple[str, str]]:
    return _outputs_there(node_id, nodes) or _region_fits_vessels(node_id, nodes)


@node(
    "shape",
    outputs={
        "mesh": Out(
            Mesh, "the closed region the elements fill (for a bowl: the cavity to the fill height plus the mound)"
        ),
        "container": Out(
            Mesh,
            "the vessel as a closed solid for a bowl, an open-top tray for a block (collider); empty for other kinds",
        ),
        "vessel": Out(
            Vessel,
            "a bowl's cavity as numbers (rim radius, depth, wall, fill, mound, offset): regions derived from it "
            "(vessel_region) follow it, measure tests elements against it; kind only for other shapes",
        ),
    },
    params={
        "kind": Param(str, "onigiri", "which shape", choices=KINDS),
        "size": Param(
            float,
            20.0,
            "sphere/cylinder radius, onigiri circumscribed radius, bowl / plate rim radius",
            range=(1e-3, 1e4),
            units="mm",
        ),
        "extents": Param(
            tuple[float, float, float],
            (40.0, 40.0, 40.0),
            "box / block edge lengths (x, y, z)",
            range=(1e-3, 1e4),
            units="mm",
        ),
        "length": Param(float, 60.0, "cylinder length along x (lying cylinder)", range=(1e-3, 1e4), units="mm"),
        "thickness": Param(float, 0.9, "onigiri thickness as a share of its circumscribed radius", range=(0.05, 2.0)),
        "roundness": Param(float, 0.35, "onigiri corner rounding (0 sharp triangle, 1 disc)", range=(0.01, 1.0)),
        "bulge": Param(float, 0.8, "onigiri face bulge: 1 ellipsoidal, towards 0 flat faces", range=(0.1, 1.0)),
        "depth": Param(
            float,
            45.0,
            "bowl cavity depth below the rim; plate: rim height above its well",
            range=(1e-3, 1e4),
            units="mm",
        ),
        "wall": Param(float, 4.0, "bowl wall / block tray wall / plate thickness", range=(1e-3, 1e3), units="mm"),
        "well": Param(float, 0.65, "plate: radius of its flat well as a share of the rim radius", range=(0.05, 0.95)),
        "exponent": Param(
            float, 4.0, "block: superellipsoid exponent (2 an ellipsoid, larger towards a box)", range=(2.0, 20.0)
        ),
        "fill": Param(float, 0.8, "bowl fill height as a share of the depth", range=(0.05, 1.0)),
        "mound": Param(float, 15.0, "height of the rice mound above the fill plane", range=(0.0, 1e4), units="mm"),
        "offset": Param(
            tuple[float, float, float],
            (0.0, 0.0, 0.0),
            "translation of the shape and its container (e.g. a plate under a pressed onigiri)",
            range=(-1e4, 1e4),
            units="mm",
        ),
        "resolution": Param(
            int,
            4,
            "mesh resolution level (icosphere subdivisions; 12·2^(level−1) segments for solids of revolution)",
            range=(1, 7),
        ),
    },
    check=_check,
    check_recipe=_recipe_rules,
)
def shape(
    ctx,
    *,
    kind,
    size,
    extents,
    length,
    thickness,
    roundness,
    bulge,
    depth,
    wall,
    well,
    exponent,
    fill,
    mound,
    offset,
    resolution,
):
    """A closed target shape (outward normals), in millimetres, centred at ``offset`` (bowl: rim at z = offset z;
    plate: the top of its flat well at z = offset z)."""
    from . import solids

    container = None
    if kind == "sphere":
        mesh = solids.sphere(size, resolution)
    elif kind == "box":
        mesh = solids.box(extents)
    elif kind == "cylinder":
        mesh = solids.lying_cylinder(size, length, sections=12 * 2**resolution // 4)
    elif kind == "block":  # a nigiri's rice; its container: an open-top tray mould around it
        mesh = solids.rounded_block(extents, exponent, subdivisions=resolution)
        container = solids.tray(extents, wall)
    elif kind == "onigiri":
        mesh = solids.onigiri(size, thickness * size, roundness, bulge, subdivisions=resolution)
    elif kind == "plate":
        mesh = solids.plate(size, depth, wall, well, segments=12 * 2 ** (resolution - 1), rings=max(4, 2**resolution))
    else:
        mesh, container = solids.bowl(
            size, depth, wall, fill, mound, segments=12 * 2 ** (resolution - 1), rings=4 * 2 ** (resolution - 1)
        )
    if any(offset):
        mesh.apply_translation(offset)
        if container is not None:
            container.apply_translation(offset)
    out_container = (
        Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64), name="none")
        if container is None
        else Mesh.from_trimesh(container, name=f"{kind}_container")
    )
    vessel = (
        Vessel("bowl", size, depth, wall, fill, mound, tuple(float(v) for v in offset), resolution)
        if kind == "bowl"
        else Vessel(kind)
    )
    return {"mesh": Mesh.from_trimesh(mesh, name=kind), "container": out_container, "vessel": vessel}
