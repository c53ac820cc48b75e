"""Curvature-dependent reflectance (CDRF) — SPEC §4 (G §3.1.2, Kubo et al.): eq. 7–9.

``f_r(θ, κ) = (L_i * g)(θ)`` with ``L_i(θ) = max(cos θ, 0)`` (eq. 8) and a Gaussian ``g`` of width
``σ(κ) = σ₀·|κ|`` (eq. 9): light bleeds past the terminator on strongly curved, translucent parts.
Three evaluations of the same integral, all pure functions of arrays:

- ``cdrf_exact``: closed form (complex error function) — the reference.
- ``cdrf_quadrature``: the convolution integral by n-point Gauss–Legendre quadrature.
- ``CdrfTable``: the fitted approximation: a (θ, σ) grid of exact values, bilinear lookup — what
  ``shade`` uses per vertex (accuracy vs cost: ``benchmarks/bench_shading.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

WATER_MAX = 24.0  # % — the range G rendered (water absorbed at 5 °C), SPEC §4
SIGMA0_DRY = 0.15  # rad·mm at 0 % water (the cooked_rice node's default)
SIGMA0_WET = 1.2  # rad·mm at 24 % water
SIGMA_MAX = 3.0  # rad — beyond this the kernel is flat over the lit half-circle (f_r ≈ 1/π·…); clamped


def sigma0_from_water(water: float, sigma0_dry: float, sigma0_wet: float) -> float:
    """σ₀ from a log–log line through (1 + 0 %, σ₀_dry) and (1 + 24 %, σ₀_wet) — SPEC §4.

    G fits log σ₀ against log water content; its fitted constants are not printed, so the line's end
    points are parameters. ``1 + w`` keeps the dry end (w = 0) finite on the log axis.
    """
    if not 0.0 <= water <= WATER_MAX:
        raise ValueError(f"water_content {water} % is outside the fitted range 0–{WATER_MAX:g} %")
    if sigma0_dry <= 0 or sigma0_wet <= 0:
        raise ValueError(f"sigma0_dry and sigma0_wet must be > 0 (log–log fit), got {sigma0_dry}, {sigma0_wet}")
    slope = np.log(sigma0_wet / sigma0_dry) / np.log(1.0 + WATER_MAX)
    return float(sigma0_dry * (1.0 + water) ** slope)


def curvature_sigma(curvature: np.ndarray, sigma0: float) -> np.ndarray:
    """σ(κ) ≈ σ₀·|κ| (eq. 9), clamped to ``SIGMA_MAX``; concave and convex bend light alike."""
    return np.minimum(sigma0 * np.abs(curvature), SIGMA_MAX)


def cdrf_exact(theta: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Eq. 7 in closed form: ∫_{−π/2}^{π/2} cos u · N(u; θ, σ²) du.

    With u = θ + σt and cos u = Re e^{iu}, completing the square gives
    ``Re e^{iθ−σ²/2}·[Φ((π/2−θ)/σ − iσ) − Φ((−π/2−θ)/σ − iσ)]``, Φ the normal CDF of a complex
    argument (``scipy.special.erf``). σ → 0 gives max(cos θ, 0).
    """
    from scipy.special import erf

    theta, sigma = np.broadcast_arrays(
        np.atleast_1d(np.asarray(theta, np.float64)), np.atleast_1d(np.asarray(sigma, np.float64))
    )
    out = np.maximum(np.cos(theta), 0.0)
    wide = sigma > 1e-6
    t, s = theta[wide], np.minimum(sigma[wide], SIGMA_MAX)
    root2 = np.sqrt(2.0)
    upper = erf(((np.pi / 2 - t) / s - 1j * s) / root2)
    lower = erf(((-np.pi / 2 - t) / s - 1j * s) / root2)
    out[wide] = np.real(np.exp(1j * t - 0.5 * s * s) * 0.5 * (upper - lower))
    return out


def cdrf_quadrature(theta: np.ndarray, sigma: np.ndarray, nodes: int = 16) -> np.ndarray:
    """Eq. 7 as the convolution integral over the lit half-circle by Gauss–Legendre quadrature."""
    theta, sigma = np.broadcast_arrays(np.asarray(theta, np.float64), np.asarray(sigma, np.float64))
    u, w = np.polynomial.legendre.leggauss(nodes)
    u, w = u * np.pi / 2, w * np.pi / 2
    s = np.maximum(np.minimum(sigma, SIGMA_MAX), 1e-6)[..., None]
    kernel = np.exp(-0.5 * ((u - theta[..., None]) / s) ** 2) / (np.sqrt(2 * np.pi) * s)
    out = np.sum(w * np.cos(u) * kernel, axis=-1)
    return np.where(sigma > 1e-6, out, np.maximum(np.cos(theta), 0.0))


@dataclass(frozen=True)
class CdrfTable:
    """The fitted approximation of eq. 7: exact values on a θ × σ grid, looked up bilinearly."""

    values: np.ndarray  # (n_theta, n_sigma)
    sigma_max: float

    @classmethod
    def build(cls, n_theta: int = 64, n_sigma: int = 32, sigma_max: float = SIGMA_MAX) -> CdrfTable:
        if n_theta < 2 or n_sigma < 2:
            raise ValueError(f"a CDRF table needs at least 2 × 2 samples, got {n_theta} × {n_sigma}")
        theta = np.linspace(0.0, np.pi, n_theta)
        sigma = np.linspace(0.0, sigma_max, n_sigma)
        return cls(cdrf_exact(theta[:, None], sigma[None, :]), sigma_max)

    def __call__(self, theta: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        n_theta, n_sigma = self.values.shape
        x = np.clip(np.asarray(theta, np.float64), 0.0, np.pi) * ((n_theta - 1) / np.pi)
        y = np.clip(np.asarray(sigma, np.float64), 0.0, self.sigma_max) * ((n_sigma - 1) / self.sigma_max)
        i = np.minimum(x.astype(np.int64), n_theta - 2)
        j = np.minimum(y.astype(np.int64), n_sigma - 2)
        fx, fy = x - i, y - j
        v = self.values
        return (1 - fx) * ((1 - fy) * v[i, j] + fy * v[i, j + 1]) + fx * ((1 - fy) * v[i + 1, j] + fy * v[i + 1, j + 1])


def _past_terminator_share(sigma: np.ndarray, nodes: int = 96) -> np.ndarray:
    """Share of the CDRF response (eq. 7) over the sphere of light directions that lies past the terminator."""
    u, w = np.polynomial.legendre.leggauss(nodes)
    theta = (u + 1.0) * np.pi / 2  # (0, π)
    weights = w * np.sin(theta)
    response = cdrf_exact(theta[None, :], np.asarray(sigma, np.float64)[:, None]) * weights
    past = theta > np.pi / 2
    return response[:, past].sum(axis=1) / np.maximum(response.sum(axis=1), 1e-12)


_SHARE_SIGMA = np.linspace(0.0, SIGMA_MAX, 64)


@cache
def _share_table() -> np.ndarray:
    """``_past_terminator_share`` on ``_SHARE_SIGMA``, computed at the first use (not at import: it loads
    scipy.special, about half a second of every run, a cached re-run included)."""
    return _past_terminator_share(_SHARE_SIGMA)


def translucency(sigma: np.ndarray) -> np.ndarray:
    """The CDRF as a diffuse-transmission weight in [0, 1] — SPEC §4 eq. 7–9 evaluated in a path tracer.

    Eq. 7 lets light reach a point from past its terminator; a path tracer gets the same effect from light
    that passes through the grain (diffuse transmission). The weight is the share of the CDRF's response, over
    all light directions, that comes from past the terminator, normalised so that 1 is an even split (a
    thin diffuser): σ → 0 (Lambert) gives 0, σ = 0.9 rad (a grain at 15 % water) 0.45, ``SIGMA_MAX`` 0.9.
    """
    share = np.interp(np.asarray(sigma, np.float64), _SHARE_SIGMA, _share_table())
    return np.clip(share / 0.5, 0.0, 1.0)
