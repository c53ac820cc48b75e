"""A cooked rice's constants from its variety and water content — SPEC §3 (moisture scales, G §2.2) and
§4 (σ₀ by a log–log line in the water content, the principled material). The material reads the shading's
and the simulation's constants, never the other way round.
"""

from __future__ import annotations

from ..shading.cdrf import SIGMA0_DRY, SIGMA0_WET
from ..simulation.moisture import WATER_CONTENT
from ..values import CookedMaterial

VARIETY = "japonica"


def cooked_material(
    variety: str = VARIETY,
    water_content: float = WATER_CONTENT,
    sigma0_dry: float = SIGMA0_DRY,
    sigma0_wet: float = SIGMA0_WET,
) -> CookedMaterial:
    """The material of rice of ``variety`` at ``water_content`` %: the simulation's moisture factors
    (``moisture_scales``) and the shading's σ₀ (``sigma0_from_water``) and rice material (``rice_material``).
    The defaults are the ``cooked_rice`` node's: what a simulation or a scene without rice reads when no
    material is wired."""
    from ..shading.cdrf import sigma0_from_water
    from ..shading.materials import rice_material
    from ..simulation.moisture import moisture_scales

    scales = moisture_scales(water_content)
    return CookedMaterial(
        variety=variety,
        water_content=float(water_content),
        stiffness_scale=scales["stiffness"],
        friction_scale=scales["friction"],
        adhesion_scale=scales["adhesion"],
        sigma0=sigma0_from_water(water_content, sigma0_dry, sigma0_wet),
        optics=rice_material(water_content),
    )
