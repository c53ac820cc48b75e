"""Overlap refine and overlap depth with medial-sphere implicit functions — SPEC §2.5–2.7 (S eq. 1–3, G eq. 1–3).

Struct-of-arrays numba kernels. Element templates (one per kind × variant) hold medial spheres and
cost points in local coordinates (CSR by ``*_start``); elements hold position, rotation, normal,
template and search range. Neighbours come from a uniform grid. The refine visits elements in a
random order, once each; elements are greedily coloured in that order so one colour class (no two
members are neighbours) runs in parallel while the result stays the same for any thread count.

The kernels take their arrays in named bundles (``ElementFrames``, ``Neighbours``, ``TemplateShapes``,
``SearchRange``, ``RefineCost``, ``Bumps``: typed named tuples, which numba passes as one argument at
no cost), as Newton passes Model / State: an order slip between two same-typed arrays cannot happen.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ..spatial_grid import CellGrid, cell_keys, cell_starts, column_run, grid_shape, neighbour_block

SAKURAI, GAN = 0, 1
INV_PHI = (np.sqrt(5.0) - 1.0) / 2.0


class ElementFrames(NamedTuple):
    """Per element: where it is, how it is turned, the normal it moves along, its template."""

    positions: np.ndarray  # (n, 3) float64, moved in place by the refine
    rotations: np.ndarray  # (n, 3, 3)
    normals: np.ndarray  # (n, 3)
    template: np.ndarray  # (n,) int64, row of the TemplateShapes


class Neighbours(NamedTuple):
    """CSR neighbour lists: element i's neighbours are ``index[start[i]:start[i + 1]]``."""

    start: np.ndarray  # (n + 1,) int64
    index: np.ndarray  # int64


class TemplateShapes(NamedTuple):
    """The ``ElementTemplates`` arrays the kernels read: cost points and medial spheres per template (CSR)."""

    pts_start: np.ndarray  # (t + 1,) int64: template t's probe points are pts[pts_start[t]:pts_start[t + 1]]
    cost_end: np.ndarray  # (t,) int64: its refine cost points end here (the medial-sphere centres follow)
    pts: np.ndarray  # (p, 3) local frame
    sph_start: np.ndarray  # (t + 1,) int64: its spheres are centers/radii[sph_start[t]:sph_start[t + 1]]
    centers: np.ndarray  # (s, 3)
    radii: np.ndarray  # (s,)
    bound: np.ndarray  # (t,) radius outside which its implicit function is ≤ 0
    circumradius: np.ndarray  # (t,)


class SearchRange(NamedTuple):
    """Per element the refine's search interval [lo, hi] of offsets t, and the offset already travelled."""

    lo: np.ndarray  # (n,)
    hi: np.ndarray  # (n,)
    travelled: np.ndarray  # (n,) offset from the surface point before this pass


class RefineCost(NamedTuple):
    """The refine cost (S eq. 2 or G eq. 1) and its golden-section search."""

    kind: int  # SAKURAI or GAN
    slope: float  # S's a
    penalty: float  # G's r·C_refine
    offset: float  # T of G eq. 2
    iterations: int  # golden-section steps


class Bumps(NamedTuple):
    """Scratch of ``_gather_bumps``: (point, neighbour) pairs, CSR over their 1-D bumps in t."""

    pair_range: np.ndarray  # (pairs + 1,) int64: pair p's bumps are pair_range[p]:pair_range[p + 1]
    pair_lo: np.ndarray  # where the pair's bumps start and end in t
    pair_hi: np.ndarray
    t0: np.ndarray  # per bump: the t of the sphere's centre, its squared distance off the path, its radius
    perp2: np.ndarray
    r: np.ndarray
    lo: np.ndarray  # where the bump starts and ends in t
    hi: np.ndarray


@njit(cache=True)
def neighbour_lists(positions, reach):
    """CSR lists of all j ≠ i with ‖p_i − p_j‖ < reach_i + reach_j, from a grid of cell 2·max(reach)
    (``spatial_grid``).

    A row lists its neighbours in the grid's visiting order, and ``_overlap_at`` sums the overlaps in that
    order, so the order is part of the refine's result. Within a cell the elements come in the order of
    numba's ``np.argsort`` of the cell keys (its quicksort: not stable), as they always have; the grid's
    stable ``counting_sort`` would list tied elements in id order and move the refine in the last bits.
    The grid's cell starts are dense (8 bytes a cell), so the cell doubles while there would be more than
    64·n + 4 Mi cells (32 MiB): only sparse scenes hundreds of cells across reach that, and there the rows
    hold the same neighbours in another order (the searchsorted lookups before 2026-12 needed no guard)."""
    n = positions.shape[0]
    cell = 2.0 * reach.max() + 1e-12
    lo = np.empty(3)
    hi = np.empty(3)
    for d in range(3):
        lo[d] = positions[:, d].min() - 1e-9
        hi[d] = positions[:, d].max()
    dims, cell = grid_shape(lo, hi, cell, 64 * n + 4 * 1024 * 1024)
    keys = cell_keys(positions, lo, dims, cell)
    order = np.argsort(keys)
    grid = CellGrid(cell_starts(keys, dims[0] * dims[1] * dims[2]), order, lo, dims, cell)
    counts = np.zeros(n + 1, np.int64)
    for sweep in range(2):
        if sweep == 1:
            for i in range(n):
                counts[i + 1] += counts[i]
            out = np.empty(counts[n], np.int64)
            fill = counts[:n].copy()
        for i in range(n):
            x0, x1, y0, y1, z0, z1 = neighbour_block(grid, positions[i, 0], positions[i, 1], positions[i, 2])
            for gx in range(x0, x1):
                for gy in range(y0, y1):
                    q0, q1 = column_run(grid, gx, gy, z0, z1)
                    for q in range(q0, q1):
                        j = order[q]
                        if j == i:
                            continue
                        dist2 = ((positions[i] - positions[j]) ** 2).sum()
                        limit = reach[i] + reach[j]
                        if dist2 < limit * limit:
                            if sweep == 0:
                                counts[i + 1] += 1
                            else:
                                out[fill[i]] = j
                                fill[i] += 1
    return counts, out


@njit(cache=True)
def colour_in_order(order, nb_start, nb):
    """Greedy graph colouring visiting elements in ``order``; returns colour per element."""
    n = order.shape[0]
    colour = np.full(n, -1, np.int64)
    used = np.full(n + 1, -1, np.int64)
    for step in range(n):
        i = order[step]
        for e in range(nb_start[i], nb_start[i + 1]):
            c = colour[nb[e]]
            if c >= 0:
                used[c] = i
        c = 0
        while used[c] == i:
            c += 1
        colour[i] = c
    return colour


@njit(cache=True, inline="always")
def _local(rot, x0, x1, x2, out):
    """out = rotᵀ·x: a world-frame vector in an element's local frame (scalar code: no temporaries)."""
    out[0] = rot[0, 0] * x0 + rot[1, 0] * x1 + rot[2, 0] * x2
    out[1] = rot[0, 1] * x0 + rot[1, 1] * x1 + rot[2, 1] * x2
    out[2] = rot[0, 2] * x0 + rot[1, 2] * x1 + rot[2, 2] * x2


@njit(cache=True)
def _implicit(q0, q1, q2, centers, radii, s0, s1, offset):
    """f(q) = max_s (r_s − ‖q − c_s‖) − T (G eq. 2 / S eq. 3), in the template's local frame."""
    best = -np.inf
    for s in range(s0, s1):
        dx = q0 - centers[s, 0]
        dy = q1 - centers[s, 1]
        dz = q2 - centers[s, 2]
        v = radii[s] - np.sqrt(dx * dx + dy * dy + dz * dz)
        if v > best:
            best = v
    return best - offset


@njit(cache=True)
def _gather_bumps(i, frames, search, neighbours, shapes, offset, world, bumps):
    """Overlap of i with its neighbours as 1-D bumps in t (S eq. 2 made one-dimensional).

    A cost point x moving as x + t·n passes sphere s of neighbour j with depth
    r_s − sqrt(perp² + (t − t0)²); only spheres that the path enters deeper than T within
    [t_lo, t_hi] are kept, grouped by (point, neighbour) pair. Returns (pairs, bumps), or (-1, -1)
    when the buffers are too small.
    """
    positions, rotations, normals, template = frames.positions, frames.rotations, frames.normals, frames.template
    pts, centers, radii, bound = shapes.pts, shapes.centers, shapes.radii, shapes.bound
    ti = template[i]
    lo, hi = search.lo[i], search.hi[i]
    n0, n1, n2 = normals[i, 0], normals[i, 1], normals[i, 2]
    ri = rotations[i]
    k0, k1 = shapes.pts_start[ti], shapes.cost_end[ti]
    for k in range(k0, k1):
        for d in range(3):
            world[k - k0, d] = ri[d, 0] * pts[k, 0] + ri[d, 1] * pts[k, 1] + ri[d, 2] * pts[k, 2]
    a = np.empty(3)
    b = np.empty(3)
    npairs = 0
    nbumps = 0
    cap_pairs, cap_bumps = bumps.pair_lo.shape[0], bumps.t0.shape[0]
    for e in range(neighbours.start[i], neighbours.start[i + 1]):
        j = neighbours.index[e]
        tj = template[j]
        dx = positions[j, 0] - positions[i, 0]
        dy = positions[j, 1] - positions[i, 1]
        dz = positions[j, 2] - positions[i, 2]
        along = min(max(dx * n0 + dy * n1 + dz * n2, lo), hi)
        ex, ey, ez = dx - along * n0, dy - along * n1, dz - along * n2
        reach = shapes.circumradius[ti] + bound[tj]
        if ex * ex + ey * ey + ez * ez >= reach * reach:
            continue  # i's swept bounding sphere misses j's implicit function
        rj = rotations[j]
        _local(rj, n0, n1, n2, b)
        bb = bound[tj] * bound[tj]
        s0, s1 = shapes.sph_start[tj], shapes.sph_start[tj + 1]
        for k in range(k1 - k0):
            _local(rj, world[k, 0] - dx, world[k, 1] - dy, world[k, 2] - dz, a)
            ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
            t_near = min(max(-ab, lo), hi)
            q0, q1, q2 = a[0] + t_near * b[0], a[1] + t_near * b[1], a[2] + t_near * b[2]
            if q0 * q0 + q1 * q1 + q2 * q2 >= bb:
                continue
            first = nbumps
            plo, phi = np.inf, -np.inf
            for s in range(s0, s1):
                depth = radii[s] - offset
                if depth <= 0.0:
                    continue
                u0, u1, u2 = a[0] - centers[s, 0], a[1] - centers[s, 1], a[2] - centers[s, 2]
                ub = u0 * b[0] + u1 * b[1] + u2 * b[2]
                perp2 = u0 * u0 + u1 * u1 + u2 * u2 - ub * ub
                if perp2 >= depth * depth:
                    continue
                half = np.sqrt(depth * depth - perp2)
                t0 = -ub
                if t0 + half <= lo or t0 - half >= hi:
                    continue
                if nbumps == cap_bumps:
                    return -1, -1
                bumps.t0[nbumps] = t0
                bumps.perp2[nbumps] = perp2
                bumps.r[nbumps] = radii[s]
                bumps.lo[nbumps] = t0 - half
                bumps.hi[nbumps] = t0 + half
                plo = min(plo, t0 - half)
                phi = max(phi, t0 + half)
                nbumps += 1
            if nbumps > first:
                if npairs == cap_pairs:
                    return -1, -1
                bumps.pair_range[npairs] = first
                bumps.pair_range[npairs + 1] = nbumps
                bumps.pair_lo[npairs] = plo
                bumps.pair_hi[npairs] = phi
                npairs += 1
    return npairs, nbumps


@njit(cache=True)
def _overlap_at(t, npairs, bumps, offset, use_max):
    """Σ (or max) over (point, neighbour) pairs of the neighbour's implicit function f > 0 at x + t·n."""
    total = 0.0
    for p in range(npairs):
        if t <= bumps.pair_lo[p] or t >= bumps.pair_hi[p]:
            continue
        best = 0.0
        for q in range(bumps.pair_range[p], bumps.pair_range[p + 1]):
            if bumps.lo[q] < t < bumps.hi[q]:
                dt = t - bumps.t0[q]
                v = bumps.r[q] - np.sqrt(bumps.perp2[q] + dt * dt) - offset
                if v > best:
                    best = v
        if use_max:
            total = max(total, best)
        else:
            total += best
    return total


@njit(cache=True)
def _cost(t, cost, npairs, bumps, start):
    """S eq. 2: Σ f(x + t·n) + a·|t|;  G eq. 1: a(max f(x + t·n)) + t with a(h) = h + r·C_refine if h > 0.

    ``start`` is the offset from the surface already travelled in earlier passes: the travel term counts
    from the surface point, not from the current position.
    """
    if cost.kind == SAKURAI:
        return _overlap_at(t, npairs, bumps, cost.offset, False) + cost.slope * abs(start + t)
    h = _overlap_at(t, npairs, bumps, cost.offset, True)
    return (h + cost.penalty if h > 0.0 else 0.0) + start + t


@njit(cache=True)
def _golden_section(lo, hi, cost, npairs, bumps, start):
    """Golden-section search for the minimum of the cost on [lo, hi] (S §3.2.1, fig. 8)."""
    if npairs == 0:
        return min(max(-start, lo), hi)  # no overlap anywhere in the range: as close to the surface as allowed
    x1 = hi - INV_PHI * (hi - lo)
    x2 = lo + INV_PHI * (hi - lo)
    f1 = _cost(x1, cost, npairs, bumps, start)
    f2 = _cost(x2, cost, npairs, bumps, start)
    for _ in range(cost.iterations):
        if f1 <= f2:
            hi, x2, f2 = x2, x1, f1
            x1 = hi - INV_PHI * (hi - lo)
            f1 = _cost(x1, cost, npairs, bumps, start)
        else:
            lo, x1, f1 = x1, x2, f2
            x2 = lo + INV_PHI * (hi - lo)
            f2 = _cost(x2, cost, npairs, bumps, start)
    return 0.5 * (lo + hi)


@njit(cache=True)
def _bump_buffers(capacity):
    """Scratch for _gather_bumps: ``capacity`` (point, neighbour) pairs and 4× as many bumps."""
    return Bumps(
        np.empty(capacity + 1, np.int64),
        np.empty(capacity),
        np.empty(capacity),
        np.empty(4 * capacity),
        np.empty(4 * capacity),
        np.empty(4 * capacity),
        np.empty(4 * capacity),
        np.empty(4 * capacity),
    )


@njit(cache=True)
def _refine_chunk(members, frames, search, neighbours, shapes, cost, max_pts, offsets):
    """Refine a run of mutually independent elements with one set of scratch buffers (grown on demand)."""
    capacity = 1024
    world = np.empty((max_pts, 3))
    bumps = _bump_buffers(capacity)
    for i in members:
        while True:
            npairs, _ = _gather_bumps(i, frames, search, neighbours, shapes, cost.offset, world, bumps)
            if npairs >= 0:
                break
            capacity *= 4  # the buffers were too small: grow them and gather again
            bumps = _bump_buffers(capacity)
        t = _golden_section(search.lo[i], search.hi[i], cost, npairs, bumps, search.travelled[i])
        offsets[i] = t
        for d in range(3):
            frames.positions[i, d] += t * frames.normals[i, d]


@njit(cache=True, parallel=True)
def refine_offsets(frames, search, neighbours, colour, order, shapes, cost, chunks):
    """Offsets t per element (``frames.positions`` updated in place), colour class by colour class in ``order``.

    ``search.travelled``: each element's offset from its surface point before this pass (0 on the first).

    Each class is split into ``chunks`` contiguous runs processed in parallel; members of a class are
    not neighbours, so the result does not depend on the thread count.
    """
    n = frames.positions.shape[0]
    offsets = np.zeros(n)
    colours = colour.max() + 1
    class_start = np.zeros(colours + 1, np.int64)
    for i in range(n):
        class_start[colour[i] + 1] += 1
    for c in range(colours):
        class_start[c + 1] += class_start[c]
    members = np.empty(n, np.int64)
    fill = class_start[:colours].copy()
    for step in range(n):
        i = order[step]
        members[fill[colour[i]]] = i
        fill[colour[i]] += 1
    max_pts = np.int64(0)  # not the literal 0: _refine_chunk would compile for Literal[int](0) and again for int64
    for t in range(shapes.pts_start.shape[0] - 1):
        max_pts = max(max_pts, shapes.pts_start[t + 1] - shapes.pts_start[t])
    for c in range(colours):
        start, size = class_start[c], class_start[c + 1] - class_start[c]
        parts = min(chunks, size)
        for part in prange(parts):
            lo = start + (size * part) // parts
            hi = start + (size * (part + 1)) // parts
            _refine_chunk(members[lo:hi], frames, search, neighbours, shapes, cost, max_pts, offsets)
    return offsets


@njit(cache=True)
def _depth_into(i, j, frames, shapes, offset):
    """max over i's cost points of j's implicit function (how deep i reaches into j), 0 if nowhere."""
    positions, rotations, template = frames.positions, frames.rotations, frames.template
    pts, bound = shapes.pts, shapes.bound
    ti, tj = template[i], template[j]
    dx = positions[i, 0] - positions[j, 0]
    dy = positions[i, 1] - positions[j, 1]
    dz = positions[i, 2] - positions[j, 2]
    reach = shapes.circumradius[ti] + bound[tj]
    if dx * dx + dy * dy + dz * dz >= reach * reach:
        return 0.0
    ri, rj = rotations[i], rotations[j]
    bb = bound[tj] * bound[tj]
    q = np.empty(3)
    best = 0.0
    s0, s1 = shapes.sph_start[tj], shapes.sph_start[tj + 1]
    for k in range(shapes.pts_start[ti], shapes.pts_start[ti + 1]):
        w0 = ri[0, 0] * pts[k, 0] + ri[0, 1] * pts[k, 1] + ri[0, 2] * pts[k, 2] + dx
        w1 = ri[1, 0] * pts[k, 0] + ri[1, 1] * pts[k, 1] + ri[1, 2] * pts[k, 2] + dy
        w2 = ri[2, 0] * pts[k, 0] + ri[2, 1] * pts[k, 1] + ri[2, 2] * pts[k, 2] + dz
        _local(rj, w0, w1, w2, q)
        if q[0] * q[0] + q[1] * q[1] + q[2] * q[2] < bb:
            best = max(best, _implicit(q[0], q[1], q[2], shapes.centers, shapes.radii, s0, s1, offset))
    return best


@njit(cache=True)
def _depth_of(i, alive, frames, neighbours, shapes, offset):
    """The deepest overlap of i with any live neighbour, both ways (``_depth_into``)."""
    best = 0.0
    for e in range(neighbours.start[i], neighbours.start[i + 1]):
        j = neighbours.index[e]
        if alive[j]:
            best = max(best, _depth_into(i, j, frames, shapes, offset), _depth_into(j, i, frames, shapes, offset))
    return best


@njit(cache=True, parallel=True)
def overlap_depths(frames, neighbours, alive, shapes, offset):
    """Per element the deepest overlap with any live neighbour, both ways (SPEC §2.7 reading of G eq. 3)."""
    n = frames.positions.shape[0]
    depth = np.zeros(n)
    for i in prange(n):
        if alive[i]:
            # i as int64: the parallel body types it unsigned, and _depth_of and _depth_into compiled twice more
            depth[i] = _depth_of(np.int64(i), alive, frames, neighbours, shapes, offset)
    return depth


@njit(cache=True)
def cull_deepest(depth, threshold, frames, neighbours, shapes, offset):
    """Remove elements deepest first while their overlap with the still-live neighbours exceeds the threshold."""
    n = depth.shape[0]
    alive = np.ones(n, np.bool_)
    order = np.argsort(-depth, kind="mergesort")
    for step in range(n):
        i = order[step]
        if depth[i] <= threshold:
            break
        if _depth_of(i, alive, frames, neighbours, shapes, offset) > threshold:
            alive[i] = False
    return alive
