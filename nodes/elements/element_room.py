"""An element against the shape it is placed in, before any work: a base model longer than the shape's smallest
span (a 200 mm chestnut piece on a 76 mm onigiri, an 80 mm egg in a 35 mm deep bowl) makes no aggregate, and the
run said so only after its element modelling, or not at all. ``base_mesh``'s ``check_work``."""

from __future__ import annotations

from .grain_shapes import CHESTNUT_PIECE_SHARE, DEFAULT_SIZE, RICE_VARIETIES

# the input a node's placement or region comes through, nearest first: a placement's own (rotate, mix_ratio), a
# placer's shape (poisson_place), a boolean's first operand, a vessel_region's vessel
UPSTREAM = ("placement", "shape", "a", "vessel")


def base_length(node_id: str, nodes) -> tuple[str, float, float, str] | None:
    """(parameter, the element's longest side in mm, the factor on that parameter's value, what the factor is) of
    a ``base_mesh`` node from its parameters; None for a mesh file (only reading it would tell)."""
    entry = nodes[node_id]
    params = entry.params
    if params["shape"] == "ikura":
        return "diameter", params["diameter"], 1.0, ""
    if params["shape"] not in DEFAULT_SIZE:
        return None
    size = params["size"] or DEFAULT_SIZE[params["shape"]]
    if params["shape"] == "chestnut":  # a quarter of the kernel the size gives
        return "size", CHESTNUT_PIECE_SHARE * max(size), CHESTNUT_PIECE_SHARE, "a quarter's share of the kernel"
    factor = 1.0
    wires = entry.inputs.get("variety") or []
    if params["shape"] == "rice" and len(wires) == 1 and nodes[wires[0].node].spec.type_name == "rice_variety":
        factor = RICE_VARIETIES[nodes[wires[0].node].params["variety"]].length_factor
    return "size", max(size[0] * factor, *size[1:]), factor, f"the variety's factor {factor:g}"


def downstream(node_id: str, nodes) -> set[str]:
    """Every node that reads ``node_id``'s outputs, directly or through others."""
    readers: dict[str, set[str]] = {}
    for reader, entry in nodes.items():
        for wires in entry.inputs.values():
            for wire in wires:
                readers.setdefault(wire.node, set()).add(reader)
    seen, todo = set(), [node_id]
    while todo:
        for reader in readers.get(todo.pop(), ()):
            if reader not in seen:
                seen.add(reader)
                todo.append(reader)
    return seen


def placed_in(node_id: str, nodes) -> str | None:
    """The ``shape`` node a placement reader (mix_ratio) puts its elements in: up its placement to the placer's
    shape, through booleans (their first operand) and vessel regions (their vessel); None past any other node."""
    current = node_id
    for _ in range(len(nodes)):
        entry = nodes[current]
        if entry.spec.type_name == "shape":
            return current
        port = next((p for p in UPSTREAM if len(entry.inputs.get(p) or []) == 1), None)
        if port is None:
            return None
        current = entry.inputs[port][0].node
    return None


def element_fits(node_id: str, nodes) -> list[tuple[str, str, bool]]:
    """The element ``node_id`` (a base_mesh) models against each shape it is placed in (a mix_ratio reading a
    library made from it): its longest side at most the shape's smallest span, the shape made from its
    parameters (milliseconds)."""
    import numpy as np

    length = base_length(node_id, nodes)
    if length is None:
        return []
    param, longest, factor, why = length
    for reader in sorted(downstream(node_id, nodes)):
        if nodes[reader].spec.type_name != "mix_ratio":
            continue
        shape_id = placed_in(reader, nodes)
        if shape_id is None:
            continue
        spans = np.ptp(_made(nodes[shape_id]).vertices, axis=0)
        room = float(spans.min())
        if longest <= room:
            continue
        kind = nodes[shape_id].params["kind"]
        if param == "diameter":
            allowed = f"diameter ≤ {room:.3g} mm"
        elif factor != 1.0:
            before = f"the length ≤ {room / factor:.3g} mm before {why}"
            allowed = f"each side ≤ {room:.3g} mm, {before}"
        else:
            allowed = f"each side ≤ {room:.3g} mm"
        return [
            (
                param,
                f"the element '{node_id}' models is {longest:.3g} mm across, larger than the shape '{shape_id}' "
                f"({kind}) that '{reader}' places it in, whose smallest span is {room:.3g} mm; allowed: {allowed}",
                False,
            )
        ]
    return []


def _made(source):
    """The mesh of the ``shape`` node ``source`` (a recipe's ``NodeEntry``), made by its own node from its
    parameters; the last one kept (a recipe's elements ask for the same shape)."""
    key = tuple(sorted(source.params.items()))
    if key not in _MADE:
        _MADE.clear()
        _MADE[key] = source.spec.call(**source.params)["mesh"]
    return _MADE[key]


_MADE: dict[tuple, object] = {}
