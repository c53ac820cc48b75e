"""Per-vertex colour from the CDRF under a set of lights — SPEC §4 (eq. 7–9).

Each light contributes ``I·c·[(1 − s)·base·max(cos θ, 0) + s·subsurface·f_r(θ, σ₀|κ|)]``: the
material's subsurface weight ``s`` blends Lambert with the curvature-dependent term, so thin,
curved, wet parts glow past the terminator. An ambient term keeps unlit sides readable.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cdrf import CdrfTable, curvature_sigma


@dataclass(frozen=True)
class Light:
    """A distant light: unit ``direction`` towards the light, linear RGB ``color``, ``intensity``."""

    direction: np.ndarray
    color: np.ndarray
    intensity: float


def make_lights(directions, colors, intensities) -> list[Light]:
    """Lights from parallel parameter lists, with clear errors for mismatches and dark lights."""
    if not directions:
        raise ValueError("light_directions: at least one light is needed")
    if len(colors) not in (1, len(directions)) or len(intensities) not in (1, len(directions)):
        raise ValueError(
            f"light_colors ({len(colors)}) and light_intensities ({len(intensities)}) must give "
            f"one value or one per light ({len(directions)} directions)"
        )
    lights = []
    for k, direction in enumerate(directions):
        d = np.asarray(direction, np.float64)
        norm = np.linalg.norm(d)
        if not norm > 0:
            raise ValueError(f"light_directions[{k}]: a zero vector has no direction")
        intensity = float(intensities[k % len(intensities)])
        if not intensity > 0:
            raise ValueError(
                f"light_intensities[{k}] = {intensity}: a light must have intensity > 0 (remove the light instead)"
            )
        color = np.asarray(colors[k % len(colors)], np.float64)
        check_color(color, f"light_colors[{k}]")
        lights.append(Light(d / norm, color, intensity))
    return lights


def check_color(color, name: str) -> None:
    """Linear RGB in [0, 1] (G Table 3 prints 0–256 for 8-bit values; divide by 255)."""
    c = np.asarray(color, np.float64)
    if c.shape != (3,) or not np.all(np.isfinite(c)) or c.min() < 0.0 or c.max() > 1.0:
        raise ValueError(f"{name} = {c.tolist()}: colours are linear RGB, three values in [0, 1]")


def cdrf_colors(
    normals: np.ndarray,
    curvature: np.ndarray,
    base: np.ndarray,
    subsurface: np.ndarray,
    weight: np.ndarray,
    sigma0: float,
    lights: list[Light],
    ambient: float,
    table: CdrfTable,
) -> np.ndarray:
    """Linear RGB per vertex (n, 3), clipped to [0, 1]; ``base``/``subsurface`` are (n, 3) or (3,)."""
    sigma = curvature_sigma(curvature, sigma0)
    weight = np.asarray(weight, np.float64).reshape(-1, 1) if np.ndim(weight) else float(weight)
    color = ambient * np.broadcast_to(base, normals.shape)
    for light in lights:
        cos = np.clip(normals @ light.direction, -1.0, 1.0)
        lambert = np.maximum(cos, 0.0)[:, None]
        bleed = table(np.arccos(cos), sigma)[:, None]
        color = color + light.intensity * light.color * ((1.0 - weight) * base * lambert + weight * subsurface * bleed)
    return np.clip(color, 0.0, 1.0)
