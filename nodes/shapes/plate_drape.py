"""A topping draped over an aggregate: a thin elastic plate resting on the aggregate's top — the fish on
nigiri (issue 17; G ch.4 sushi rice). Pure functions of arrays, called by the ``drape`` node.

The slab's bottom surface w(u, v) over a grid in the slab's own plan minimises a Kirchhoff plate's energy
(ν = 0 form) under its load, resting on the aggregate's upper envelope H (an obstacle problem):

    min_w  ½·D·∫(w_uu² + 2·w_uv² + w_vv²) dA + ∫ q·w dA   subject to  w ≥ H where the aggregate is,

with D = E·t³/12 the bending stiffness and q = ρ·g·t + p the weight per area plus the press of the hand.
Finite differences on the grid; solved by a primal–dual active set (each step one sparse solve with the
touching nodes held at H). The slab keeps its length: along u, the draped rows are re-parametrised by arc
length, so a drooping end is pulled in rather than stretched. Units: mm, kg, s (so pressures are in kPa).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PlateGrid:
    """Grid nodes (i, j) at u = u0 + i·h, v = v0 + j·h in the slab's plan."""

    u0: float
    v0: float
    h: float
    nu: int
    nv: int

    @classmethod
    def covering(cls, length: float, width: float, h: float) -> PlateGrid:
        nu, nv = int(np.ceil(length / h)) + 3, int(np.ceil(width / h)) + 3
        return cls(-0.5 * (nu - 1) * h, -0.5 * (nv - 1) * h, h, nu, nv)

    @property
    def u(self) -> np.ndarray:
        return self.u0 + self.h * np.arange(self.nu)

    @property
    def v(self) -> np.ndarray:
        return self.v0 + self.h * np.arange(self.nv)


def upper_envelope(points_uvz: np.ndarray, grid: PlateGrid) -> np.ndarray:
    """(nu, nv) highest z of the points binned to their nearest node; −inf where no point falls."""
    i = np.rint((points_uvz[:, 0] - grid.u0) / grid.h).astype(np.int64)
    j = np.rint((points_uvz[:, 1] - grid.v0) / grid.h).astype(np.int64)
    inside = (i >= 0) & (i < grid.nu) & (j >= 0) & (j < grid.nv)
    envelope = np.full(grid.nu * grid.nv, -np.inf)
    np.maximum.at(envelope, i[inside] * grid.nv + j[inside], points_uvz[inside, 2])
    return envelope.reshape(grid.nu, grid.nv)


def _second_differences(n: int, h: float):
    """(n − 2, n) second difference along one axis, 1/h²."""
    import scipy.sparse as sp

    return sp.diags([1.0, -2.0, 1.0], [0, 1, 2], shape=(n - 2, n)) / h**2


def _first_differences(n: int, h: float):
    import scipy.sparse as sp

    return sp.diags([-1.0, 1.0], [0, 1], shape=(n - 1, n)) / h


def plate_stiffness(grid: PlateGrid, bending: float):
    """K with wᵀKw/2 = D/2·Σ h²·(w_uu² + 2·w_uv² + w_vv²): the plate's bending energy (free edges: the
    differences are taken only where both neighbours exist, so affine w costs nothing)."""
    import scipy.sparse as sp

    iu, iv = sp.identity(grid.nu), sp.identity(grid.nv)
    duu = sp.kron(_second_differences(grid.nu, grid.h), iv)
    dvv = sp.kron(iu, _second_differences(grid.nv, grid.h))
    duv = sp.kron(_first_differences(grid.nu, grid.h), _first_differences(grid.nv, grid.h))
    k = duu.T @ duu + dvv.T @ dvv + 2.0 * (duv.T @ duv)
    return (bending * grid.h**2 * k).tocsr()


def drape_plate(envelope: np.ndarray, grid: PlateGrid, bending: float, load: float, max_steps: int = 60) -> np.ndarray:
    """The plate's rest shape w (nu, nv) on the obstacle ``envelope`` (−inf: nothing underneath): the
    primal–dual active set method on the energy above (``plate_stiffness``, load ``q·h²`` per node)."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve

    obstacle = envelope.ravel()
    supported = np.isfinite(obstacle)
    if not supported.any():
        raise ValueError("the slab has nothing under it: the aggregate does not reach under the slab's plan")
    k = plate_stiffness(grid, bending)
    # a tiny spring to the mean support height keeps K positive definite while fewer than three nodes touch
    spring = 1e-12 * k.diagonal().mean()
    k = k + sp.identity(k.shape[0]) * spring
    f = np.full(k.shape[0], load * grid.h**2) - spring * obstacle[supported].mean()
    active = supported.copy()
    w = np.where(supported, obstacle, obstacle[supported].max())
    for _ in range(max_steps):
        free = ~active
        w[active] = obstacle[active]
        if free.any():
            rhs = -f[free] - k[free][:, active] @ w[active]
            w[free] = spsolve(k[free][:, free].tocsc(), rhs)
        reaction = k @ w + f  # ≥ 0 where the envelope holds the plate up
        tolerance = 1e-9 * max(1.0, np.abs(reaction).max())
        now = supported & np.where(active, reaction > tolerance, w < obstacle - 1e-9)
        if np.array_equal(now, active):
            break
        if not now.any():  # released everywhere: the plate would fall off; keep the highest support
            now = supported & (obstacle == obstacle[supported].max())
        active = now
    else:
        raise ValueError(f"the drape did not settle in {max_steps} active-set steps; raise the grid cell")
    return w.reshape(grid.nu, grid.nv)


def arc_lengths(w: np.ndarray, grid: PlateGrid, axis: int) -> np.ndarray:
    """(nu, nv) arc length of the draped surface along u (axis 0) or v (axis 1), 0 on the slab's centre line:
    a rest coordinate lands where this equals it (the slab bends, it does not stretch)."""
    steps = np.sqrt(grid.h**2 + np.diff(w, axis=axis) ** 2)
    zero = np.zeros((1, grid.nv)) if axis == 0 else np.zeros((grid.nu, 1))
    s = np.concatenate([zero, np.cumsum(steps, axis=axis)], axis=axis)
    along = grid.u if axis == 0 else grid.v
    lines = s if axis == 0 else s.T
    centre = np.array([np.interp(0.0, along, line) for line in lines.T])
    return s - (centre[None, :] if axis == 0 else centre[:, None])


def _unroll(rest: np.ndarray, across: np.ndarray, s: np.ndarray, along: np.ndarray, h: float, start: float):
    """Positions along a grid axis whose arc length (``s``: one column per line across) equals ``rest``,
    interpolated between the two lines bracketing each point's coordinate ``across``."""
    k = np.clip((across - start) / h, 0.0, s.shape[1] - 1.000001)
    k0 = np.floor(k).astype(np.int64)
    b = k - k0
    out = np.empty(len(rest))
    for line in np.unique(k0):
        mask = k0 == line
        a0 = np.interp(rest[mask], s[:, line], along)
        a1 = np.interp(rest[mask], s[:, line + 1], along)
        out[mask] = a0 * (1 - b[mask]) + a1 * b[mask]
    return out


def _bilinear(values: np.ndarray, grid: PlateGrid, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    x = np.clip((u - grid.u0) / grid.h, 0.0, grid.nu - 1.000001)
    y = np.clip((v - grid.v0) / grid.h, 0.0, grid.nv - 1.000001)
    i, j = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    a, b = x - i, y - j
    return (
        values[i, j] * (1 - a) * (1 - b)
        + values[i + 1, j] * a * (1 - b)
        + values[i, j + 1] * (1 - a) * b
        + values[i + 1, j + 1] * a * b
    )


def drape_points(local: np.ndarray, thickness: float, w: np.ndarray, grid: PlateGrid) -> np.ndarray:
    """Flat slab points (U, V, z), z ∈ [−t/2, t/2] about the mid-plane, onto the draped surface: U → u by
    arc length along u, then V → v by arc length along v (``arc_lengths``), the bottom (z = −t/2) on w, the
    rest offset along the surface normal."""
    u = _unroll(local[:, 0], local[:, 1], arc_lengths(w, grid, 0), grid.u, grid.h, grid.v0)
    v = _unroll(local[:, 1], u, arc_lengths(w, grid, 1).T, grid.v, grid.h, grid.u0)
    wu = np.gradient(w, grid.h, axis=0)
    wv = np.gradient(w, grid.h, axis=1)
    normal = np.stack([-_bilinear(wu, grid, u, v), -_bilinear(wv, grid, u, v), np.ones(len(local))], axis=1)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    bottom = np.stack([u, v, _bilinear(w, grid, u, v)], axis=1)
    return bottom + (local[:, 2:3] + 0.5 * thickness) * normal


def rounded_slab(length: float, width: float, thickness: float, corner: float, cell: float):
    """A flat slab, rounded in plan (corner radius ``corner``) and along every edge (radius t/2), centred at
    the origin: (vertices, faces), closed and outward (marching cubes of its signed distance)."""
    from nodes.elements.level_set_mesh import field_surface

    corner = min(corner, 0.5 * width, 0.5 * length)
    edge = 0.5 * thickness
    pad = 2 * cell
    axes = [np.arange(-0.5 * e - pad, 0.5 * e + pad + cell, cell) for e in (length, width, thickness)]
    u, v, z = np.meshgrid(*axes, indexing="ij")
    # rounded rectangle in plan (shrunk by the edge radius), then rounded along its rim
    qu, qv = np.abs(u) - (0.5 * length - corner), np.abs(v) - (0.5 * width - corner)
    plan = np.hypot(np.maximum(qu, 0), np.maximum(qv, 0)) + np.minimum(np.maximum(qu, qv), 0) - corner
    du, dz = plan + edge, np.abs(z) - (0.5 * thickness - edge)
    distance = np.hypot(np.maximum(du, 0), np.maximum(dz, 0)) + np.minimum(np.maximum(du, dz), 0) - edge
    origin = np.array([a[0] for a in axes])
    return field_surface(-distance.astype(np.float32), origin, cell, 0.0)


def fat_lines(local_centres: np.ndarray, width: float, spacing: float, line_width: float, angle: float, chevron: float):
    """Face part per face: 1 (fat) on thin parallel chevrons across the slab, 0 (flesh) elsewhere: the myosepta
    (the sheets of connective tissue and fat between the muscle's flakes, "folded and nested in complex W-like
    shapes", McGee, On Food and Cooking, 2004) where a slice cuts them. A nigiri's slice is a few cm of the
    fillet's width, so it shows one fold of the W: each line a chevron whose arms run back ``chevron`` mm over
    half the slab's width from its apex (``flake_phase``), every line the same shape a flake further on. Across
    the line (not along the slab) a line is ``line_width`` wide on average, swelling and thinning a little along
    its length (``LINE_SWELL``: a sheet meets the knife at an angle that changes along it). 0 spacing: no fat."""
    if spacing <= 0:
        return np.zeros(len(local_centres), np.int32)
    phase, stretch = flake_phase(local_centres, width, angle, chevron)
    line = np.floor(phase / spacing)  # which sheet: each swells at its own places
    along = local_centres[:, 1] * np.cos(np.radians(angle)) - local_centres[:, 0] * np.sin(np.radians(angle))
    swell = 1.0 + LINE_SWELL * np.sin(LINE_SWELL_WAVE * along + 2.4 * line)
    return (np.mod(phase, spacing) < line_width * swell * stretch).astype(np.int32)


def flake_phase(local_centres: np.ndarray, width: float, angle: float, chevron: float):
    """(phase, stretch) of points on the flat slab: the phase (mm) grows by one flake's spacing from one fat line
    to the next; lines run at ``angle`` degrees to the slab's width, bent into a chevron at ``CHEVRON_APEX`` of
    the width off its middle (the horizontal septum), drifting a little (``CHEVRON_DRIFT``: a sheet is not a ruled
    surface). ``stretch`` is the phase's gradient, so a width in phase over it is a width across the line."""
    u, v = local_centres[:, 0], local_centres[:, 1]
    a = np.radians(angle)
    normal, along = u * np.cos(a) + v * np.sin(a), v * np.cos(a) - u * np.sin(a)
    half = 0.5 * width
    x = (along - CHEVRON_APEX * width) / half
    drift = CHEVRON_DRIFT * np.sin(0.31 * u + 0.17 * v + 1.3)
    slope = chevron / half * x / np.sqrt(x * x + CHEVRON_CORNER**2)  # d(bend)/d(along)
    return normal + chevron * _soft_abs(x) + drift, np.sqrt(1.0 + slope * slope)


def flake_relief(local: np.ndarray, thickness: float, width: float, spacing: float, angle: float, chevron: float):
    """Height (mm) added to the slab's top at flat-slab points ``local`` (U, V, z): each flake between two fat
    lines a low dome ``FLAKE_RELIEF`` high, down to 0 at the lines, fading out over the rounded rim (z from the
    top face down to the mid-plane). A cut fillet's flakes stand a little proud of the sheets between them, and
    the wet film on them catches the key as a run of glints, one a flake, where a flat face shows one smear."""
    if spacing <= 0:
        return np.zeros(len(local))
    phase, _ = flake_phase(local, width, angle, chevron)
    dome = np.sin(np.pi * np.mod(phase, spacing) / spacing) ** 2
    top = np.clip(2.0 * local[:, 2] / thickness, 0.0, 1.0) ** 4  # 1 on the top face, 0 at the mid-plane
    return FLAKE_RELIEF * dome * top


CHEVRON_DRIFT = 0.3  # mm: how far a line wanders from its chevron (≈ 20 mm waves)
CHEVRON_APEX = 0.15  # the chevron's apex (the horizontal septum) off the slab's middle, a share of its width
# a line's width runs from (1 − swell) to (1 + swell) times its mean along its length, over ≈ 10 mm waves
LINE_SWELL, LINE_SWELL_WAVE = 0.25, 0.6
# the chevron's apex rounded over this share of the half-width (a sheet bends, it does not fold)
CHEVRON_CORNER = 0.08
FLAKE_RELIEF = 0.2  # mm: a flake's dome over the fat lines beside it (chosen: under the 0.5 mm cell of a drape)


def _soft_abs(x: np.ndarray) -> np.ndarray:
    return np.sqrt(x * x + CHEVRON_CORNER**2) - CHEVRON_CORNER
