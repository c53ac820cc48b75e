"""Mesh-level depenetration after the XPBD relaxation — SPEC §2.6 (overlap refine), on the meshes.

The particle clusters are a proxy: their spheres lie inside the element (``clusters``), so two
elements whose spheres only touch may still cut into each other where the spheres leave the surface
uncovered, and the contact solver tolerates a little residual overlap. This pass removes what is
left on the element meshes themselves: every vertex of an element's outer shell is tested against
each neighbour's signed distance field φ (its local grid, built with the cluster, carried through
the neighbour's map x = D·R·u + t), and the pair is pushed apart along the neighbour's outward
normal ∇φ by the deepest vertex's depth −φ, half each (a position-level contact C = φ(x) ≥ 0 with
equal masses, SPEC §3); a vertex in a collider wall (the free-space field φ_c < 0) pushes its element
out along ∇φ_c. Gauss–Seidel over the pairs from the lowest up, a few sweeps until no vertex is
deeper than the tolerance. Elements only translate: rotations, deformations and bends stay the
solver's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from .collider import sample_phi


@dataclass(frozen=True, eq=False)
class ShapeFields:
    """Per distinct element mesh: φ on its local grid (padded to one shape, φ > 0 outside), the grid's
    origin, pitch and true size, and the outer shell's vertices (CSR ``sstart``)."""

    phi: np.ndarray  # (s, nx, ny, nz)
    origin: np.ndarray  # (s, 3)
    pitch: np.ndarray  # (s,)
    dims: np.ndarray  # (s, 3) int64, the unpadded grid size
    surface: np.ndarray  # (v, 3) local vertices of every shape's outer shell
    sstart: np.ndarray  # (s + 1,)


def shape_fields(clusters) -> ShapeFields:
    """Stack the fields and shells of ``clusters`` (``ElementCluster`` with ``field`` set), in order."""
    dims = np.array([c.field.shape for c in clusters], np.int64)
    top = dims.max(axis=0)
    phi = np.empty((len(clusters), *top))
    for s, c in enumerate(clusters):
        phi[s] = np.inf  # beyond a shape's own grid: free space (never read: ``dims`` bounds the lookups)
        nx, ny, nz = c.field.shape
        phi[s, :nx, :ny, :nz] = c.field
    surface = np.concatenate([c.surface for c in clusters])
    sstart = np.concatenate([[0], np.cumsum([len(c.surface) for c in clusters])]).astype(np.int64)
    return ShapeFields(
        phi,
        np.array([c.field_origin for c in clusters], np.float64),
        np.array([c.field_pitch for c in clusters], np.float64),
        dims,
        np.ascontiguousarray(surface, np.float64),
        sstart,
    )


@njit(cache=True, inline="always")
def _world(v, lin, rot, bend, t, x):
    """x = L·v + R·B·m(v) + t (``Aggregate.element_points``), m(v) = [x², y², z², xy, yz, zx]."""
    m0, m1, m2 = v[0] * v[0], v[1] * v[1], v[2] * v[2]
    m3, m4, m5 = v[0] * v[1], v[1] * v[2], v[2] * v[0]
    b0 = bend[0, 0] * m0 + bend[0, 1] * m1 + bend[0, 2] * m2 + bend[0, 3] * m3 + bend[0, 4] * m4 + bend[0, 5] * m5
    b1 = bend[1, 0] * m0 + bend[1, 1] * m1 + bend[1, 2] * m2 + bend[1, 3] * m3 + bend[1, 4] * m4 + bend[1, 5] * m5
    b2 = bend[2, 0] * m0 + bend[2, 1] * m1 + bend[2, 2] * m2 + bend[2, 3] * m3 + bend[2, 4] * m4 + bend[2, 5] * m5
    for a in range(3):
        x[a] = lin[a, 0] * v[0] + lin[a, 1] * v[1] + lin[a, 2] * v[2] + t[a]
        x[a] += rot[a, 0] * b0 + rot[a, 1] * b1 + rot[a, 2] * b2


@njit(cache=True)
def vertices_inside(
    i, j, shape, lin, inv, rot, bend, t, phi, origin, pitch, dims, surface, sstart, sign, normals, depths, count
):
    """Element i's shell vertices inside element j: from row ``count`` on, each one's depth −φⱼ into
    ``depths`` and j's unit outward normal there, times ``sign``, into ``normals`` (world space:
    ∇ₓφ = (D·R)⁻ᵀ ∇ᵤφ; j's bend ignored: small). Returns the new count."""
    sj = shape[j]
    hi0 = origin[sj, 0] + (dims[sj, 0] - 1) * pitch[sj]
    hi1 = origin[sj, 1] + (dims[sj, 1] - 1) * pitch[sj]
    hi2 = origin[sj, 2] + (dims[sj, 2] - 1) * pitch[sj]
    u = np.empty(3)
    n = np.empty(3)
    x = np.empty(3)
    for k in range(sstart[shape[i]], sstart[shape[i] + 1]):
        _world(surface[k], lin[i], rot[i], bend[i], t[i], x)
        for a in range(3):
            u[a] = inv[j, a, 0] * (x[0] - t[j, 0]) + inv[j, a, 1] * (x[1] - t[j, 1]) + inv[j, a, 2] * (x[2] - t[j, 2])
        if u[0] <= origin[sj, 0] or u[1] <= origin[sj, 1] or u[2] <= origin[sj, 2]:
            continue
        if u[0] >= hi0 or u[1] >= hi1 or u[2] >= hi2:
            continue
        val, gx, gy, gz = sample_phi(phi[sj], origin[sj], pitch[sj], u[0], u[1], u[2])
        if val >= 0.0:
            continue
        for a in range(3):
            n[a] = inv[j, 0, a] * gx + inv[j, 1, a] * gy + inv[j, 2, a] * gz
        norm = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        if norm > 0.0:
            for a in range(3):
                normals[count, a] = sign * n[a] / norm
            depths[count] = -val
            count += 1
    return count


@njit(cache=True)
def separating_translation(normals, depths, count, out):
    """A short translation T of element i relative to j with T·nₖ ≥ dₖ for the penetrating vertices
    (cyclic projections onto the half-spaces, Kaczmarz, from T = 0): the deepest vertex's normal alone
    misleads when two elements cross deeply, where the normals on either side disagree."""
    out[:] = 0.0
    for _ in range(16):
        moved = False
        for k in range(count):
            short = depths[k] - (out[0] * normals[k, 0] + out[1] * normals[k, 1] + out[2] * normals[k, 2])
            if short > 1e-9:
                for a in range(3):
                    out[a] += short * normals[k, a]
                moved = True
        if not moved:
            break


@njit(cache=True)
def wall_depth(i, centre, shape, lin, rot, bend, t, surface, sstart, cphi, corigin, cpitch, push):
    """Depth of element i's deepest shell vertex inside a collider wall (0 if none); ``push`` gets the
    unit direction of the depth-weighted sum of wall normals, back to free space. A vertex's depth is
    measured from where the segment from the element's centre ``centre`` (in free space) enters the
    wall, along the normal there: a vertex past the middle of a thin wall is still pushed back to the
    element's side (−φ_c and ∇φ_c alone would send it out through the far side)."""
    deepest = 0.0
    push[:] = 0.0
    if not sample_phi(cphi, corigin, cpitch, centre[0], centre[1], centre[2])[0] > 0.0:
        return 0.0  # the element straddles the wall (placed across it): no translation frees it
    e = np.empty(3)
    x = np.empty(3)
    for k in range(sstart[shape[i]], sstart[shape[i] + 1]):
        _world(surface[k], lin[i], rot[i], bend[i], t[i], x)
        val = sample_phi(cphi, corigin, cpitch, x[0], x[1], x[2])[0]
        if not val < 0.0:
            continue
        lo, hi = 0.0, 1.0  # bisection for the entry point e = centre + s·(x − centre), φ_c(e) = 0
        for _ in range(12):
            mid = 0.5 * (lo + hi)
            for a in range(3):
                e[a] = centre[a] + mid * (x[a] - centre[a])
            if sample_phi(cphi, corigin, cpitch, e[0], e[1], e[2])[0] > 0.0:
                lo = mid
            else:
                hi = mid
        for a in range(3):
            e[a] = centre[a] + hi * (x[a] - centre[a])
        _, gx, gy, gz = sample_phi(cphi, corigin, cpitch, e[0], e[1], e[2])
        norm = np.sqrt(gx * gx + gy * gy + gz * gz)
        if norm <= 0.0:
            continue
        depth = ((e[0] - x[0]) * gx + (e[1] - x[1]) * gy + (e[2] - x[2]) * gz) / norm
        depth = max(depth, -val)
        push[0] += depth * gx / norm
        push[1] += depth * gy / norm
        push[2] += depth * gz / norm
        deepest = max(deepest, depth)
    norm = np.sqrt(push[0] ** 2 + push[1] ** 2 + push[2] ** 2)
    if norm <= 0.0:
        return 0.0
    push /= norm
    return deepest


@njit(cache=True)
def _wall(i, centre, radius, shape, lin, rot, bend, t, surface, sstart, cphi, corigin, cpitch, push):
    """``wall_depth`` of element i, 0 at once when its bounding sphere is in free space."""
    mid = np.empty(3)
    for a in range(3):
        mid[a] = centre[i, a] + t[i, a]
    if sample_phi(cphi, corigin, cpitch, mid[0], mid[1], mid[2])[0] > radius[i]:
        return 0.0
    return wall_depth(i, mid, shape, lin, rot, bend, t, surface, sstart, cphi, corigin, cpitch, push)


@njit(cache=True)
def separate(
    pairs,
    centre,
    radius,
    shape,
    lin,
    inv,
    rot,
    bend,
    t,
    phi,
    origin,
    pitch,
    dims,
    surface,
    sstart,
    cphi,
    corigin,
    cpitch,
    walls,
    sweeps,
    tolerance,
    step,
):
    """Gauss–Seidel sweeps over ``pairs`` (in the given order) and, with ``walls``, the collider: each
    pair is moved apart by its deepest vertex's depth along the depth-weighted normal, half each, each
    element out of a wall by its deepest vertex's depth beyond what the solver left there (an element
    the particles' proxy let into a wall, mostly one placed across it, is not pushed through its
    neighbours); no move is longer than ``step``. ``t`` (element
    positions) is updated in place; stops after the first sweep whose deepest pair overlap is ≤
    ``tolerance`` (walls do not hold the sweeps: an element placed across a wall stays there).
    Returns the deepest pair overlap of each sweep run (mm), measured before that sweep's moves."""
    history = np.zeros(sweeps)
    most = 2 * np.max(sstart[1:] - sstart[:-1])
    normals = np.empty((most, 3))
    depths = np.empty(most)
    push = np.empty(3)
    wall = np.empty(3)
    allowed = np.zeros(t.shape[0])  # what the solver left in a wall: the pass goes no deeper
    if walls:
        for i in range(t.shape[0]):
            allowed[i] = _wall(
                i, centre, radius, shape, lin, rot, bend, t, surface, sstart, cphi, corigin, cpitch, wall
            )
    done = 0
    for sweep in range(sweeps):
        worst = 0.0
        for p in range(pairs.shape[0]):
            i, j = pairs[p, 0], pairs[p, 1]
            gap = 0.0
            for a in range(3):
                gap += (centre[i, a] + t[i, a] - centre[j, a] - t[j, a]) ** 2
            if gap > (radius[i] + radius[j]) ** 2:
                continue
            # i's vertices in j: i moves out along j's normal; j's in i: i moves against i's normal
            field = (phi, origin, pitch, dims, surface, sstart)
            count = vertices_inside(i, j, shape, lin, inv, rot, bend, t, *field, 1.0, normals, depths, 0)
            count = vertices_inside(j, i, shape, lin, inv, rot, bend, t, *field, -1.0, normals, depths, count)
            if count == 0:
                continue
            depth = depths[:count].max()
            separating_translation(normals, depths, count, push)
            norm = np.sqrt(push[0] ** 2 + push[1] ** 2 + push[2] ** 2)
            if norm <= 0.0:
                continue
            move = 0.5 * min(norm, step) / norm
            for a in range(3):
                t[i, a] += move * push[a]
                t[j, a] -= move * push[a]
            worst = max(worst, depth)
        if walls:
            for i in range(t.shape[0]):
                depth = _wall(i, centre, radius, shape, lin, rot, bend, t, surface, sstart, cphi, corigin, cpitch, wall)
                if depth > allowed[i]:
                    for a in range(3):
                        t[i, a] += min(depth - allowed[i], step) * wall[a]
        history[sweep] = worst
        done = sweep + 1
        if worst <= tolerance:
            break
    return history[:done]


def _pairs(centre, radius, margin):
    """Element pairs whose bounding spheres are within ``margin``, the lower pair first (by the lower
    centre's height, then by index: deterministic)."""
    from scipy.spatial import cKDTree

    pairs = cKDTree(centre).query_pairs(2.0 * radius.max() + margin, output_type="ndarray")
    if not len(pairs):
        return np.zeros((0, 2), np.int64)
    gap = np.linalg.norm(centre[pairs[:, 0]] - centre[pairs[:, 1]], axis=1)
    pairs = pairs[gap <= radius[pairs[:, 0]] + radius[pairs[:, 1]] + margin]
    low = np.minimum(centre[pairs[:, 0], 2], centre[pairs[:, 1], 2])
    return np.ascontiguousarray(pairs[np.lexsort((pairs[:, 1], pairs[:, 0], low))], np.int64)


def separate_elements(
    aggregate, fields: ShapeFields, shape: np.ndarray, collider=None, sweeps=48, tolerance=0.005, step=0.05
):
    """Translations (m, 3) that move the elements of ``aggregate`` (element i has shape ``shape[i]`` of
    ``fields``) apart until no shell vertex is deeper in a neighbour or, with ``collider`` (φ, origin,
    pitch of the free space), in a wall than ``tolerance`` element lengths, or ``sweeps`` ran out; and
    the deepest overlap per sweep (element lengths). A move is at most ``step`` element lengths, and the
    pairs are found again every 8 sweeps, so a crowded element is not pushed far at once."""
    p = aggregate.placement
    n = len(p)
    rot = np.ascontiguousarray(p.rotations, np.float64)
    lin = rot if aggregate.deformations is None else np.einsum("nij,njk->nik", aggregate.deformations, rot)
    lin = np.ascontiguousarray(lin)
    inv = np.ascontiguousarray(np.linalg.inv(lin))
    bend = np.zeros((n, 3, 6)) if aggregate.bends is None else np.ascontiguousarray(aggregate.bends, np.float64)
    t0 = np.ascontiguousarray(p.positions, np.float64)
    # bounding spheres of the shells as placed (centre relative to the position; a translation keeps both)
    centre, radius, length = np.empty((n, 3)), np.empty(n), np.empty(n)
    for i in range(n):
        local = fields.surface[fields.sstart[shape[i]] : fields.sstart[shape[i] + 1]]
        world = aggregate.element_points(i, local)
        lo, hi = world.min(axis=0), world.max(axis=0)
        centre[i] = 0.5 * (lo + hi) - t0[i]
        radius[i] = np.linalg.norm(world - 0.5 * (lo + hi), axis=1).max()
        length[i] = np.ptp(local, axis=0).max()
    unit = float(np.median(length))
    walls = collider is not None
    cphi, corigin, cpitch = collider if walls else (np.ones((2, 2, 2)), np.zeros(3), 1.0)
    cphi, corigin = np.ascontiguousarray(cphi, np.float64), np.asarray(corigin, np.float64)
    shape = np.ascontiguousarray(shape, np.int64)
    t = t0.copy()
    history = []
    chunk = 8  # sweeps between pair searches: each moves an element ≤ 8·step·(neighbours) — the margin below
    while len(history) < sweeps:
        pairs = _pairs(centre + t, radius, 2.0 * chunk * step * unit)
        run = separate(
            pairs,
            centre,
            radius,
            shape,
            lin,
            inv,
            rot,
            bend,
            t,
            fields.phi,
            fields.origin,
            fields.pitch,
            fields.dims,
            fields.surface,
            fields.sstart,
            cphi,
            corigin,
            float(cpitch),
            walls,
            min(chunk, sweeps - len(history)),
            tolerance * unit,
            step * unit,
        )
        history.extend(run / unit)
        if run[-1] <= tolerance * unit:
            break
    return t - t0, np.array(history)
