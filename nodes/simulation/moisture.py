"""Water content → material scale factors — SPEC §3 (G §2.2, Tomita et al.) and §4.

G gives trends, not a law: the elastic modulus falls with soaking time, pores open (0.02 → 4.72 µm²
from 0 to 120 min), viscosity falls. Our reading, with water content w in % of grain mass
(G renders 0–24 %): stiffness × 1/(1 + w/10) (softening), friction × (1 − w/60) (lubrication:
−40 % at 24 %), adhesion × w/(w + 8) (no capillary bridges when dry, saturating when wet).
"""

from typing import NamedTuple

WATER_CONTENT = 15.0  # % — the default cooked rice (G's renders span 0–24 %; 15 % is the rice of G ch.5's bowls)


def moisture_scales(water_content: float) -> dict[str, float]:
    """Multipliers for stiffness, friction and adhesion at ``water_content`` percent."""
    w = float(water_content)
    if w < 0:
        raise ValueError(f"water_content must be ≥ 0 %, got {w}")
    return {"stiffness": 1.0 / (1.0 + w / 10.0), "friction": max(0.0, 1.0 - w / 60.0), "adhesion": w / (w + 8.0)}


class MoistureFactors(NamedTuple):
    """The factors a ``CookedMaterial`` carries, by the same names: what the solver reads of a material."""

    stiffness_scale: float
    friction_scale: float
    adhesion_scale: float


def moisture_factors(water_content: float) -> MoistureFactors:
    """``moisture_scales`` as the fields of a cooked material: the simulation's factors when none is wired."""
    scales = moisture_scales(water_content)
    return MoistureFactors(scales["stiffness"], scales["friction"], scales["adhesion"])
