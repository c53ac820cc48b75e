"""Principled material presets per element kind — G Table 3 colour columns, SPEC §4.

Colours are linear RGB in [0, 1]; lengths (subsurface radius) in mm. Cooked rice is interpolated
by water content (0–24 %, SPEC §4): wetter grains are whiter, more translucent and glossier (a
water film: clearcoat). Ikura has two parts (``Mesh.parts``: 0 membrane, 1 yolk); kakigori ice is
transmissive (IOR 1.31) and the flakes at the top of the mound carry syrup.
"""

from __future__ import annotations

import numpy as np

from ..values import Material
from .cdrf import WATER_MAX

PRESETS = ("rice", "ikura", "ice")
_KIND_WORDS = {
    "rice": ("rice", "japonica", "indica", "aromatic", "grain"),
    "ikura": ("ikura", "roe", "egg"),
    "ice": ("ice", "kakigori", "flake"),
}


def preset_for_kind(kind: str, overrides: dict[str, str]) -> str:
    """The preset of an element kind: an explicit ``kind=preset`` override, else by the kind's name."""
    if kind in overrides:
        return overrides[kind]
    for preset, words in _KIND_WORDS.items():
        if any(word in kind.lower() for word in words):
            return preset
    raise ValueError(
        f"element kind '{kind}' matches no material preset; name it in parameter 'presets' "
        f"as '{kind}=<preset>' with <preset> one of {', '.join(PRESETS)}"
    )


def parse_overrides(entries: list[str]) -> dict[str, str]:
    """``["japonica=rice", ...]`` → dict, refusing unknown presets and malformed entries."""
    out = {}
    for entry in entries:
        kind, sep, preset = entry.partition("=")
        if not sep or not kind or preset not in PRESETS:
            raise ValueError(f"presets entry '{entry}': expected 'kind=preset' with preset one of {', '.join(PRESETS)}")
        out[kind] = preset
    return out


def _mix(dry, wet, t):
    return tuple(float(a + (b - a) * t) for a, b in zip(dry, wet))


def rice_material(water: float, name: str = "rice") -> Material:
    """Cooked (or raw) rice at a water content in % — translucency, whiteness, gloss grow with water.

    ``subsurface`` scales the CDRF's diffuse transmission (``cdrf.translucency``, per vertex from σ₀|κ|);
    the water film adds a clearcoat and a sheen at grazing angles (G fig. 3.1.2.1: dull at 0 %, glossy at 24 %).
    """
    if not 0.0 <= water <= WATER_MAX:
        raise ValueError(f"water_content {water} % is outside 0–{WATER_MAX:g} %")
    t = water / WATER_MAX
    return Material(
        name=name,
        base_color=_mix((0.66, 0.60, 0.47), (0.90, 0.89, 0.84), t),
        subsurface=0.3 + 0.6 * t,
        subsurface_radius=_mix((0.3, 0.2, 0.1), (1.2, 0.9, 0.6), t),
        subsurface_color=_mix((0.80, 0.72, 0.55), (0.96, 0.94, 0.88), t),
        specular=0.5,
        roughness=0.7 - 0.35 * t,
        sheen=0.6 * t,
        sheen_tint=0.3,
        clearcoat=0.5 * t,
        clearcoat_roughness=0.25 - 0.15 * t,
        ior=1.45 - 0.08 * t,
    )


def ikura_materials() -> tuple[Material, Material]:
    """(membrane, yolk): a clear dielectric skin (IOR 1.36) holding an orange fluid, around an oil yolk.

    Both are transmissive: ``subsurface_color`` is the colour light keeps after crossing the part (absorption
    over ``subsurface_radius`` mm), so the yolk shows through the membrane as a deeper, frosted orange core
    (oil, IOR 1.47, in the egg fluid). All-specular eggs also keep the preview's caustic noise low: no diffuse
    surface inside an egg is lit only through its skin.
    """
    membrane = Material(
        name="ikura_membrane",
        base_color=(0.90, 0.20, 0.02),
        subsurface=0.0,
        subsurface_radius=(4.0, 1.2, 0.5),
        subsurface_color=(0.97, 0.30, 0.045),
        specular=0.5,
        roughness=0.2,
        clearcoat=1.0,
        clearcoat_roughness=0.02,
        ior=1.36,
        transmission=1.0,
        transmission_roughness=0.2,
    )
    yolk = Material(
        name="ikura_yolk",
        base_color=(1.0, 0.55, 0.10),
        subsurface=0.0,
        subsurface_radius=(1.0, 0.4, 0.1),
        subsurface_color=(1.0, 0.70, 0.30),
        roughness=0.3,
        ior=1.47,
        exterior_ior=1.36,
        transmission=1.0,
        transmission_roughness=0.3,
    )
    return membrane, yolk


def ice_materials(syrup_color) -> tuple[Material, Material]:
    """(plain ice, syrup-soaked ice): transmissive, IOR 1.31, slightly frosted; the syrup tints and glosses it."""
    ice = Material(
        name="ice",
        base_color=(0.92, 0.96, 1.0),
        subsurface=0.1,
        subsurface_radius=(5.0, 5.0, 5.0),
        subsurface_color=(0.9, 0.95, 1.0),
        roughness=0.15,
        ior=1.31,
        transmission=1.0,
        transmission_roughness=0.15,
    )
    syrup = Material(
        name="ice_syrup",
        base_color=tuple(float(c) for c in syrup_color),
        subsurface=0.4,
        subsurface_radius=(1.0, 0.3, 0.3),
        subsurface_color=tuple(float(c) for c in syrup_color),
        roughness=0.05,
        clearcoat=0.8,
        clearcoat_roughness=0.03,
        ior=1.31,
        transmission=0.9,
        transmission_roughness=0.05,
    )
    return ice, syrup


def ceramic_material(color) -> Material:
    """The bowl (scenery): a glazed ceramic — a coloured body under a glossy clear glaze."""
    return Material(
        name="ceramic",
        base_color=tuple(float(c) for c in color),
        roughness=0.35,
        clearcoat=1.0,
        clearcoat_roughness=0.04,
        ior=1.5,
    )


def syrup_mask(heights: np.ndarray, coverage: float) -> np.ndarray:
    """Elements in the top ``coverage`` share of the mound's height carry syrup (poured from above)."""
    if len(heights) == 0 or coverage <= 0:
        return np.zeros(len(heights), bool)
    lo, hi = heights.min(), heights.max()
    return heights >= hi - coverage * (hi - lo)
