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
    """Cooked (or raw) rice at a water content in % — translucency, whiteness, gloss grow with water."""
    if not 0.0 <= water <= WATER_MAX:
        raise ValueError(f"water_content {water} % is outside 0–{WATER_MAX:g} %")
    t = water / WATER_MAX
    return Material(
        name=name,
        base_color=_mix((0.62, 0.55, 0.40), (0.86, 0.85, 0.80), t),
        subsurface=0.25 + 0.6 * t,
        subsurface_radius=_mix((0.3, 0.2, 0.1), (1.2, 0.9, 0.6), t),
        subsurface_color=_mix((0.80, 0.72, 0.55), (0.95, 0.93, 0.88), t),
        specular=0.5,
        roughness=0.65 - 0.3 * t,
        clearcoat=0.4 * t,
        clearcoat_roughness=0.1,
        ior=1.45 - 0.08 * t,
    )


def ikura_materials() -> tuple[Material, Material]:
    """(membrane, yolk): a translucent orange skin with a wet clearcoat around an oil-yellow yolk."""
    membrane = Material(
        name="ikura_membrane",
        base_color=(0.85, 0.12, 0.02),
        subsurface=0.8,
        subsurface_radius=(2.0, 0.6, 0.2),
        subsurface_color=(0.95, 0.25, 0.04),
        specular=0.5,
        roughness=0.08,
        clearcoat=1.0,
        clearcoat_roughness=0.03,
        ior=1.36,
        transmission=0.4,
    )
    yolk = Material(
        name="ikura_yolk",
        base_color=(0.95, 0.40, 0.04),
        subsurface=0.5,
        subsurface_radius=(1.0, 0.4, 0.1),
        subsurface_color=(1.0, 0.45, 0.05),
        roughness=0.2,
        ior=1.47,
        transmission=0.2,
    )
    return membrane, yolk


def ice_materials(syrup_color) -> tuple[Material, Material]:
    """(plain ice, syrup-soaked ice): transmissive, IOR 1.31; the syrup tints and thickens it."""
    ice = Material(
        name="ice",
        base_color=(0.92, 0.96, 1.0),
        subsurface=0.1,
        subsurface_color=(0.9, 0.95, 1.0),
        roughness=0.15,
        ior=1.31,
        transmission=1.0,
    )
    syrup = Material(
        name="ice_syrup",
        base_color=tuple(float(c) for c in syrup_color),
        subsurface=0.4,
        subsurface_radius=(1.0, 0.3, 0.3),
        subsurface_color=tuple(float(c) for c in syrup_color),
        roughness=0.1,
        clearcoat=0.5,
        ior=1.31,
        transmission=0.6,
    )
    return ice, syrup


def ceramic_material(color) -> Material:
    """The bowl (scenery): a glazed ceramic."""
    return Material(
        name="ceramic",
        base_color=tuple(float(c) for c in color),
        roughness=0.3,
        clearcoat=0.6,
        clearcoat_roughness=0.05,
        ior=1.5,
    )


def syrup_mask(heights: np.ndarray, coverage: float) -> np.ndarray:
    """Elements in the top ``coverage`` share of the mound's height carry syrup (poured from above)."""
    if len(heights) == 0 or coverage <= 0:
        return np.zeros(len(heights), bool)
    lo, hi = heights.min(), heights.max()
    return heights >= hi - coverage * (hi - lo)
