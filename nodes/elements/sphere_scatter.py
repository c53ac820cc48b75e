"""Node ``sphere_scatter``: random porosity spheres on and inside the base mesh — SPEC §1.2 (G §3.1.1)."""

from __future__ import annotations

from nodegraph import In, Out, Param, node
from nodegraph.cost import estimated_by, passes
from nodegraph.values import Mesh

from ..values import SphereSet


def _check(p: dict) -> list[tuple[str, str]]:
    lo, hi = p["radius_range"]
    return [("radius_range", f"low {lo} must not exceed high {hi}")] if lo > hi else []


# the shape it carries on: its input's smallest inscribed radius (the spheres sink into the skin, no deeper)
@estimated_by(passes("mesh"))
@node(
    "sphere_scatter",
    inputs={"mesh": In(Mesh, "closed base mesh (mm)")},
    outputs={"spheres": Out(SphereSet, "sphere centres and radii; tags 0 = surface (sunk by sink), 1 = inside")},
    params={
        "count": Param(int, 40, "number of spheres (0 keeps the base mesh as it is)", range=(0, 5000)),
        "radius_range": Param(
            tuple[float, float],
            (0.2, 0.5),
            "radii drawn uniformly in [low, high]; the default suits a 3 mm wide grain",
            range=(0.001, 100.0),
            units="mm",
        ),
        "surface_share": Param(
            float, 0.7, "fraction of spheres centred on the surface; the rest inside", range=(0.0, 1.0)
        ),
        "sink": Param(
            float,
            0.0,
            "surface spheres' centres sunk this fraction of their radius under the skin along its normal: 0 = "
            "G's spheres centred on the surface (half-ball bumps), 0.6 = gentle swellings (cooked rice, issue 26), "
            "1 = tangent from inside (porosity wholly inside)",
            range=(0.0, 1.0),
        ),
    },
    random=True,
    check=_check,
)
def sphere_scatter(ctx, mesh, *, count, radius_range, surface_share, sink):
    """Scatter ``count`` spheres: a ``surface_share`` at the surface (by area, ``sink`` under it), the rest inside.

    These are the porosity parameters of G §3.1.1; each variant draws its own spheres from its seed.
    """
    from .sphere_sampling import scatter_spheres

    centers, radii, tags = scatter_spheres(
        mesh.vertices, mesh.faces, count, tuple(radius_range), surface_share, ctx.rng, sink
    )
    return SphereSet(centers, radii, tags)
