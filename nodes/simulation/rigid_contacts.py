"""Contacts between grains answered by the grains as rigid bodies — Müller et al. 2020, "Detailed rigid body
simulation with extended position based dynamics", eqs. 2–3.

A grain is a cluster of particles that shape matching holds together (``shape_matching``). Pushing only the two
touching particles (``contact_constraints.contact_sweep``) leaves shape matching to spread the push over the
grain, and it hands back only ≈ 1/n of it per pass: at 10 substeps × 2 iterations grains ended each solve inside
one another (docs/accuracy.md). Here each pair's correction moves both grains whole: the generalised inverse mass
of grain g at its particle p is w = 1/M + (r × n)ᵀ I⁻¹ (r × n), r = x_p − c_g; a correction that moves p by s
along n takes Δλ = s / w, translates the grain by Δλ·n/M and turns it by I⁻¹(r × Δλ·n) (a small rotation, which
shape matching then makes exact). The split of a correction between the two grains is the particles' rule
(``contact_constraints.split_share``: mass scaling by height, sleepers held still) on the generalised inverse
masses, and friction (``friction.pair_drift``) moves the grains the same way along the drift. A grain of one
particle has r = 0: it moves as the particle sweep moves it.

Gauss–Seidel stays race-free and deterministic by colouring grains, not particles: slabs along x as thick as the
largest x distance between the centres of two listed grains, coloured by slab index mod 3. Touching grains lie
in the same or adjacent slabs, so slabs of one colour share no grain and run in parallel; within a slab the
grains go from the lowest centre up (ties by index) and their pairs in list order: supports take their load before
the grains resting on them (the 890-grain ball at 10 × 2 stood at atan H/R 22.8° after 1 s, 18.2° in index order;
docs/accuracy.md). Compliant contacts (``squeeze_strain``) keep the particle sweep.
"""

import numpy as np
from numba import njit, prange

from .contact_constraints import pair_normal, sleeper_share, split_share
from .friction import RELEASE, ROLLS, TESTED, pair_drift, rubbed_share


@njit(cache=True)
def _body(x, w, r, start, g, centre, inv_mass, inv_inertia):
    """Centre, inverse mass and inverse inertia tensor (about the centre, from the particles as they stand, each
    a solid sphere) of grain g; inverse mass 0 when a particle of it is static."""
    s, e = start[g], start[g + 1]
    mass = 0.0
    cx = cy = cz = 0.0
    static = False
    for k in range(s, e):
        if w[k] <= 0.0:
            static = True
            break
        mk = 1.0 / w[k]
        mass += mk
        cx += mk * x[k, 0]
        cy += mk * x[k, 1]
        cz += mk * x[k, 2]
    if static or mass <= 0.0:
        inv_mass[g] = 0.0
        mass = cx = cy = cz = 0.0
        for k in range(s, e):
            mass += 1.0
            cx += x[k, 0]
            cy += x[k, 1]
            cz += x[k, 2]
        centre[g, 0], centre[g, 1], centre[g, 2] = cx / mass, cy / mass, cz / mass
        inv_inertia[g, :, :] = 0.0
        return
    cx /= mass
    cy /= mass
    cz /= mass
    centre[g, 0], centre[g, 1], centre[g, 2] = cx, cy, cz
    inv_mass[g] = 1.0 / mass
    a = np.zeros((3, 3))
    for k in range(s, e):
        mk = 1.0 / w[k]
        dx, dy, dz = x[k, 0] - cx, x[k, 1] - cy, x[k, 2] - cz
        own = 0.4 * mk * r[k] * r[k] + mk * (dx * dx + dy * dy + dz * dz)
        a[0, 0] += own - mk * dx * dx
        a[1, 1] += own - mk * dy * dy
        a[2, 2] += own - mk * dz * dz
        a[0, 1] -= mk * dx * dy
        a[0, 2] -= mk * dx * dz
        a[1, 2] -= mk * dy * dz
    a[1, 0], a[2, 0], a[2, 1] = a[0, 1], a[0, 2], a[1, 2]
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    inv = inv_inertia[g]
    inv[0, 0] = c00 / det
    inv[1, 0] = c01 / det
    inv[2, 0] = c02 / det
    inv[0, 1] = (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]) / det
    inv[1, 1] = (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]) / det
    inv[2, 1] = (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]) / det
    inv[0, 2] = (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]) / det
    inv[1, 2] = (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]) / det
    inv[2, 2] = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]) / det


@njit(cache=True, inline="always")
def _turn(inv, kx, ky, kz):
    """I⁻¹·k."""
    return (
        inv[0, 0] * kx + inv[0, 1] * ky + inv[0, 2] * kz,
        inv[1, 0] * kx + inv[1, 1] * ky + inv[1, 2] * kz,
        inv[2, 0] * kx + inv[2, 1] * ky + inv[2, 2] * kz,
    )


@njit(cache=True, inline="always")
def generalised(x, bodies, g, i, ux, uy, uz):
    """The generalised inverse mass of grain g (−1: a static particle, 0) at its particle i along the unit vector
    u: 1/M + (r × u)ᵀ I⁻¹ (r × u), r = x_i − c_g (Müller et al. 2020 eq. 2)."""
    if g < 0:
        return 0.0
    centre, inv_mass, inv_inertia = bodies
    if inv_mass[g] <= 0.0:
        return 0.0
    rx, ry, rz = x[i, 0] - centre[g, 0], x[i, 1] - centre[g, 1], x[i, 2] - centre[g, 2]
    kx, ky, kz = ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux
    ax, ay, az = _turn(inv_inertia[g], kx, ky, kz)
    return inv_mass[g] + kx * ax + ky * ay + kz * az


@njit(cache=True, inline="always")
def move_grain(x, start, bodies, g, i, ux, uy, uz, s):
    """Move grain g as a rigid body so that its particle i moves by s along the unit vector u: Δλ = s / w, the
    centre by Δλ·u/M, a turn of I⁻¹(r × Δλ·u) (Müller et al. 2020 eq. 3), each particle by Δx + θ × (x − c)."""
    if g < 0 or s == 0.0:
        return
    centre, inv_mass, inv_inertia = bodies
    im = inv_mass[g]
    if im <= 0.0:
        return
    cx, cy, cz = centre[g, 0], centre[g, 1], centre[g, 2]
    rx, ry, rz = x[i, 0] - cx, x[i, 1] - cy, x[i, 2] - cz
    kx, ky, kz = ry * uz - rz * uy, rz * ux - rx * uz, rx * uy - ry * ux
    ax, ay, az = _turn(inv_inertia[g], kx, ky, kz)
    lam = s / (im + kx * ax + ky * ay + kz * az)
    tx, ty, tz = lam * im * ux, lam * im * uy, lam * im * uz
    ox, oy, oz = lam * ax, lam * ay, lam * az
    angle = np.sqrt(ox * ox + oy * oy + oz * oz)
    sin = np.sin(angle)
    cos1 = 1.0 - np.cos(angle)
    if angle > 0.0:
        ox, oy, oz = ox / angle, oy / angle, oz / angle
    for k in range(start[g], start[g + 1]):  # Rodrigues: d cos φ + (k × d) sin φ + k (k·d)(1 − cos φ)
        dx, dy, dz = x[k, 0] - cx, x[k, 1] - cy, x[k, 2] - cz
        ex, ey, ez = oy * dz - oz * dy, oz * dx - ox * dz, ox * dy - oy * dx
        kd = ox * dx + oy * dy + oz * dz
        x[k, 0] += tx + sin * ex + cos1 * (ox * kd - dx)
        x[k, 1] += ty + sin * ey + cos1 * (oy * kd - dy)
        x[k, 2] += tz + sin * ez + cos1 * (oz * kd - dz)
    centre[g, 0] = cx + tx
    centre[g, 1] = cy + ty
    centre[g, 2] = cz + tz


@njit(cache=True, inline="always")
def push_pair(x, start, bodies, ga, gb, i, j, ux, uy, uz, amount, share):
    """Move particle i by ``share``·``amount`` along u and j by the rest against it, each with its grain."""
    move_grain(x, start, bodies, ga, i, ux, uy, uz, share * amount)
    move_grain(x, start, bodies, gb, j, -ux, -uy, -uz, amount - share * amount)


@njit(cache=True)
def _project_grain(x, x_prev, awake, pushed, model, rows, rowof, entries, rule, bodies, g):
    """Project, in list order, every pair listed in the rows of grain g's particles (each pair once: full rows
    from the lower index), the pair rule of ``contact_constraints._project_slab`` with rigid grains: friction
    first, then the normal correction, each moving both grains whole (``push_pair``)."""
    w, r, elem, start = model.w, model.r, model.elem, model.start
    nbr_start, nbr, half = rows.nbr_start, rows.nbr, rows.half
    allowance, anchor, load, held_mean, modes, rubbed, glued, _ = entries
    wake_step, lift, upright, mu_s, mu_k, anchored, normal, cohesion, _, _, _ = rule
    any_glued = glued.shape[0] > 0
    n_moving = start[start.shape[0] - 1]
    for i in range(start[g], start[g + 1]):
        p = rowof[i]
        for a in range(nbr_start[p], nbr_start[p + 1]):
            j = nbr[a]
            if not half and j < i:
                continue
            if not (awake[i] or awake[j]):
                continue
            nx, ny, nz, d = pair_normal(x, i, j)
            depth = r[i] + r[j] - d
            if depth <= 0.0:
                if anchored and mu_s > 0.0 and depth < -RELEASE * (r[i] + r[j]):
                    anchor[a, 0] = np.nan
                continue
            gb = elem[j] if j < n_moving else -1
            wa = generalised(x, bodies, g, i, nx, ny, nz)
            wb = generalised(x, bodies, gb, j, nx, ny, nz)
            if awake[i] and awake[j]:
                share = split_share(wa, wb, x[j, 2] - x[i, 2], nz, lift, upright)
            else:
                share = sleeper_share(x, x_prev, w, awake, pushed, i, j, wake_step)
            if share < 0.0:
                continue
            # loads and drifts as the particles' impulses: a correction s along u is the impulse s / (w_a + w_b) of
            # the grains, the particles' w_i + w_j times it in the particle sweep's units
            unit = (w[i] + w[j]) / (wa + wb)
            pen = depth - allowance[a] if normal else 0.0
            if mu_s > 0.0:
                mode = TESTED
                if anchored:
                    pooled = held_mean[a] > 0.0 and not (any_glued and glued[a]) and modes[a] != ROLLS
                    own = held_mean[a] if pooled else load[a] + max(pen, 0.0) * unit
                    held = own + cohesion * (w[i] + w[j])
                    if pooled:
                        mode = modes[a]
                else:
                    held = depth * unit
                t, tx, ty, tz = pair_drift(x, x_prev, anchor, a, i, j, (nx, ny, nz), anchored)
                if t > 1e-12:
                    ux, uy, uz = -tx / t, -ty / t, -tz / t
                    ta = generalised(x, bodies, g, i, ux, uy, uz)
                    tb = generalised(x, bodies, gb, j, ux, uy, uz)
                    slip = (w[i] + w[j]) / (ta + tb)
                    fr = (mu_s, mu_k, anchored)
                    scale = rubbed_share(rubbed, a, t * slip, tx * slip, ty * slip, tz * slip, held, fr, mode)
                    rub = ta / (ta + tb) if any_glued and glued[a] else share
                    push_pair(x, start, bodies, g, gb, i, j, ux, uy, uz, scale * t, rub)
                    if anchored and scale < 1.0:  # it slid: it sticks again, if at all, where it now is
                        for k in range(3):
                            anchor[a, k] = x[i, k] - x[j, k]
            if pen > 0.0:
                if anchored and mu_s > 0.0:
                    load[a] += pen * unit
                push_pair(x, start, bodies, g, gb, i, j, nx, ny, nz, pen, share)


@njit(cache=True, parallel=True)
def rigid_sweep(state, model, rows, entries, rule):
    """One Gauss–Seidel sweep of the contacts with rigid grains, in place: the arguments of
    ``contact_constraints.contact_sweep`` (``rule.alpha`` 0: rigid contacts) but the grid, which the grains'
    own colouring replaces. The result does not depend on the thread count."""
    x, x_prev, awake, pushed = state.x, state.x_prev, state.awake, state.pushed
    start, elem = model.start, model.elem
    nbr_start, nbr, order = rows.nbr_start, rows.nbr, rows.order
    m = start.shape[0] - 1
    n_moving = start[m]
    if m == 0:
        return
    centre = np.empty((m, 3))
    inv_mass = np.empty(m)
    inv_inertia = np.empty((m, 3, 3))
    for g in prange(m):
        _body(x, model.w, model.r, start, g, centre, inv_mass, inv_inertia)
    bodies = (centre, inv_mass, inv_inertia)
    rowof = np.empty(order.shape[0], np.int64)
    for p in prange(order.shape[0]):
        rowof[order[p]] = p
    # slab thickness: the largest x distance between the centres of two listed grains
    reach = np.zeros(m)
    for g in prange(m):
        most = 0.0
        for i in range(start[g], start[g + 1]):
            p = rowof[i]
            for a in range(nbr_start[p], nbr_start[p + 1]):
                j = nbr[a]
                if j < n_moving:
                    most = max(most, abs(centre[elem[j], 0] - centre[g, 0]))
        reach[g] = most
    thick = max(reach.max(), 1e-6) * (1.0 + 1e-9)
    low = centre[:, 0].min()
    slab = np.empty(m, np.int64)
    for g in range(m):
        slab[g] = int(np.floor((centre[g, 0] - low) / thick))
    slabs = slab.max() + 1
    first = np.zeros(slabs + 1, np.int64)  # grains by slab, in index order within each
    for g in range(m):
        first[slab[g] + 1] += 1
    for s in range(slabs):
        first[s + 1] += first[s]
    fill = first[:slabs].copy()
    grains = np.empty(m, np.int64)
    for g in range(m):
        grains[fill[slab[g]]] = g
        fill[slab[g]] += 1
    for s in prange(slabs):  # within a slab from the lowest grain up: supports take their load first
        run = grains[first[s] : first[s + 1]].copy()
        heights = np.empty(run.shape[0])
        for b in range(run.shape[0]):
            heights[b] = centre[run[b], 2]
        up = np.argsort(heights, kind="mergesort")
        for b in range(run.shape[0]):
            grains[first[s] + b] = run[up[b]]
    for colour in range(3):
        for k in prange((slabs - colour + 2) // 3):
            s = colour + 3 * k
            for b in range(first[s], first[s + 1]):
                _project_grain(x, x_prev, awake, pushed, model, rows, rowof, entries, rule, bodies, grains[b])
