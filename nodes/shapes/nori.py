"""The ``nori`` node: a band of nori (dried seaweed) wrapped around the lower part of a shape — the onigiri's
sheet, folded under its flat side and up both faces (SPEC §2 scenery; issue 26: an onigiri reads as one by its
band). Given the settled grains, the sheet drapes over them rather than the mould they slumped out of."""

from __future__ import annotations

from nodegraph.node import In, Out, node
from nodegraph.params import Param
from nodegraph.values import Mesh
from nodes.values import Aggregate


def band_size(shape: Mesh, width: float, height: float) -> tuple[float, float]:
    """The band's width and height in mm from its shares of the shape's width (x) and height (z)."""
    extent = shape.vertices.max(axis=0) - shape.vertices.min(axis=0)
    return float(width * extent[0]), float(height * extent[2])


def _check(params: dict) -> list[tuple[str, str]]:
    """A sheet thicker than its gap would cut into what it lies on (its thickness goes inwards)."""
    if params.get("thickness", 0.0) > params.get("gap", 0.3):
        return [
            (
                "thickness",
                f"{params['thickness']:g} mm is more than the gap ({params['gap']:g} mm): the sheet's inner face "
                "would cut into the rice it lies on; allowed: thickness ≤ gap",
            )
        ]
    return []


def _band_fits(node_id: str, nodes) -> list[tuple[str, str, bool]]:
    """The band against the shape it dresses, before any work (the run said so after its simulation, 52 s in):
    when a ``shape`` node's parameters make that shape, the band is wrapped round it at a few rays, and a band
    that leaves it is refused with the widest share that fits at its height."""
    from .shape import made_for_check

    entry = nodes[node_id]
    source = made_for_check(entry.inputs.get("shape") or [], nodes)
    if source is None:
        return []
    source_id, mould = source
    params = entry.params
    if _leaves(mould, params["width"], params) is None:
        return []
    low, high = 0.0, params["width"]  # the widest share that fits at this height: a bisection
    for _ in range(20):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if _leaves(mould, middle, params) is None else (low, middle)
    extent = mould.vertices.max(axis=0) - mould.vertices.min(axis=0)
    allowed = f"width ≤ {low:.3f} at height {params['height']:g}" if low > 0 else "a lower height"
    return [
        (
            "width" if low > 0 else "height",
            f"a band {params['width']:g} × {extent[0]:.1f} mm wide and {params['height']:g} × {extent[2]:.1f} mm "
            f"high leaves the shape '{source_id}' it dresses; allowed: {allowed} (shares of the shape's width "
            "and height)",
            False,
        )
    ]


def _leaves(mould, width: float, params) -> str | None:
    """Why a band ``width`` (a share) at the node's height, gap and rays leaves ``mould``, or None when it fits:
    at the run's own rays (4 × 16 passed a rounder onigiri whose 48 × 320 met a face from inside, 0.12 s each)."""
    from .solids import wrap_band

    mm_width, mm_height = band_size(mould, width, params["height"])
    try:
        wrap_band(mould.vertices, mould.faces, mm_width, mm_height, params["gap"], params["columns"], params["rows"])
    except ValueError as exc:
        return str(exc)
    return None


@node(
    "nori",
    inputs={
        "shape": In(Mesh, "the closed shape the band wraps (the onigiri's mould): its faces along ±y"),
        "aggregate": In(
            Aggregate,
            "the grains as they rest: the sheet lies on them (a slumped onigiri is lower and wider than its mould)",
            optional=True,
        ),
    },
    outputs={"mesh": Out(Mesh, "the band: an open sheet named 'nori' (shade gives it the nori material)")},
    params={
        "width": Param(
            float,
            0.38,
            "band width along x, centred on the shape, as a share of the shape's width (it follows the shape)",
            range=(0.001, 1.0),
        ),
        "height": Param(
            float,
            0.35,
            "how far up the faces the band reaches from the shape's lowest point, as a share of the shape's height",
            range=(0.001, 0.999),
        ),
        "gap": Param(float, 0.3, "distance of the sheet from the shape's surface", range=(0.0, 100.0), units="mm"),
        "columns": Param(int, 24, "faces across the band's width", range=(1, 1000)),
        "rows": Param(int, 64, "faces along the band, from one face's top edge round to the other's", range=(2, 4000)),
        "reach": Param(
            float,
            2.0,
            "with an aggregate: how far along the sheet a grain holds it up (its stiffness: it spans the grains' tops)",
            range=(0.0, 100.0),
            units="mm",
        ),
        "ribs": Param(
            float,
            0.0,
            "height of the sheet's fine ribbing (the lines of the mat it dried on), outwards; 0 = a smooth sheet",
            range=(0.0, 10.0),
            units="mm",
        ),
        "rib_period": Param(float, 1.6, "spacing of the ribs along the band", range=(0.01, 100.0), units="mm"),
        "crinkle": Param(
            float,
            0.0,
            "height of the dry sheet's crinkles and fibres (waves 4–12 mm and 0.5–1.5 mm long, drawn from the "
            "seed), outwards; 0 = none",
            range=(0.0, 10.0),
            units="mm",
        ),
        "thickness": Param(
            float,
            0.0,
            "the sheet's thickness, inwards from where it lies: a closed thin solid with cut edges; 0 = an open "
            "sheet with no thickness. At most the gap, so the rice under it stays under it",
            range=(0.0, 10.0),
            units="mm",
        ),
    },
    random=True,  # the crinkles' waves
    check=_check,
    check_work=_band_fits,
)
def nori(ctx, shape, aggregate=None, *, width, height, gap, columns, rows, reach, ribs, rib_period, crinkle, thickness):
    """The shape's surface (or the grains on it) under a plane ``height`` (a share of the shape's height) above
    the shape's lowest point, in a strip ``width`` (a share of its width) across x, ``gap`` outside it: a
    rectangular sheet folded round the shape's bottom, ``thickness`` thick, crinkled by up to ``crinkle``."""
    from .solids import SheetSurface, wrap_band

    width, height = band_size(shape, width, height)
    drape = None if aggregate is None else band_points(aggregate, shape, width, reach)
    seed = int(ctx.rng.integers(2**31))
    vertices, faces = wrap_band(
        shape.vertices,
        shape.faces,
        width,
        height,
        gap,
        columns,
        rows,
        drape,
        reach,
        SheetSurface(ribs, rib_period, crinkle, thickness, seed),
    )
    return Mesh(vertices, faces, name="nori")


def band_points(aggregate: Aggregate, shape: Mesh, width: float, reach: float):
    """The vertices of the elements that can reach the band's strip (its width about the shape's middle x, plus
    ``reach``), in world space."""
    import numpy as np

    middle = 0.5 * (shape.vertices[:, 0].min() + shape.vertices[:, 0].max())
    extent = max(np.linalg.norm(m.vertices, axis=1).max() for lib in aggregate.libraries for m in lib.meshes)
    near = np.flatnonzero(np.abs(aggregate.placement.positions[:, 0] - middle) <= 0.5 * width + reach + extent)
    if not len(near):
        return np.empty((0, 3))
    shapes = aggregate.without_normals()
    points = np.concatenate([shapes.element_mesh(int(i)).vertices for i in near])
    return points[np.abs(points[:, 0] - middle) <= 0.5 * width + reach]
