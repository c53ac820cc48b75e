"""Container and ground colliders and moulds: meshes → signed distance grid → particle projection — SPEC §3.

φ > 0 in free space, φ < 0 inside the collider solid. The inside/outside split is the meshes' winding
number (``nodes.mesh_inside``, the test the voxeliser and placement use). Near the surface (a band of a
few cells) φ is the exact point–triangle distance signed by it; farther away it is the Euclidean distance
transform of the split (``edt``). Each particle keeps φ ≥ r (C = φ(x) − r ≥ 0), with the same
position-level friction as particle contacts. With the speed clamp of one radius per substep a particle
cannot cross a wall between two projections, whatever the wall's thickness (test: fast grains against a
thin bowl).
"""

from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import numpy as np
from numba import get_num_threads, njit, prange

from ..triangle_distance import point_triangle_offset
from .friction import RELEASE, ROLLING, RUBBED, TESTED, friction_wall, next_mode, pooled_load


@njit(cache=True, nogil=True)
def surface_band_rows(vertices, faces, normals, origin, pitch, band, first, last, dist, align):
    """Exact unsigned distance on the grid points of rows ``first`` ≤ i < ``last`` within ``band`` of the surface,
    written into ``dist`` (filled with inf by the caller; ``align``, zeros, is scratch of the same shape).

    Faces in order, each over the points of its box in these rows; a point farther than the band from the face's
    plane (a lower bound of its distance to the face; ``slack`` covers rounding) is passed over before the
    point–triangle distance, and a column's points are taken only where its line crosses that slab. Each row
    sees the faces in the same order whatever the rows' split, so rows computed apart (on threads,
    ``surface_band``) give the bits of one pass over the whole grid. Releases the GIL.
    """
    slack = band + 1e-6 * pitch
    lo = np.empty(3, np.int64)
    hi = np.empty(3, np.int64)
    for f in range(faces.shape[0]):
        a = vertices[faces[f, 0]]
        b = vertices[faces[f, 1]]
        c = vertices[faces[f, 2]]
        for k in range(3):
            mn = min(a[k], b[k], c[k]) - band
            mx = max(a[k], b[k], c[k]) + band
            lo[k] = max(0, int(np.floor((mn - origin[k]) / pitch)))
            hi[k] = min(dist.shape[k] - 1, int(np.ceil((mx - origin[k]) / pitch)))
        nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
        for i in range(max(lo[0], first), min(hi[0], last - 1) + 1):
            px = origin[0] + i * pitch
            sx = (px - a[0]) * nx
            for j in range(lo[1], hi[1] + 1):
                py = origin[1] + j * pitch
                sxy = sx + (py - a[1]) * ny  # signed distance from the face's plane, but for z
                k0, k1 = lo[2], hi[2]
                if abs(nz) > 0.05:  # the column crosses the slab |s| ≤ slack between these heights (±1 cell)
                    z0 = a[2] - (slack + sxy) / nz
                    z1 = a[2] + (slack - sxy) / nz
                    k0 = max(k0, int(np.floor((min(z0, z1) - origin[2]) / pitch)) - 1)
                    k1 = min(k1, int(np.ceil((max(z0, z1) - origin[2]) / pitch)) + 1)
                for k in range(k0, k1 + 1):
                    pz = origin[2] + k * pitch
                    if abs(sxy + (pz - a[2]) * nz) > slack:
                        continue
                    ex, ey, ez = point_triangle_offset(px, py, pz, a, b, c)
                    d = np.sqrt(ex * ex + ey * ey + ez * ez)
                    if d > band:
                        continue
                    dn = ex * nx + ey * ny + ez * nz
                    cos = abs(dn) / d if d > 1e-12 else 1.0
                    # near-ties (within 1e-9, at edges and vertices) keep the face whose normal best explains
                    # the offset: the choice of the former normal-sign rule, kept so φ keeps its bits (a plain
                    # minimum moves φ by up to 1e-9 mm at thousands of band points of the bowl)
                    if d < dist[i, j, k] - 1e-9 or (d <= dist[i, j, k] + 1e-9 and cos > align[i, j, k]):
                        dist[i, j, k] = d
                        align[i, j, k] = cos


# row blocks per thread in ``surface_band``: the bowl's faces are not spread evenly over its rows
BLOCKS_PER_THREAD = 4


def surface_band(vertices, faces, normals, origin, pitch, shape, band):
    """Exact unsigned distance on grid points within ``band`` of the surface, inf outside the band: blocks of rows
    (``surface_band_rows``) on numba's thread count of Python threads, the same bits for any count."""
    dist = np.full(shape, np.inf)
    align = np.zeros(shape)
    threads = min(get_num_threads(), shape[0])
    cuts = np.linspace(0, shape[0], BLOCKS_PER_THREAD * threads + 1).astype(np.int64)
    blocks = list(zip(cuts[:-1], cuts[1:]))

    def rows(block):
        surface_band_rows(vertices, faces, normals, origin, pitch, band, block[0], block[1], dist, align)

    if threads <= 1:
        rows((0, shape[0]))
    else:
        with ThreadPoolExecutor(threads) as pool:
            for _ in pool.map(rows, blocks):
                pass
    return dist


@njit(cache=True, nogil=True)
def signed_rows(dist, inside, far, sign, first, last, phi):
    """``sign`` × φ on rows ``first`` ≤ i < ``last`` into ``phi``: the band's exact distance where it is finite, else
    ``far``, the distance transform to the other side (out of the solid inside it, into it outside), negative
    inside. Releases the GIL."""
    _, ny, nz = dist.shape
    for i in range(first, last):
        for j in range(ny):
            for k in range(nz):
                d = dist[i, j, k]
                if not np.isfinite(d):
                    d = far[i, j, k]
                phi[i, j, k] = sign * (-d if inside[i, j, k] else d)


# grids smaller than this are signed on one thread: a pool costs more than it saves (an element's shell field)
THREADED_POINTS = 1 << 20


def signed_field(dist, inside, far, sign=1.0):
    """``sign`` × φ (``signed_rows``) in one pass, no temporary grids: blocks of rows on numba's thread count of
    Python threads (each point is written alone, so the bits are those of one pass). A mould's φ is −1 × the
    solid's: the sign here saves a pass over the grid and a copy of it."""
    phi = np.empty(dist.shape)
    threads = min(get_num_threads(), dist.shape[0]) if dist.size >= THREADED_POINTS else 1
    cuts = np.linspace(0, dist.shape[0], threads + 1).astype(np.int64)
    if threads <= 1:
        signed_rows(dist, inside, far, float(sign), 0, dist.shape[0], phi)
        return phi
    with ThreadPoolExecutor(threads) as pool:
        for _ in pool.map(
            lambda b: signed_rows(dist, inside, far, float(sign), b[0], b[1], phi),
            zip(cuts[:-1], cuts[1:]),
        ):
            pass
    return phi


def signed_distance_grid(meshes, lo, hi, pitch: float, band_cells: float = 3.0, sign: float = 1.0):
    """φ on a grid covering [lo, hi] for the union of watertight collider meshes (overlapping ones too), times
    ``sign`` (−1: a mould's free space, its inside positive).

    Returns (phi float64 (nx, ny, nz), origin, pitch). Raises ValueError for a non-watertight mesh,
    whose inside is undefined.
    """
    import edt
    import trimesh

    from ..mesh_inside import inside_columns

    tms = []
    for k, mesh in enumerate(meshes):
        tm = trimesh.Trimesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), process=True)
        if not tm.is_watertight:
            raise ValueError(
                f"colliders[{k}] ({mesh.name or 'unnamed'}): mesh is not watertight; a collider "
                "must be a closed solid (give the bowl or ground a thickness)"
            )
        if tm.volume < 0:
            tm.invert()
        tms.append(tm)
    merged = trimesh.util.concatenate(tms)
    vertices, faces = np.asarray(merged.vertices, float), np.asarray(merged.faces, np.int64)
    origin = np.asarray(lo, float)
    shape = tuple(int(s) for s in np.ceil((np.asarray(hi) - origin) / pitch).astype(int) + 1)
    dist = surface_band(
        vertices, faces, np.asarray(merged.face_normals, float), origin, pitch, shape, band_cells * pitch
    )
    # the one inside test (column winding number > 0: the union of overlapping solids, nested shells inside);
    # grid points on the surface itself (φ = 0) belong to the free side of the far field's split
    axes = [origin[d] + np.arange(shape[d]) * pitch for d in range(3)]
    inside = inside_columns(vertices, faces, *axes)
    inside &= dist > 0.0
    # one multi-label transform (inside 1, outside 2): each point's distance to the nearest point of the other side,
    # the bits of the two binary transforms (depth of ``inside``, clearance of ``~inside``) in one pass over the grid
    far = edt.edt(2 - inside.view(np.uint8), anisotropy=(pitch,) * 3, parallel=get_num_threads())
    return signed_field(dist, inside, far, sign), origin, float(pitch)


def free_space_field(colliders, moulds, lo, hi, pitch: float, reach: float = 0.0):
    """φ of the free space on one grid: outside every collider solid and inside the moulds
    (onigiri mould, bunny), φ = min(φ_colliders, −φ_moulds); a mould's inside is where elements may
    be. Returns (phi, origin, pitch) as ``signed_distance_grid``.

    φ is exact (the band) up to ``reach`` (the largest particle radius) and two cells beyond: a particle is tested
    at its centre, one radius from the wall, where the trilinear φ reads its cell's corners up to √3 cells farther.
    Past the band the distance transform is off by up to half a cell; read there, a flat slab was bumpy by 0.14 mm
    at a 0.29 mm pitch, and a grain set down on it tilted 28° slid or held at μs 0.6 by where it stood."""
    band_cells = max(3.0, reach / pitch + 2.0)
    phi = None
    for meshes, sign in ((colliders, 1.0), (moulds, -1.0)):
        if meshes:
            part, origin, pitch = signed_distance_grid(meshes, lo, hi, pitch, band_cells, sign=sign)
            phi = part if phi is None else np.minimum(phi, part)
    return phi, origin, pitch


@njit(cache=True, inline="always")
def sample_phi(phi, origin, pitch, px, py, pz):
    """Trilinear φ and its gradient at a point; outside the grid φ = +inf (free space)."""
    fx = (px - origin[0]) / pitch
    fy = (py - origin[1]) / pitch
    fz = (pz - origin[2]) / pitch
    nx, ny, nz = phi.shape
    if fx < 0 or fy < 0 or fz < 0 or fx >= nx - 1 or fy >= ny - 1 or fz >= nz - 1:
        return np.inf, 0.0, 0.0, 0.0
    i = int(fx)
    j = int(fy)
    k = int(fz)
    u = fx - i
    v = fy - j
    t = fz - k
    c000 = phi[i, j, k]
    c100 = phi[i + 1, j, k]
    c010 = phi[i, j + 1, k]
    c110 = phi[i + 1, j + 1, k]
    c001 = phi[i, j, k + 1]
    c101 = phi[i + 1, j, k + 1]
    c011 = phi[i, j + 1, k + 1]
    c111 = phi[i + 1, j + 1, k + 1]
    c00 = c000 + (c100 - c000) * u
    c10 = c010 + (c110 - c010) * u
    c01 = c001 + (c101 - c001) * u
    c11 = c011 + (c111 - c011) * u
    c0 = c00 + (c10 - c00) * v
    c1 = c01 + (c11 - c01) * v
    val = c0 + (c1 - c0) * t
    gx = (
        (1 - v) * (1 - t) * (c100 - c000)
        + v * (1 - t) * (c110 - c010)
        + (1 - v) * t * (c101 - c001)
        + v * t * (c111 - c011)
    ) / pitch
    gy = (
        (1 - u) * (1 - t) * (c010 - c000)
        + u * (1 - t) * (c110 - c100)
        + (1 - u) * t * (c011 - c001)
        + u * t * (c111 - c101)
    ) / pitch
    gz = (c1 - c0) / pitch
    return val, gx, gy, gz


COARSE = 4  # SDF cells per side of a block of ``block_minimum``


@njit(cache=True)
def block_minimum(phi):
    """min φ over each block of COARSE³ grid cells and the grid points on its far faces: a lower
    bound of the trilinear φ anywhere in the block. Particles whose block bound exceeds their
    radius skip the wall projection without touching the fine grid (the interior of a pile: the
    fine φ of a 50k-sphere box is 38 MB, read at random)."""
    nx, ny, nz = phi.shape
    bx, by, bz = (nx + COARSE - 1) // COARSE, (ny + COARSE - 1) // COARSE, (nz + COARSE - 1) // COARSE
    out = np.full((bx, by, bz), np.inf)
    for i in range(nx):
        for j in range(ny):
            for k in range(nz):
                v = phi[i, j, k]
                # grid point (i, j, k) bounds the blocks it is a corner of: its own and those below
                for a in range(max(0, (i - 1) // COARSE), min(bx, i // COARSE + 1)):
                    for b in range(max(0, (j - 1) // COARSE), min(by, j // COARSE + 1)):
                        for c in range(max(0, (k - 1) // COARSE), min(bz, k // COARSE + 1)):
                            if v < out[a, b, c]:
                                out[a, b, c] = v
    return out


class ColliderGrid(NamedTuple):
    """φ of the free space as ``collider_project`` takes it (``model.ColliderField.args()``)."""

    phi: np.ndarray  # (nx, ny, nz)
    origin: np.ndarray  # (3,)
    pitch: float
    blocks: np.ndarray  # ``block_minimum`` of φ


@njit(cache=True)  # called, not inlined: a rare path, and its three φ samples cost 3.4 of 17.8 s of compiling
def _swept_back(x, x_prev, phi, origin, pitch, val, gx, gy, gz, i):
    """Swept test for a centre that ended inside the solid (φ < 0) although it started the solve in
    free space (φ(x_prev) > 0): a contact push or a long step crossed the surface, and ∇φ there may
    point out of the wall's far side (a thin wall). Bisection on the segment x_prev → x for the last
    point with φ ≥ 0; the particle is put there and projected from it. Returns φ and ∇φ at its new
    place (unchanged when x_prev is not in free space: a particle placed inside keeps ∇φ)."""
    v0, _, _, _ = sample_phi(phi, origin, pitch, x_prev[i, 0], x_prev[i, 1], x_prev[i, 2])
    if not v0 > 0.0:
        return val, gx, gy, gz
    lo = 0.0
    hi = 1.0
    for _ in range(20):
        mid = 0.5 * (lo + hi)
        v, _, _, _ = sample_phi(
            phi,
            origin,
            pitch,
            x_prev[i, 0] + mid * (x[i, 0] - x_prev[i, 0]),
            x_prev[i, 1] + mid * (x[i, 1] - x_prev[i, 1]),
            x_prev[i, 2] + mid * (x[i, 2] - x_prev[i, 2]),
        )
        if v >= 0.0:
            lo = mid
        else:
            hi = mid
    for k in range(3):
        x[i, k] = x_prev[i, k] + lo * (x[i, k] - x_prev[i, k])
    return sample_phi(phi, origin, pitch, x[i, 0], x[i, 1], x[i, 2])


@njit(cache=True, inline="always")
def _near_wall(x, w, r, origin, pitch, blocks, i):
    """Whether particle i has mass and its coarse block of φ (``block_minimum``) comes within its radius: the
    others are clear of every wall. Tested in ``collider_project``'s loop before ``_wall_one``, whose call costs
    more than this test for the many particles far from any wall."""
    if w[i] <= 0.0:
        return False
    fx = (x[i, 0] - origin[0]) / pitch
    fy = (x[i, 1] - origin[1]) / pitch
    fz = (x[i, 2] - origin[2]) / pitch
    if fx >= 0 and fy >= 0 and fz >= 0:
        bi = int(fx) // COARSE
        bj = int(fy) // COARSE
        bk = int(fz) // COARSE
        if bi < blocks.shape[0] and bj < blocks.shape[1] and bk < blocks.shape[2] and blocks[bi, bj, bk] > r[i]:
            return False
    return True


# called, not inlined into ``collider_project``'s parallel loop: inlined, numba 0.68 lost the writes to the state
# bundle's arrays it fetched (what friction removed stayed 0)
@njit(cache=True)
def _wall_one(state, r, elem, phi, origin, pitch, rule, i):
    """Project particle i, one ``_near_wall`` passes (see ``collider_project``); returns its (r − φ)/r, 0 when
    clear."""
    x, x_prev, anchor, load, mean = state.x, state.x_prev, state.wall_anchor, state.wall_load, state.wall_mean
    rubbed, modes = state.wall_rubbed, state.wall_mode
    mu_s, anchored = rule[0], rule[2]
    val, gx, gy, gz = sample_phi(phi, origin, pitch, x[i, 0], x[i, 1], x[i, 2])
    pen = r[i] - val
    if pen <= 0.0:
        if anchored and mu_s > 0.0 and val > (1.0 + 2.0 * RELEASE) * r[i]:
            anchor[i, 0] = np.nan  # clear of the wall: let go (a particle skipped above keeps a stale anchor,
            # which its next touch finds too far, slides once and re-anchors)
        return 0.0
    if val < 0.0 and x_prev is not x:
        # i as int64: in the parallel loop's body numba types the index unsigned, a second compilation of _swept_back
        val, gx, gy, gz = _swept_back(x, x_prev, phi, origin, pitch, val, gx, gy, gz, np.int64(i))
        pen = r[i] - val
    g = np.sqrt(gx * gx + gy * gy + gz * gz)
    if g < 1e-12:
        return pen / r[i]
    nx, ny, nz = gx / g, gy / g, gz / g
    x[i, 0] += pen * nx
    x[i, 1] += pen * ny
    x[i, 2] += pen * nz
    load[i] += pen
    if mu_s > 0.0:
        e = elem[i]  # the element's mean wall load over the last substep and its mode, 0 if it touched none
        pooled = mean[e] > 0.0
        held, mode = (pooled_load(modes[e], mean[e], load[i]), modes[e]) if pooled else (load[i], TESTED)
        friction_wall(x, x_prev, anchor, rubbed, i, nx, ny, nz, pen, held, rule, mode)
    return pen / r[i]


@njit(cache=True, parallel=True)
def collider_project(state, model, grid, rule):
    """Push particles out to φ ≥ r along ∇φ, then apply static/dynamic friction against the wall
    (``friction.friction_wall``; normal load: the mean over the element's touching particles of the walls' pushes
    in the last substep, ``wall_means``, else the particle's own pushes this substep; ``rule``: a
    ``friction_models.FrictionRule``, ``anchor`` (n, 3) per particle; μs = 0 skips friction and leaves the
    anchors). In place; particles are independent. ``blocks``: the ``block_minimum`` of φ (particles far from
    every wall are skipped). ``state``: ``StateArrays`` (x, x_prev, wall_anchor, wall_load, wall_mean; x_prev is x
    in pre-stabilisation: no swept test), ``model``: ``ModelArrays`` (w, r, elem), ``grid``: ``ColliderGrid``. Returns
    max (r − φ)/r."""
    x = state.x
    w, r, elem = model.w, model.r, model.elem
    phi, origin, pitch, blocks = grid.phi, grid.origin, grid.pitch, grid.blocks
    n = x.shape[0]
    worst = np.zeros(n)
    for i in prange(n):
        if _near_wall(x, w, r, origin, pitch, blocks, i):
            worst[i] = _wall_one(state, r, elem, phi, origin, pitch, rule, i)
    return worst.max() if n > 0 else 0.0


@njit(cache=True, parallel=True)
def collider_penetration(x, r, phi, origin, pitch):
    """max over particles of (r − φ)/r, without moving anything (diagnostics)."""
    n = x.shape[0]
    worst = np.zeros(n)
    for i in prange(n):
        val, _, _, _ = sample_phi(phi, origin, pitch, x[i, 0], x[i, 1], x[i, 2])
        worst[i] = max(0.0, (r[i] - val) / r[i])
    return worst.max() if n > 0 else 0.0


@njit(cache=True)
def _clear_side(x, r, s, e, cx, cy, cz, phi, origin, pitch):
    """Whether every particle s:e of a cluster with centre (cx, cy, cz) lies in free space (φ ≥ 0) and on the
    centre's side of every wall: no point of the segment from the centre to it (8 samples) is inside a solid."""
    for i in range(s, e):
        for k in range(1, 9):
            f = k / 8.0
            v, _, _, _ = sample_phi(
                phi, origin, pitch, cx + f * (x[i, 0] - cx), cy + f * (x[i, 1] - cy), cz + f * (x[i, 2] - cz)
            )
            if v < 0.0:
                return False
    return True


@njit(cache=True)
def rigid_into_free_space(x, r, start, phi, origin, pitch):
    """Move each cluster whole (start: its particle ranges) along ∇φ at its centre, a quarter cell at a time and at
    most its own size (the diameter of its particles' union), until every particle lies in free space on its
    centre's side of the walls (``_clear_side``). A placed element that reaches through a container's wall (a long
    grain near a bowl's rim) then starts the run inside and rigid; else the wall pushes each particle out on its
    own side, the far ones out of the far side, and the cluster stays torn across the wall for good: the contacts
    and the wall have the last word over shape matching (a reduced indica bowl: 9 of 60 clusters 2.4–3 mm out of
    shape after frame 1, their meshes 2 mm off their spheres; docs/look.md). Clusters whose centre is not in free
    space are left alone. In place; returns how many clusters moved."""
    moved = 0
    step = 0.25 * pitch
    for c in range(start.shape[0] - 1):
        s, e = start[c], start[c + 1]
        cx, cy, cz = 0.0, 0.0, 0.0
        for i in range(s, e):
            cx += x[i, 0]
            cy += x[i, 1]
            cz += x[i, 2]
        cx /= e - s
        cy /= e - s
        cz /= e - s
        reach = 0.0
        for i in range(s, e):
            reach = max(reach, np.sqrt((x[i, 0] - cx) ** 2 + (x[i, 1] - cy) ** 2 + (x[i, 2] - cz) ** 2) + r[i])
        reach *= 2.0
        travel = 0.0
        while travel < reach and not _clear_side(x, r, s, e, cx, cy, cz, phi, origin, pitch):
            v, gx, gy, gz = sample_phi(phi, origin, pitch, cx, cy, cz)
            g = np.sqrt(gx * gx + gy * gy + gz * gz)
            if not v > 0.0 or g < 1e-12:
                break
            dx, dy, dz = step * gx / g, step * gy / g, step * gz / g
            for i in range(s, e):
                x[i, 0] += dx
                x[i, 1] += dy
                x[i, 2] += dz
            cx += dx
            cy += dy
            cz += dz
            travel += step
        moved += travel > 0.0
    return moved


@njit(cache=True)
def wall_means(start, state, rule):
    """Each element's mean wall load over its touching particles into ``state.wall_mean`` (per element, 0 where
    none touches), its remembered force (``friction.remember``) into ``state.wall_force`` and its friction mode
    for the next substep (``friction.contact_mode``; TESTED without anchors) into ``state.wall_mode``; the
    particles' loads and what friction removed cleared for the next substep: static friction then tests a grain
    against the walls as one rigid contact (``friction.pool_contacts`` does the same for grain on grain).
    ``rule``: a ``friction_models.FrictionRule``."""
    load, mean, rubbed, modes, force = (
        state.wall_load,
        state.wall_mean,
        state.wall_rubbed,
        state.wall_mode,
        state.wall_force,
    )
    mu_s, anchored = rule[0], rule[2]
    m = start.shape[0] - 1
    for e in range(m):  # serial: one pass over the particles (a prange here lost its writes to ``mean``)
        total = 0.0
        count = 0
        tx, ty, tz = 0.0, 0.0, 0.0
        slid = False
        for i in range(start[e], start[e + 1]):
            if load[i] > 0.0:
                total += load[i]
                count += 1
            tx += rubbed[i, 0]
            ty += rubbed[i, 1]
            tz += rubbed[i, 2]
            slid |= rubbed[i, 4] > 0.0
            load[i] = 0.0
            for k in range(RUBBED):
                rubbed[i, k] = 0.0
        mean[e] = total / count if count > 0 else 0.0
        mode = next_mode(force, e, total, tx, ty, tz, slid, mu_s, modes[e])
        modes[e] = TESTED if start[e + 1] - start[e] <= ROLLING or not anchored else mode
