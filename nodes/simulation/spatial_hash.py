"""Per-particle neighbour lists (CSR) for the contact family — SPEC §3.

Hand-written in numba rather than scipy's cKDTree because the lists are rebuilt every substep and
must skip same-element pairs. Particles are counting-sorted into a dense grid over their bounding
box (``nodes.spatial_grid``: z fastest, so the 27 neighbour cells of a particle are 9 contiguous
runs of the sorted order). The cell size grows if the box would need more than
``MAX_CELLS_PER_PARTICLE``·n cells (a scattered or exploding scene), which only makes the search
coarser, never wrong.

The grid is also the contacts' graph colouring (``contact_constraints.contact_sweep``): a
particle's neighbours lie in the 27 cells around its own at build time, so slabs of cells whose x
indices agree modulo 3 share no particle and can be solved in parallel.
"""

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ..spatial_grid import CellGrid, build_grid, column_run, neighbour_block

MAX_CELLS_PER_PARTICLE = 64
ROW_CAPACITY = 16  # list slots per particle in the single scan (a settled pile lists ≈ 5 half / 10 full)


class SortedParticles(NamedTuple):
    """Position, radius and element of each particle in the grid's sorted order (a cell's run is contiguous)."""

    x: np.ndarray  # (n, 3)
    r: np.ndarray  # (n,)
    elem: np.ndarray  # (n,) int64


@njit(cache=True, inline="always")
def _visit(particles, grid, p, reach, half, n_active, out, write_at, cap):
    """Count the neighbours of sorted particle p from other elements, writing the first ``cap``
    of them to out[write_at:] (cap = 0: count only).

    With ``half`` each moving pair is found once, from the partner that comes first in the
    cell-sorted order (q > p): the runs before p are skipped, so half the cells are scanned;
    static partners (ids ≥ ``n_active``, whose own rows stay empty) are kept from either side.
    Works on the cell-sorted copies ``particles`` (contiguous memory for a cell's run) and
    writes the partners' sorted positions q (their ids are order[q]).
    """
    xs, rs, es = particles.x, particles.r, particles.elem
    order = grid.order
    px, py, pz = xs[p, 0], xs[p, 1], xs[p, 2]
    x0, x1, y0, y1, z0, z1 = neighbour_block(grid, px, py, pz)
    statics = n_active < xs.shape[0]
    mine = es[p]
    rp = rs[p] + reach
    found = 0
    for gx in range(x0, x1):
        for gy in range(y0, y1):
            q0, q1 = column_run(grid, gx, gy, z0, z1)
            if half and not statics:
                q0 = max(q0, p + 1)
            for q in range(q0, q1):
                if half and q < p and order[q] < n_active:
                    continue
                ex = xs[q, 0] - px
                ey = xs[q, 1] - py
                ez = xs[q, 2] - pz
                lim = rp + rs[q]
                if ex * ex + ey * ey + ez * ez <= lim * lim and es[q] != mine:
                    if found < cap:
                        out[write_at + found] = q
                    found += 1
    return found


@njit(cache=True, parallel=True)
def neighbour_lists(x, r, elem, reach, cell_size, n_active, half):
    """CSR lists of particles j of another element with |x_i − x_j| ≤ r_i + r_j + reach, and the
    grid they were found in: (nbr_start, nbr, at, cell_start, order, dims); ``nbr`` holds the partners'
    particle ids, ``at`` their rows (sorted positions), so that the sweep can work on sorted copies.

    Rows are stored in the grid's sorted order: row p, nbr[nbr_start[p]:nbr_start[p + 1]], lists the
    partners of particle order[p]. The Gauss–Seidel sweep walks the particles in that order, so it
    reads the per-entry arrays (partners, allowance, anchors, load) front to back; stored by particle id,
    each row was a jump in memory, and at 50k particles the sweep took 1.8× as long on a 1 MiB-L2 core.

    ``cell_size`` must be ≥ 2·max(r) + reach. One parallel scan into fixed slots, then a
    compacting copy (a count pass and a fill pass scanned every cell twice). Rows of
    particles i ≥ ``n_active`` (static obstacles, which come last) stay empty: every pair with a
    static particle is listed from its moving partner, and the pair kernels only need that side.
    ``half``: each pair is listed once, in the row of the partner that comes first in the grid's
    cell order (static partners: in the moving one's row) — all the Gauss–Seidel contacts need, at
    half the scan; the Jacobi adhesion kernel needs full rows,
    where the pair kernels take each pair from its lower index.
    """
    n = x.shape[0]
    lo = np.empty(3)
    for k in range(3):
        lo[k] = x[:, k].min()
    start, order, lo, dims, cell = build_grid(x, lo, cell_size, MAX_CELLS_PER_PARTICLE * n + 4096)
    grid = CellGrid(start, order, lo, dims, cell)  # built here: a parallel loop finds a named tuple's class at its call
    xs = np.empty((n, 3))
    rs = np.empty(n)
    es = np.empty(n, np.int64)
    for p in prange(n):
        i = order[p]
        xs[p, 0] = x[i, 0]
        xs[p, 1] = x[i, 1]
        xs[p, 2] = x[i, 2]
        rs[p] = r[i]
        es[p] = elem[i]
    particles = SortedParticles(xs, rs, es)
    # one scan into ROW_CAPACITY slots per particle, then a compacting copy; rows that overflow
    # (deep overlaps, dense adhesion rows) are scanned again straight into the lists
    counts = np.zeros(n + 1, np.int64)
    slots = np.empty(n * ROW_CAPACITY, np.int64)
    for p in prange(n):
        if order[p] < n_active:
            counts[p + 1] = _visit(particles, grid, p, reach, half, n_active, slots, p * ROW_CAPACITY, ROW_CAPACITY)
    for p in range(n):
        counts[p + 1] += counts[p]
    at = np.empty(counts[n], np.int64)
    for p in prange(n):
        if order[p] < n_active:
            c = counts[p + 1] - counts[p]
            if c <= ROW_CAPACITY:
                for k in range(c):
                    at[counts[p] + k] = slots[p * ROW_CAPACITY + k]
            else:
                _visit(particles, grid, p, reach, half, n_active, at, counts[p], c)
    nbr = np.empty_like(at)
    for a in prange(at.shape[0]):
        nbr[a] = order[at[a]]
    return counts, nbr, at, start, order, dims
