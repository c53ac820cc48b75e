"""The ``chopsticks`` node: a pair of Japanese chopsticks (hashi) lying on the table beside a dish, as a food
photographer stages a bowl (issue 48: "no garnish or props"). Each stick is a closed, tapered octagonal rod
(katakuchi-bashi: tapered at one end, JNTO), its underside flat on the table, the pair side by side; sizes in
docs/sizes.md. A prop: the preview frames the dish, not its props (``mitsuba_scene``), so the pair can reach past
the frame's edge as it would in a photograph."""

from __future__ import annotations

import numpy as np

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh

SIDES = 8  # an octagonal section: round enough at a stick's size in the frame, 2 × 8 + 2 vertices a stick
NAME = "chopsticks"  # the shade node gives a scenery mesh of this name ``materials.lacquer_material``


def stick(length: float, head: float, tip: float) -> tuple[np.ndarray, np.ndarray]:
    """One closed stick along +x from 0 (head, ``head`` mm across) to ``length`` (tip, ``tip`` mm across), its
    underside on z = 0: octagonal rings at both ends, each end closed by a fan round its centre."""
    angles = 2.0 * np.pi * (np.arange(SIDES) + 0.5) / SIDES
    ring = np.stack([np.cos(angles), np.sin(angles)], axis=1) / np.cos(np.pi / SIDES) / 2.0  # flats 1 apart
    rows = []
    for x, across in ((0.0, head), (length, tip)):
        rows.append(np.column_stack([np.full(SIDES, x), ring[:, 0] * across, ring[:, 1] * across + across / 2.0]))
    vertices = np.concatenate([*rows, [[0.0, 0.0, head / 2.0], [length, 0.0, tip / 2.0]]])
    faces = []
    for k in range(SIDES):
        a, b = k, (k + 1) % SIDES
        faces += [[a, b, SIDES + b], [a, SIDES + b, SIDES + a]]  # the side, outwards
        faces += [[2 * SIDES, b, a], [2 * SIDES + 1, SIDES + a, SIDES + b]]  # the head's cap (−x), the tip's (+x)
    return vertices, np.asarray(faces, np.int64)


def pair(
    dish: Mesh, length: float, head: float, tip: float, gap: float, distance: float, side: float, heading: float
) -> Mesh:
    """Two sticks ``gap`` mm apart (between their heads' axes), their middle ``distance`` mm outside the dish's
    outline (its widest radius about its vertical axis) in the direction ``side`` (degrees from +x), pointing their
    tips along ``heading`` (degrees from +x), lying on the plane of the dish's lowest point."""
    lo, hi = dish.vertices.min(axis=0), dish.vertices.max(axis=0)
    centre = 0.5 * (lo + hi)
    reach = float(np.linalg.norm(dish.vertices[:, :2] - centre[:2], axis=1).max())
    out = np.array([np.cos(np.radians(side)), np.sin(np.radians(side))])
    along = np.array([np.cos(np.radians(heading)), np.sin(np.radians(heading))])
    across = np.array([-along[1], along[0]])
    middle = centre[:2] + out * (reach + distance)
    vertices, faces = stick(length, head, tip)
    parts_v, parts_f = [], []
    for k, shift in enumerate((-gap / 2.0, gap / 2.0)):
        start = middle - along * length / 2.0 + across * shift
        xy = start + vertices[:, :1] * along + vertices[:, 1:2] * across
        parts_v.append(np.column_stack([xy, vertices[:, 2] + lo[2]]))
        parts_f.append(faces + k * len(vertices))
    return Mesh(np.concatenate(parts_v), np.concatenate(parts_f), name=NAME)


def _check(params: dict) -> list[tuple[str, str]]:
    """Sticks that taper the right way and do not cross, before any work."""
    issues = []
    head, tip, gap = params.get("head", 7.0), params.get("tip", 2.5), params.get("gap", 12.0)
    if tip > head:
        issues.append(("tip", f"tip {tip:g} mm is wider than the head {head:g} mm; allowed: tip ≤ head"))
    if gap < head:
        issues.append(("gap", f"gap {gap:g} mm is less than a head across ({head:g} mm); allowed: gap ≥ head"))
    return issues


@node(
    "chopsticks",
    inputs={"dish": In(Mesh, "the dish they lie beside (the bowl's container): its outline and the table's height")},
    outputs={"mesh": Out(Mesh, "two closed sticks named 'chopsticks' (shade gives them a lacquer)")},
    params={
        # an adult's pair: 21–23 cm (women), 23–25 cm (men); 1.5 × the span of thumb and index finger
        # (docs/sizes.md)
        "length": Param(float, 230.0, "each stick's length", range=(10.0, 1000.0), units="mm"),
        "head": Param(float, 7.0, "across the stick's thick end (the head, held)", range=(0.5, 50.0), units="mm"),
        "tip": Param(float, 2.5, "across the stick's tapered tip", range=(0.2, 50.0), units="mm"),
        "gap": Param(float, 12.0, "between the two sticks' axes", range=(0.0, 200.0), units="mm"),
        "distance": Param(float, 35.0, "from the dish's outline to the pair's middle", range=(0.0, 1000.0), units="mm"),
        "side": Param(
            float,
            20.0,
            "where the pair lies, seen from the dish's centre (0: +x)",
            range=(-360.0, 360.0),
            units="degrees",
        ),
        "heading": Param(float, 100.0, "the way the tips point (0: +x)", range=(-360.0, 360.0), units="degrees"),
    },
    check=_check,
)
def chopsticks(ctx, dish, *, length, head, tip, gap, distance, side, heading):
    """A pair of tapered sticks on the table beside ``dish`` (see ``pair``)."""
    return pair(dish, length, head, tip, gap, distance, side, heading)
