"""Node ``cooked_rice``: the one cooked material a recipe's simulation and shading read — SPEC §3–4."""

from __future__ import annotations

from nodegraph import In, Out, Param, node

from ..values import CookedMaterial, RiceVariety
from .cooked import SIGMA0_DRY, SIGMA0_WET, WATER_CONTENT


@node(
    "cooked_rice",
    inputs={"variety": In(RiceVariety, "the rice variety (a rice_variety node, the one the library reads)")},
    outputs={
        "material": Out(
            CookedMaterial,
            "variety, water content, moisture factors on stiffness / friction / adhesion (xpbd), CDRF σ₀ and the "
            "principled material (shade)",
        )
    },
    params={
        "water_content": Param(
            float,
            WATER_CONTENT,
            "water absorbed by the grains (G rendered 0–24 %, water at 5 °C): the xpbd node's effect 'moisture' "
            "scales stiffness, friction and adhesion by it; the shade node's σ₀ and rice material (its colour, "
            "translucency and gloss) follow it",
            range=(0.0, 24.0),
            units="%",
        ),
        "sigma0_dry": Param(
            float,
            SIGMA0_DRY,
            "σ₀ at 0 % water: CDRF blur per unit curvature (σ = σ₀·|κ|)",
            range=(1e-4, 10.0),
            units="rad·mm",
        ),
        "sigma0_wet": Param(
            float, SIGMA0_WET, "σ₀ at 24 % water (log–log line between the two)", range=(1e-4, 10.0), units="rad·mm"
        ),
    },
)
def cooked_rice(ctx, variety, *, water_content, sigma0_dry, sigma0_wet):
    """One cooked rice, read by xpbd and shade: moisture factors and optics from its water content — SPEC §3–4
    (``cooked.cooked_material``)."""
    from .cooked import cooked_material

    return cooked_material(variety.name, water_content, sigma0_dry, sigma0_wet)
