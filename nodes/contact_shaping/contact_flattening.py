"""Contact flattening: the soft grains' meshes pressed flat where they meet — SPEC §3 (G: a low-resolution
simulation carries the high-resolution grains), measured by issue 17's mesh-level overlap.

The XPBD run resolves contacts between the particle clusters, whose spheres lie inside each grain and
leave its surface uncovered by up to ≈ 0.1 of a grain length (``clusters``): two grains whose spheres only
touch still cut into each other's meshes. Cooked rice is soft; where two grains press together each one
flattens. This pass does that on the meshes, locally, with no pile-wide propagation. Per touching pair,
each element's shell vertices inside the other are found on the other's own local grid φ, carried through
its map (SPEC §5 x = D·R·u + R·B·m(u) + t); those past the plane halfway through the overlap (across the
lens' axis, ``share`` ½) go onto it, so both surfaces meet there — the contact patch of two equally soft
bodies (``neighbour_pushes``). A vertex inside a collider wall, or outside a mould, moves all the way back
(walls are rigid). No vertex moves more than ``cap`` of its element's thickness, so a grain placed deep
across another is not folded through itself: what that leaves is measured, not hidden.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numba import njit

from ..simulation.collider import sample_phi


class ElementMaps(NamedTuple):
    """Per element: its mesh's shape index, the map of its local frame (SPEC §5 x = D·R·u + R·B·m(u) + t:
    L⁻¹ = (D·R)⁻¹, R, B, t) and its world bounding box, padded by the clearance."""

    shape: np.ndarray  # (e,) int64, row of the ShapeFields and VertexRings
    lin_inv: np.ndarray  # (e, 3, 3)
    rot: np.ndarray  # (e, 3, 3)
    bend: np.ndarray  # (e, 3, 6)
    t: np.ndarray  # (e, 3)
    lo: np.ndarray  # (e, 3)
    hi: np.ndarray  # (e, 3)


class ElementVertices(NamedTuple):
    """All elements' world vertices, CSR by element: element i's are ``world[start[i]:start[i + 1]]``."""

    world: np.ndarray  # (v, 3)
    start: np.ndarray  # (e + 1,) int64
    shell: np.ndarray  # (v,) True for the vertices of the element's outer shell


class ContactPairs(NamedTuple):
    """CSR neighbour lists of the elements that are flattened: element i's are ``index[start[i]:start[i + 1]]``."""

    start: np.ndarray  # (own + 1,) int64
    index: np.ndarray  # int64


class VertexRings(NamedTuple):
    """Each shape's vertex neighbours as one CSR (``vertex_rings``)."""

    row: np.ndarray  # (s,) int64: shape s's vertex v has its ring at start[row[s] + v]
    start: np.ndarray  # int64
    ring: np.ndarray  # int64, the shape's own vertex indices


class InsideVertices(NamedTuple):
    """Scratch of ``_inside``: the rows of the vertices found, their depth and the other element's normal there."""

    rows: np.ndarray  # (most,) int64
    depth: np.ndarray  # (most,)
    normal: np.ndarray  # (most, 3)


class ShapeFields(NamedTuple):
    """Per distinct element mesh: φ of its outer shell on its local grid (padded to one shape, φ > 0 out)."""

    phi: np.ndarray  # (s, nx, ny, nz)
    origin: np.ndarray  # (s, 3)
    pitch: np.ndarray  # (s,)
    dims: np.ndarray  # (s, 3) int64, each grid's own size


def shape_fields(shells: list[tuple[np.ndarray, np.ndarray]], cells: int = 32) -> ShapeFields:
    """φ of each closed shell (vertices, faces) in its local frame, ``cells`` across its longest side plus a
    3-cell border: the pitch is a grain length / 32 ≈ 0.2 mm for rice (``collider.signed_distance_grid``)."""
    import trimesh

    from ..simulation.collider import signed_distance_grid

    grids = []
    for vertices, faces in shells:
        body = trimesh.Trimesh(vertices, faces, process=False)
        lo, hi = body.bounds
        pitch = float((hi - lo).max()) / cells
        grids.append(signed_distance_grid([body], lo - 3 * pitch, hi + 3 * pitch, pitch))
    dims = np.array([g[0].shape for g in grids], np.int64)
    phi = np.full((len(grids), *dims.max(axis=0)), np.inf)
    for s, (grid, _, _) in enumerate(grids):
        phi[s, : grid.shape[0], : grid.shape[1], : grid.shape[2]] = grid
    origin = np.array([g[1] for g in grids], np.float64)
    return ShapeFields(phi, origin, np.array([g[2] for g in grids], np.float64), dims)


@njit(cache=True, inline="always")
def _local(x, lin_inv, rot, bend, t, u):
    """u with x = L·u + R·B·m(u) + t (two fixed-point steps from the affine inverse: bends are small)."""
    y0, y1, y2 = x[0] - t[0], x[1] - t[1], x[2] - t[2]
    for a in range(3):
        u[a] = lin_inv[a, 0] * y0 + lin_inv[a, 1] * y1 + lin_inv[a, 2] * y2
    for _ in range(2):
        m = (u[0] * u[0], u[1] * u[1], u[2] * u[2], u[0] * u[1], u[1] * u[2], u[2] * u[0])
        b0 = bend[0, 0] * m[0] + bend[0, 1] * m[1] + bend[0, 2] * m[2] + bend[0, 3] * m[3] + bend[0, 4] * m[4]
        b1 = bend[1, 0] * m[0] + bend[1, 1] * m[1] + bend[1, 2] * m[2] + bend[1, 3] * m[3] + bend[1, 4] * m[4]
        b2 = bend[2, 0] * m[0] + bend[2, 1] * m[1] + bend[2, 2] * m[2] + bend[2, 3] * m[3] + bend[2, 4] * m[4]
        b0 += bend[0, 5] * m[5]  # no array per call: this runs for every vertex tested
        b1 += bend[1, 5] * m[5]
        b2 += bend[2, 5] * m[5]
        z0 = y0 - (rot[0, 0] * b0 + rot[0, 1] * b1 + rot[0, 2] * b2)
        z1 = y1 - (rot[1, 0] * b0 + rot[1, 1] * b1 + rot[1, 2] * b2)
        z2 = y2 - (rot[2, 0] * b0 + rot[2, 1] * b1 + rot[2, 2] * b2)
        for a in range(3):
            u[a] = lin_inv[a, 0] * z0 + lin_inv[a, 1] * z1 + lin_inv[a, 2] * z2


@njit(cache=True)
def near_surface(points, shell, j, maps, fields, clearance, found, offset):
    """Shell points (``shell`` marks them among ``points``) closer to element j's rest surface than ``clearance``
    (inside: depth > 0), into ``found``: their rows plus ``offset``, world depth and j's outward unit normal there
    (j's φ on its local grid, scaled by |∇ₓφ| = |(D·R)⁻ᵀ∇ᵤφ|). Returns how many."""
    rows, depth, normal = found.rows, found.depth, found.normal
    lin_inv, rot, bend, t, lo, hi = maps.lin_inv[j], maps.rot[j], maps.bend[j], maps.t[j], maps.lo[j], maps.hi[j]
    sj = maps.shape[j]
    dims = fields.dims
    count = 0
    u = np.empty(3)
    grid = fields.phi[sj, : dims[sj, 0], : dims[sj, 1], : dims[sj, 2]]
    for k in range(points.shape[0]):
        if not shell[k]:
            continue
        x = points[k]
        if x[0] < lo[0] or x[1] < lo[1] or x[2] < lo[2] or x[0] > hi[0] or x[1] > hi[1] or x[2] > hi[2]:
            continue
        _local(x, lin_inv, rot, bend, t, u)
        val, gx, gy, gz = sample_phi(grid, fields.origin[sj], fields.pitch[sj], u[0], u[1], u[2])
        if not val < np.inf:
            continue
        g = np.sqrt(gx * gx + gy * gy + gz * gz)
        if not g > 0.0:
            continue
        gx, gy, gz = gx / g, gy / g, gz / g  # unit: deep inside, the trilinear gradient is short, not φ wrong
        w0 = lin_inv[0, 0] * gx + lin_inv[1, 0] * gy + lin_inv[2, 0] * gz
        w1 = lin_inv[0, 1] * gx + lin_inv[1, 1] * gy + lin_inv[2, 1] * gz
        w2 = lin_inv[0, 2] * gx + lin_inv[1, 2] * gy + lin_inv[2, 2] * gz
        norm = np.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        if not norm > 0.0 or -val / norm + clearance <= 0.0:
            continue
        rows[count] = offset + k
        depth[count] = -val / norm
        normal[count, 0] = w0 / norm
        normal[count, 1] = w1 / norm
        normal[count, 2] = w2 / norm
        count += 1
    return count


@njit(cache=True)
def _inside(vertices, i, j, maps, fields, clearance, found):
    """Shell vertices of element i closer to element j than ``clearance``: ``near_surface`` on i's rows."""
    s, e = vertices.start[i], vertices.start[i + 1]
    return near_surface(vertices.world[s:e], vertices.shell[s:e], j, maps, fields, clearance, found, s)


@njit(cache=True, inline="always")
def lens_axis(found_x, cx, found_y, cy, n):
    """The axis n (unit, into ``n``) of the lens two elements overlap in: the depth-weighted outward normals of
    both sides' points inside the other (``near_surface``: ``cx`` of i's in j, ``cy`` of j's in i); False when
    they cancel."""
    for a in range(3):
        n[a] = 0.0
        for k in range(cy):
            n[a] += found_y.depth[k] * found_y.normal[k, a]
        for k in range(cx):
            n[a] -= found_x.depth[k] * found_x.normal[k, a]
    norm = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    if not norm > 0.0:
        return False
    for a in range(3):
        n[a] /= norm
    return True


@njit(cache=True)
def neighbour_pushes(vertices, pairs, maps, fields, rings, clearance, share):
    """Per shell vertex of each of the first elements (rows of ``pairs``): its move onto the contact plane
    of each neighbour j it is inside (CSR ``pairs``, in order). The plane of a pair: normal
    n, the lens' axis, the depth-weighted sum of j's outward normals at its vertices inside i less i's at
    its vertices inside j (one vertex's nearest-surface normal points sideways in a thin grain); at
    a − ``share``·(a − b) along n, [b, a] the overlap's extent along n (how far each side's vertices
    reach into the other). i's vertices inside j and past the plane go back onto it, less half the
    ``clearance``, and the cap they form is relaxed in the plane (``relax_cap``). The pair's other element
    computes the same plane from its side. Each element writes only its own vertices, in a fixed order:
    deterministic. Serial: a parallel kernel took ≈ 70 s to compile here, for ≈ 2× on 2 cores."""
    world, vstart = vertices.world, vertices.start
    push = np.zeros((vstart[pairs.start.shape[0] - 1], 3))
    most = 0
    for e in range(vstart.shape[0] - 1):
        most = max(most, vstart[e + 1] - vstart[e])
    for i in range(pairs.start.shape[0] - 1):
        found_x = InsideVertices(np.empty(most, np.int64), np.empty(most), np.empty((most, 3)))
        found_y = InsideVertices(np.empty(most, np.int64), np.empty(most), np.empty((most, 3)))
        rows_x, depth_x = found_x.rows, found_x.depth
        rows_y, depth_y = found_y.rows, found_y.depth
        n = np.empty(3)
        for q in range(pairs.start[i], pairs.start[i + 1]):
            j = pairs.index[q]
            cx = _inside(vertices, i, j, maps, fields, clearance, found_x)
            if cx == 0:
                continue
            cy = _inside(vertices, j, i, maps, fields, clearance, found_y)
            if not lens_axis(found_x, cx, found_y, cy, n):
                continue
            top = -np.inf  # a: how far i reaches along n (its vertices in j; without any, from j's in i and depths)
            bottom = np.inf  # b: how far j reaches back (its vertices in i; without any, from i's in j)
            for k in range(cx):
                h = world[rows_x[k], 0] * n[0] + world[rows_x[k], 1] * n[1] + world[rows_x[k], 2] * n[2]
                top = max(top, h)
                if cy == 0:
                    bottom = min(bottom, h - depth_x[k])
            for k in range(cy):
                h = world[rows_y[k], 0] * n[0] + world[rows_y[k], 1] * n[1] + world[rows_y[k], 2] * n[2]
                bottom = min(bottom, h)
                if cx == 0:
                    top = max(top, h + depth_y[k])
            plane = top - share * (top - bottom) - 0.5 * clearance
            capped = 0
            for k in range(cx):
                r = rows_x[k]
                h = 0.0
                for a in range(3):
                    h += (world[r, a] + push[r, a]) * n[a]
                if h > plane:
                    for a in range(3):
                        push[r, a] -= (h - plane) * n[a]
                    rows_x[capped] = r  # the cap: i's vertices now on the plane
                    capped += 1
            if capped > 1:
                relax_cap(
                    world, push, rows_x, capped, vstart[i], rings.row[maps.shape[i]], rings.start, rings.ring, n, plane
                )
    return push


@njit(cache=True)
def relax_cap(world, push, cap, count, first, row, ring_start, ring, n, plane, sweeps=40):
    """The cap (rows ``cap[:count]``) relaxed in the plane n·x = ``plane``: each vertex to the mean of its
    ring neighbours, projected back onto the plane, Gauss–Seidel, its rim fixed (Tutte: a disk whose
    rim is convex embeds without folds). Plain projection folds the cap where its faces look away from
    n (a grain's edge or tip pressed flat), which a renderer shows as creases: on the 1,984-grain bowl
    43,067 folded faces without, 33,944 with (of 3.6 M; 200 sweeps fold as many as 40: the rest do not
    come from an unconverged relaxation)."""
    p = np.empty(3)
    for _ in range(sweeps):
        for c in range(count):
            v = cap[c]
            local = v - first
            lo, hi = ring_start[row + local], ring_start[row + local + 1]
            p[:] = 0.0
            for q in range(lo, hi):
                u = first + ring[q]
                for a in range(3):
                    p[a] += world[u, a] + push[u, a]
            h = 0.0
            for a in range(3):
                p[a] /= hi - lo
                h += p[a] * n[a]
            for a in range(3):
                push[v, a] = p[a] - (h - plane) * n[a] - world[v, a]


@njit(cache=True)
def wall_pushes(world, shell, cphi, corigin, cpitch, clearance, reach):
    """Per shell vertex inside the free-space field's solid (φ_c < ``clearance``) but no deeper than
    ``reach`` (beyond, it may be past a thin wall's middle, where ∇φ_c points out the far side): the
    whole way back along ∇φ_c, plus the clearance — walls do not give."""
    push = np.zeros_like(world)
    for k in range(world.shape[0]):
        if not shell[k]:
            continue
        val, gx, gy, gz = sample_phi(cphi, corigin, cpitch, world[k, 0], world[k, 1], world[k, 2])
        if not val < clearance or val < -reach:
            continue
        norm = np.sqrt(gx * gx + gy * gy + gz * gz)
        if norm > 0.0:
            move = (clearance - val) / norm
            push[k, 0] = move * gx
            push[k, 1] = move * gy
            push[k, 2] = move * gz
    return push


def capped(push: np.ndarray, vstart: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """``push`` with each vertex's move shortened to its element's ``limit`` (same direction)."""
    per_vertex = np.repeat(limit, np.diff(vstart))
    length = np.linalg.norm(push, axis=1)
    scale = np.minimum(1.0, per_vertex / np.maximum(length, 1e-300))
    return push * scale[:, None]


@dataclass(frozen=True, eq=False)
class Dents:
    """Per-vertex moves of the flattened elements (world frame), one row per moved vertex, sorted by element."""

    element: np.ndarray  # (k,) int64
    vertex: np.ndarray  # (k,) int64, index into the element's mesh
    offset: np.ndarray  # (k, 3)


@dataclass(frozen=True, eq=False)
class _Elements:
    """The elements of several aggregates as flat arrays: maps, shapes, world shells, bounding boxes."""

    lin_inv: np.ndarray
    rot: np.ndarray
    bend: np.ndarray
    t: np.ndarray
    shape: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    thickness: np.ndarray  # smallest extent of each element's shell in its own frame
    world: list  # per element: its mesh's world vertices
    shell: list  # per element: True for the vertices of its outer shell


def outer_vertices(mesh) -> np.ndarray:
    """True for vertices of the outer shell (faces of part 0) and of no inner part (the ikura yolk)."""
    if mesh.parts is None:
        return np.ones(len(mesh.vertices), bool)
    mask = np.zeros(len(mesh.vertices), bool)
    mask[np.unique(mesh.faces[mesh.parts == 0])] = True
    mask[np.unique(mesh.faces[mesh.parts != 0])] = False
    return mask


def _gather(aggregates, fields_of) -> _Elements:
    """Flatten ``aggregates`` into one list of elements; ``fields_of(mesh)`` gives a mesh's shape index."""
    rows = {k: [] for k in ("lin_inv", "rot", "bend", "t", "shape", "lo", "hi", "thickness")}
    world, shell = [], []
    outer_of: dict[int, tuple] = {}  # per library mesh: its outer shell's vertices and thickness, found once
    for aggregate in aggregates:
        p = aggregate.placement
        bare = aggregate.without_normals()  # the same vertices, without rotating and bending each mesh's normals
        rot = np.asarray(p.rotations, np.float64)
        lin = rot if aggregate.deformations is None else np.einsum("nij,njk->nik", aggregate.deformations, rot)
        bend = np.zeros((len(p), 3, 6)) if aggregate.bends is None else np.asarray(aggregate.bends, np.float64)
        t = np.asarray(p.positions, np.float64)  # part offsets move inner parts only, not the shell
        for i in range(len(p)):
            library = aggregate.libraries[p.kinds[i]]
            base = library.meshes[p.variants[i] % len(library)]
            mesh = bare.element_mesh(i)
            if id(base) not in outer_of:
                used = outer_vertices(base)
                outer_of[id(base)] = (used, float(np.ptp(base.vertices[used], axis=0).min()))
            outer, thickness = outer_of[id(base)]
            points = mesh.vertices[outer]
            rows["lo"].append(points.min(axis=0))
            rows["hi"].append(points.max(axis=0))
            rows["thickness"].append(thickness)
            rows["shape"].append(fields_of(base))
            world.append(np.asarray(mesh.vertices, np.float64))
            shell.append(outer)
        rows["lin_inv"].append(np.linalg.inv(lin))
        rows["rot"].append(rot)
        rows["bend"].append(bend)
        rows["t"].append(t)
    lo, hi = np.array(rows["lo"]).reshape(-1, 3), np.array(rows["hi"]).reshape(-1, 3)
    centre = 0.5 * (lo + hi)
    return _Elements(
        np.ascontiguousarray(np.concatenate(rows["lin_inv"])),
        np.ascontiguousarray(np.concatenate(rows["rot"])),
        np.ascontiguousarray(np.concatenate(rows["bend"])),
        np.ascontiguousarray(np.concatenate(rows["t"])),
        np.array(rows["shape"], np.int64),
        lo,
        hi,
        centre,
        0.5 * np.linalg.norm(hi - lo, axis=1),
        np.array(rows["thickness"]),
        world,
        shell,
    )


def vertex_rings(meshes) -> VertexRings:
    """Each (vertex count, faces) mesh's vertex neighbours as one CSR: shape s's vertex v has neighbours
    ``ring[ring_start[row[s] + v] : ring_start[row[s] + v + 1]]`` (its own vertex indices)."""
    rows, starts, rings, offset = [], [], [], 0
    for count, faces in meshes:
        edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
        edges = np.unique(np.concatenate([edges, edges[:, ::-1]]), axis=0)  # sorted by vertex, then neighbour
        start = np.searchsorted(edges[:, 0], np.arange(count + 1))
        rows.append(sum(len(x) for x in starts))
        starts.append(start + offset)
        rings.append(edges[:, 1])
        offset += len(edges)
    return VertexRings(
        np.array(rows, np.int64),
        np.concatenate(starts).astype(np.int64),
        np.concatenate(rings).astype(np.int64),
    )


def _neighbour_lists(elements: _Elements, own: int, margin: float):
    """CSR of each of the first ``own`` elements' neighbours among all (bounding spheres within ``margin``),
    in index order (deterministic)."""
    from itertools import chain

    from scipy.spatial import cKDTree

    if own == 0:
        return np.zeros(1, np.int64), np.zeros(0, np.int64)
    tree = cKDTree(elements.centre)
    reach = 2.0 * float(elements.radius.max()) + margin
    found = tree.query_ball_point(elements.centre[:own], reach, return_sorted=True)  # one query for all
    sizes = np.fromiter((len(f) for f in found), np.int64, count=own)
    near = np.fromiter(chain.from_iterable(found), np.int64, count=int(sizes.sum()))
    row = np.repeat(np.arange(own, dtype=np.int64), sizes)
    gap = np.linalg.norm(elements.centre[near] - elements.centre[row], axis=1)
    keep = (near != row) & (gap <= elements.radius[row] + elements.radius[near] + margin)
    start = np.concatenate([[0], np.cumsum(np.bincount(row[keep], minlength=own))]).astype(np.int64)
    return start, near[keep]


def flatten(
    aggregate,
    neighbours=(),
    free_space=None,
    clearance: float = 0.005,
    share: float = 0.5,
    cap: float = 0.5,
    contacts: bool = True,
) -> tuple[Dents, dict]:
    """The dents of ``aggregate``'s elements pressed against each other and the ``neighbours``' elements
    (which are not moved here: flatten them with this aggregate as their neighbour) when ``contacts``, and,
    with ``free_space`` (φ, origin, pitch of the colliders' free space), against the walls. ``clearance`` is
    in element lengths (the median), ``cap`` in each element's thickness. Returns the dents and what moved."""
    fields: dict[int, int] = {}
    shells: list = []
    faces_of: list = []

    def fields_of(mesh) -> int:
        key = id(mesh)
        if key not in fields:
            fields[key] = len(shells)
            used = outer_vertices(mesh)
            faces = mesh.faces if mesh.parts is None else mesh.faces[mesh.parts == 0]
            remap = np.cumsum(used) - 1
            shells.append((mesh.vertices[used], remap[faces]))
            faces_of.append((len(mesh.vertices), np.asarray(mesh.faces)))
        return fields[key]

    everything = [aggregate, *neighbours]
    elements = _gather(everything, fields_of)
    grids = shape_fields(shells)
    own = len(aggregate.placement)
    world = np.concatenate(elements.world) if elements.world else np.zeros((0, 3))
    shell = np.concatenate(elements.shell) if elements.shell else np.zeros(0, bool)
    vstart = np.concatenate([[0], np.cumsum([len(w) for w in elements.world])]).astype(np.int64)
    length = float(np.median(np.ptp(np.stack([elements.lo, elements.hi]), axis=0).max(axis=1)))
    gap = clearance * length
    nstart, near = _neighbour_lists(elements, own if contacts else 0, 2.0 * gap)
    if not contacts:  # no pair is tested: every element's row is empty
        nstart = np.zeros(own + 1, np.int64)
    pad = np.full(3, gap)
    maps = ElementMaps(
        elements.shape, elements.lin_inv, elements.rot, elements.bend, elements.t, elements.lo - pad, elements.hi + pad
    )
    vertices = ElementVertices(world, vstart, shell)
    push = neighbour_pushes(vertices, ContactPairs(nstart, near), maps, grids, vertex_rings(faces_of), gap, share)
    if free_space is not None:
        cphi, corigin, cpitch = free_space
        reach = 0.5 * float(np.min(elements.thickness[:own])) if own else 0.0
        mine = vstart[own]
        push += wall_pushes(
            world[:mine] + push, shell[:mine], np.ascontiguousarray(cphi), np.asarray(corigin, float), float(cpitch),
            gap, reach,
        )  # fmt: skip
    push = capped(push, vstart[: own + 1], cap * elements.thickness[:own])
    moved = np.flatnonzero(np.any(push != 0.0, axis=1))
    owner = np.searchsorted(vstart, moved, side="right") - 1
    dents = Dents(owner.astype(np.int64), (moved - vstart[owner]).astype(np.int64), push[moved])
    depth = np.linalg.norm(push[moved], axis=1) / length
    dented = np.unique(owner)
    folded = sum(
        folded_faces(world[vstart[i] : vstart[i + 1]], push[vstart[i] : vstart[i + 1]], faces_of[elements.shape[i]][1])
        for i in dented
    )
    figures = {
        "elements": own,
        "dented_elements": len(dented),
        "moved_vertices": len(moved),
        "dent_p50": float(np.percentile(depth, 50)) if len(depth) else 0.0,
        "dent_p95": float(np.percentile(depth, 95)) if len(depth) else 0.0,
        "dent_max": float(depth.max()) if len(depth) else 0.0,
        "folded_faces": int(folded),
        "capped_vertices": int(
            np.sum(np.isclose(np.linalg.norm(push[moved], axis=1), cap * elements.thickness[owner]))
        ),
    }
    return dents, figures


def folded_faces(vertices: np.ndarray, push: np.ndarray, faces: np.ndarray) -> int:
    """How many faces the moves turn over (their normal reversed): folds a renderer would show as creases."""

    def normals(x):
        return np.cross(x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]])

    return int(np.sum(np.einsum("ij,ij->i", normals(vertices), normals(vertices + push)) < 0.0))


def merged_dents(aggregate, dents: Dents) -> dict:
    """The ``DeformedAggregate`` dent fields of ``dents`` added to those ``aggregate`` carries already (a
    second pass starts from the first's flattened meshes)."""
    element, vertex, offset = dents.element, dents.vertex, dents.offset
    if getattr(aggregate, "dented", False):
        element = np.concatenate([aggregate.dent_element, element])
        vertex = np.concatenate([aggregate.dent_vertex, vertex])
        offset = np.concatenate([aggregate.dent_offset, offset])
    key = element * (int(vertex.max()) + 1 if len(vertex) else 1) + vertex
    unique, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    # each key's offsets summed in their order (as np.add.at would, at a tenth of its time)
    summed = np.stack([np.bincount(inverse, offset[:, d], len(unique)) for d in range(3)], axis=1)
    return {"dent_element": element[first], "dent_vertex": vertex[first], "dent_offset": summed}
