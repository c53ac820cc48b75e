"""Buoyant parts inside an element: the ikura yolk rising through the white — SPEC §1 (G ch.5).

The yolk (mesh faces with ``parts == 1``) is a particle of its own inside its egg's cluster. In the
white of density ρ_w it feels gravity plus buoyancy, a = g·(1 − ρ_w/ρ_y) (upward when ρ_y < ρ_w),
a viscous drag towards the egg's velocity, and a containment constraint |x_y − c_egg| ≤ R_in − r_y
that keeps it inside the membrane. Its reaction on the much heavier egg (≈ 15 % of its mass) is
neglected.
"""

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .shape_matching import centre_of_mass, quat_to_matrix


class YolkMotion(NamedTuple):
    """What the yolk kernels take of one solve: the ``Control``'s buoyant acceleration, the solve h, the drag."""

    accel: np.ndarray  # (3,) mm/s²
    h: float  # s
    drag: float  # 1/s (``settings.YOLK_DRAG``)


@njit(cache=True, parallel=True)
def yolk_predict(yolks, state, model, room, motion):
    """Drag the yolk velocity towards its egg's mean velocity, add buoyant acceleration, move:
    v_y ← v_egg + (v_y − v_egg)·e^{−drag·h} + h·a, x_y ← x_y + h·v_y. ``yolks``: ``state.YolkArrays``,
    ``state``: ``StateArrays`` (v), ``model``: ``ModelArrays`` (w, start), ``room``: ``model.YolkRoom``
    (owner), ``motion``: ``YolkMotion``."""
    yx, yv, y_prev = yolks.x, yolks.v, yolks.x_prev
    v = state.v
    w, start = model.w, model.start
    owner = room.owner
    accel, h, drag_rate = motion.accel, motion.h, motion.drag
    k = yx.shape[0]
    relax = np.exp(-drag_rate * h)
    for y in prange(k):
        c = owner[y]
        ev = centre_of_mass(v, w, start[c], start[c + 1])  # the egg's velocity
        for d in range(3):
            y_prev[y, d] = yx[y, d]
            yv[y, d] = ev[d] + (yv[y, d] - ev[d]) * relax + h * accel[d]
            yx[y, d] += h * yv[y, d]


@njit(cache=True, parallel=True)
def yolk_contain(yolks, state, model, space, motion):
    """Project each yolk back inside its egg (|x_y − c| ≤ room, c = c_egg + R·centre) and set v = Δx/h.
    ``yolks``: ``state.YolkArrays``, ``state``: ``StateArrays`` (x, quats), ``model``: ``ModelArrays`` (w, start),
    ``space``: ``model.YolkRoom``, ``motion``: ``YolkMotion`` (h)."""
    yx, yv, y_prev = yolks.x, yolks.v, yolks.x_prev
    x, quats = state.x, state.quats
    w, start = model.w, model.start
    owner, centre_local, room = space.owner, space.centre, space.room
    h = motion.h
    k = yx.shape[0]
    for y in prange(k):
        c = owner[y]
        rot = np.empty((3, 3))
        quat_to_matrix(quats[c], rot)
        cx, cy, cz = centre_of_mass(x, w, start[c], start[c + 1])
        # scalar arithmetic, not ``rot @ v``: numba sends that to BLAS, whose spinning thread pool
        # took the cores from the parallel kernels (ikura don 8× slower under OpenMP)
        cx += rot[0, 0] * centre_local[y, 0] + rot[0, 1] * centre_local[y, 1] + rot[0, 2] * centre_local[y, 2]
        cy += rot[1, 0] * centre_local[y, 0] + rot[1, 1] * centre_local[y, 1] + rot[1, 2] * centre_local[y, 2]
        cz += rot[2, 0] * centre_local[y, 0] + rot[2, 1] * centre_local[y, 1] + rot[2, 2] * centre_local[y, 2]
        ox, oy, oz = yx[y, 0] - cx, yx[y, 1] - cy, yx[y, 2] - cz
        dist = np.sqrt(ox * ox + oy * oy + oz * oz)
        if dist > room[y]:
            f = room[y] / dist
            yx[y, 0] = cx + ox * f
            yx[y, 1] = cy + oy * f
            yx[y, 2] = cz + oz * f
        for d in range(3):
            yv[y, d] = (yx[y, d] - y_prev[y, d]) / h
