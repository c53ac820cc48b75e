"""Contact deformation: the soft grains' meshes dented smoothly where they press together, their volume kept —
SPEC §3 (G: each grain an elastic body, the low-resolution simulation carrying the high-resolution grain).

The XPBD run resolves contacts between particle clusters that leave a grain's surface uncovered, so the meshes
of touching grains still cut into each other (issue 17). ``contact_flattening`` pressed the cut-in vertices
onto a plane: a crease at the patch's rim, folded faces, and volume lost (issue 25). Here each element's
shell gets a displacement field d instead, the solution of a small obstacle problem:

    minimise Σ_edges |d_u − d_v|² + κ Σ_v |d_v|²   subject to   n_c·(x_c + d_c) ≤ p_c for every contact c,

a screened membrane (κ sets how far a dent spreads: decay length ``spread``) solved by projected Gauss–Seidel.
The contacts are the half-spaces of ``contact_flattening``: between two elements the plane across their
overlap's lens, each element giving way its ``share``; against a wall or mould the wall's tangent plane.
Then the volume the dent took comes back as a bulge of the free surface along its normals (cooked rice is
nearly incompressible), new contacts the bulge makes are added (away from the neighbour's rest surface), and
the two repeat. On the full main job it still folds faces where a bumpy skin is held on a plane, and its bulge
bound gives back too little volume: docs/contact.md measures it against the flattening, which the recipes keep.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from .collider import sample_phi
from .contact_flattening import (
    ContactPairs,
    Dents,
    ElementMaps,
    ElementVertices,
    InsideVertices,
    _gather,
    _neighbour_lists,
    lens_axis,
    near_surface,
    outer_vertices,
    shape_fields,
    vertex_rings,
)


class ShellFaces(NamedTuple):
    """Each shape's outer-shell faces (indices into its own mesh's vertices) and its edge-adjacent face pairs, as
    CSRs by shape."""

    start: np.ndarray  # (s + 1,) int64
    faces: np.ndarray  # (f, 3) int64
    pair_start: np.ndarray  # (s + 1,) int64: shape s's edge-adjacent face pairs are pairs[pair_start[s]:...]
    pairs: np.ndarray  # (p, 2) int64, rows of the shape's own faces


class Walls(NamedTuple):
    """The colliders' free-space field (φ > 0 free, ``collider.free_space_field``) and how deep a vertex may be in
    a wall and still go back out along ∇φ (beyond, it may be past a thin wall's middle)."""

    phi: np.ndarray  # (nx, ny, nz)
    origin: np.ndarray  # (3,)
    pitch: float
    reach: float


class DeformSettings(NamedTuple):
    """The solve's settings, world lengths: gap left between surfaces, each element's share of a contact, a dent's
    decay length, Gauss–Seidel sweeps per solve, solve–bulge rounds."""

    clearance: float
    share: float
    spread: float
    sweeps: int
    rounds: int
    guard: bool


class Constraints(NamedTuple):
    """Scratch of one element's contacts: vertex row (local), half-space n·x ≤ p, the pair (−1 for a wall)."""

    row: np.ndarray  # (most,) int64
    normal: np.ndarray  # (most, 3)
    plane: np.ndarray  # (most,)
    pair: np.ndarray  # (most,) int64


class Figures(NamedTuple):
    """Per element: rest volume, volume before the bulge (dented only) and after, folded faces, capped vertices,
    how much the fold guard shortened its move (0: not at all, 1: to nothing)."""

    rest: np.ndarray
    dented: np.ndarray
    final: np.ndarray
    folded: np.ndarray
    capped: np.ndarray
    shrunk: np.ndarray


@njit(cache=True)
def _pair_planes(vertices, i, pairs, maps, fields, settings, found, out):
    """Element i's contacts with each neighbour j of ``pairs``: its rest vertices inside j (within the clearance)
    below the plane across the overlap's lens at a − share·(a − b) along the lens' axis n, [b, a] how far the
    two sides reach into each other (the plane ``contact_flattening.neighbour_pushes`` flattens onto; j computes
    the same plane from its side). Into ``out`` from row 0; returns how many."""
    world, vstart = vertices.world, vertices.start
    found_x, found_y = found
    rows_x, depth_x = found_x.rows, found_x.depth
    rows_y, depth_y = found_y.rows, found_y.depth
    own = world[vstart[i] : vstart[i + 1]]
    own_shell = vertices.shell[vstart[i] : vstart[i + 1]]
    clearance, share = settings.clearance, settings.share
    n = np.empty(3)
    count = 0
    for q in range(pairs.start[i], pairs.start[i + 1]):
        j = pairs.index[q]
        cx = near_surface(own, own_shell, j, maps, fields, clearance, found_x, 0)
        if cx == 0:
            continue
        other = world[vstart[j] : vstart[j + 1]]
        cy = near_surface(other, vertices.shell[vstart[j] : vstart[j + 1]], i, maps, fields, clearance, found_y, 0)
        if not lens_axis(found_x, cx, found_y, cy, n):
            continue
        top, bottom = -np.inf, np.inf
        for k in range(cx):
            h = own[rows_x[k], 0] * n[0] + own[rows_x[k], 1] * n[1] + own[rows_x[k], 2] * n[2]
            top = max(top, h)
            if cy == 0:
                bottom = min(bottom, h - depth_x[k])
        for k in range(cy):
            h = other[rows_y[k], 0] * n[0] + other[rows_y[k], 1] * n[1] + other[rows_y[k], 2] * n[2]
            bottom = min(bottom, h)
            if cx == 0:
                top = max(top, h + depth_y[k])
        plane = top - share * (top - bottom) - 0.5 * clearance
        for k in range(cx):
            if count == out.row.shape[0]:
                return count
            out.row[count] = rows_x[k]
            out.normal[count, 0], out.normal[count, 1], out.normal[count, 2] = n[0], n[1], n[2]
            out.plane[count] = plane
            out.pair[count] = q
            count += 1
    return count


@njit(cache=True)
def _wall_planes(points, shell, walls, clearance, out, count):
    """Contacts of the shell vertices inside the walls (φ < clearance, no deeper than the reach): the wall's
    tangent plane moved out by the clearance — walls do not give. Appended to ``out`` after ``count``."""
    for k in range(points.shape[0]):
        if not shell[k] or count == out.row.shape[0]:
            continue
        val, gx, gy, gz = sample_phi(walls.phi, walls.origin, walls.pitch, points[k, 0], points[k, 1], points[k, 2])
        if not val < clearance or val < -walls.reach:
            continue
        g = np.sqrt(gx * gx + gy * gy + gz * gz)
        if not g > 0.0:
            continue
        out.row[count] = k
        out.normal[count, 0], out.normal[count, 1], out.normal[count, 2] = -gx / g, -gy / g, -gz / g
        out.plane[count] = -(gx * points[k, 0] + gy * points[k, 1] + gz * points[k, 2]) / g - (clearance - val)
        out.pair[count] = -1
        count += 1
    return count


@njit(cache=True)
def _project(position, contact, count, rounds=3):
    """Each contacted vertex back into its half-spaces (n·x ≤ p), in order, ``rounds`` times (a vertex with two)."""
    for _ in range(rounds):
        for c in range(count):
            k = contact.row[c]
            h = 0.0
            for a in range(3):
                h += contact.normal[c, a] * position[k, a]
            if h > contact.plane[c]:
                for a in range(3):
                    position[k, a] -= (h - contact.plane[c]) * contact.normal[c, a]


@njit(cache=True)
def _volume(points, faces):
    """Enclosed volume of a closed shell (divergence theorem)."""
    total = 0.0
    for f in range(faces.shape[0]):
        a, b, c = points[faces[f, 0]], points[faces[f, 1]], points[faces[f, 2]]
        total += (
            a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
        )
    return total / 6.0


@njit(cache=True)
def _area_normals(points, faces, out):
    """Per vertex: the sum of its faces' normals × area / 3 (its share of the surface, along its normal)."""
    out[:] = 0.0
    for f in range(faces.shape[0]):
        a, b, c = points[faces[f, 0]], points[faces[f, 1]], points[faces[f, 2]]
        e0, e1, e2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
        g0, g1, g2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
        n0, n1, n2 = (e1 * g2 - e2 * g1) / 6.0, (e2 * g0 - e0 * g2) / 6.0, (e0 * g1 - e1 * g0) / 6.0
        for v in range(3):
            out[faces[f, v], 0] += n0
            out[faces[f, v], 1] += n1
            out[faces[f, v], 2] += n2


@njit(cache=True)
def _folded(rest, points, faces, pairs):
    """Edge-adjacent face pairs whose normals the deformation turned more than 150° apart (none at rest): a fold,
    which a renderer shows as a crease and which fools a pseudonormal inside test (the checkers' criterion)."""
    count = 0
    limit = np.cos(np.radians(150.0))
    for q in range(pairs.shape[0]):
        cos_now = _cosine(points, faces[pairs[q, 0]], faces[pairs[q, 1]])
        if cos_now < limit and not _cosine(rest, faces[pairs[q, 0]], faces[pairs[q, 1]]) < limit:
            count += 1
    return count


@njit(cache=True)
def _cosine(points, f, g):
    """Cosine of the angle between two faces' normals."""
    a = np.cross(points[f[1]] - points[f[0]], points[f[2]] - points[f[0]])
    b = np.cross(points[g[1]] - points[g[0]], points[g[2]] - points[g[0]])
    norm = np.sqrt(np.dot(a, a) * np.dot(b, b))
    return np.dot(a, b) / norm if norm > 0.0 else 1.0


@njit(cache=True)
def _relax(field, position, rest, ring_of, contact, count, screen, sweeps):
    """``sweeps`` of projected Gauss–Seidel on the screened membrane: each shell vertex's dent to its ring's mean
    over (degree + κ), then the contacts (``position`` = ``rest`` + ``field`` + the bulge, kept in step)."""
    start, ring, row, shell = ring_of
    for _ in range(sweeps):
        for k in range(field.shape[0]):
            if not shell[k]:
                continue
            lo, hi = start[row + k], start[row + k + 1]
            for a in range(3):
                s = 0.0
                for q in range(lo, hi):
                    s += field[ring[q], a]
                new = s / (hi - lo + screen)
                position[k, a] += new - field[k, a]
                field[k, a] = new
        for c in range(count):
            k = contact.row[c]
            h = 0.0
            for a in range(3):
                h += contact.normal[c, a] * position[k, a]
            if h > contact.plane[c]:
                for a in range(3):
                    step = (h - contact.plane[c]) * contact.normal[c, a]
                    position[k, a] -= step
                    field[k, a] -= step


@njit(cache=True)
def deform_elements(vertices, pairs, maps, fields, rings, shells, walls, settings, cap):
    """Per shell vertex of each of the first elements (rows of ``pairs``): its move, the dent of the obstacle
    problem above plus the bulge that gives the element its rest volume back (module docstring). Each element
    writes only its own vertices, in a fixed order: deterministic. Returns the moves and the ``Figures``."""
    world, vstart = vertices.world, vertices.start
    own = pairs.start.shape[0] - 1
    push = np.zeros((vstart[own], 3))
    figures = Figures(
        np.zeros(own), np.zeros(own), np.zeros(own), np.zeros(own, np.int64), np.zeros(own, np.int64), np.zeros(own)
    )
    most = 0
    for e in range(vstart.shape[0] - 1):
        most = max(most, vstart[e + 1] - vstart[e])
    found = (
        InsideVertices(np.empty(most, np.int64), np.empty(most), np.empty((most, 3))),
        InsideVertices(np.empty(most, np.int64), np.empty(most), np.empty((most, 3))),
    )
    contact = Constraints(
        np.empty(8 * most, np.int64), np.empty((8 * most, 3)), np.empty(8 * most), np.empty(8 * most, np.int64)
    )
    mark = np.full(most, -1, np.int64)
    for i in range(own):
        first, last = vstart[i], vstart[i + 1]
        rest = world[first:last]
        shell = vertices.shell[first:last]
        s = maps.shape[i]
        faces = shells.faces[shells.start[s] : shells.start[s + 1]]
        adjacent = shells.pairs[shells.pair_start[s] : shells.pair_start[s + 1]]
        figures.rest[i] = _volume(rest, faces)
        primary = _pair_planes(vertices, i, pairs, maps, fields, settings, found, contact)
        primary = _wall_planes(rest, shell, walls, settings.clearance, contact, primary)
        if primary == 0:
            figures.dented[i] = figures.final[i] = figures.rest[i]
            continue
        nv = last - first
        position = rest.copy()
        field = np.zeros((nv, 3))
        # κ from the decay per edge r = exp(−h/spread): a 1-D chain d_k = (d_{k−1} + d_{k+1}) / (2 + κ) decays by r
        edges, length = 0, 0.0
        for k in range(nv):
            for q in range(rings.start[rings.row[s] + k], rings.start[rings.row[s] + k + 1]):
                length += np.sqrt(np.sum((rest[rings.ring[q]] - rest[k]) ** 2))
                edges += 1
        edge = length / max(edges, 1)
        decay = np.exp(-edge / settings.spread)
        screen = (1.0 - decay) ** 2 / decay
        ring_of = (rings.start, rings.ring, rings.row[s], shell)
        count = primary
        area = np.empty((nv, 3))
        weight = np.empty(nv)
        reach = 0.0
        for r in range(settings.rounds):
            if r > 0:  # the bulge's new contacts: vertices now near a neighbour, kept off its rest surface
                count = primary
                for q in range(pairs.start[i], pairs.start[i + 1]):
                    for c in range(primary):
                        if contact.pair[c] == q:
                            mark[contact.row[c]] = q
                    j = pairs.index[q]
                    margin = settings.clearance + reach
                    found_count = near_surface(position, shell, j, maps, fields, margin, found[0], 0)
                    for c in range(found_count):
                        k = found[0].rows[c]
                        if mark[k] == q or count == contact.row.shape[0]:
                            continue
                        nn = found[0].normal[c]
                        contact.row[count] = k
                        contact.normal[count, 0], contact.normal[count, 1], contact.normal[count, 2] = (
                            -nn[0],
                            -nn[1],
                            -nn[2],
                        )
                        contact.plane[count] = -np.dot(nn, position[k]) - (margin + found[0].depth[c])
                        contact.pair[count] = q
                        count += 1
                    for c in range(primary):
                        mark[contact.row[c]] = -1
                count = _wall_planes(position, shell, walls, settings.clearance, contact, count)
            _relax(field, position, rest, ring_of, contact, count, screen, settings.sweeps)
            _project(position, contact, count)
            if r == 0:
                figures.dented[i] = _volume(position, faces)
            if r == settings.rounds - 1:
                break
            # the bulge: the lost volume back over the free surface, along its normals, fading into the contacts
            _area_normals(position, faces, area)
            for k in range(nv):
                weight[k] = 1.0 if shell[k] else 0.0
            for c in range(count):
                weight[contact.row[c]] = 0.0
            for _ in range(3):
                for k in range(nv):
                    if weight[k] > 0.0:
                        lo, hi = rings.start[rings.row[s] + k], rings.start[rings.row[s] + k + 1]
                        total = 0.0
                        for q in range(lo, hi):
                            total += weight[rings.ring[q]]
                        weight[k] = 0.5 * weight[k] + 0.5 * total / (hi - lo)
            lost = figures.rest[i] - _volume(position, faces)
            spread_area = 0.0
            for k in range(nv):
                spread_area += weight[k] * np.sqrt(np.sum(area[k] ** 2))
            if not spread_area > 0.0:
                break
            # the fold guard: a bulge moves no vertex more than a fifth of an edge per round (what is left is reported)
            step = min(lost / spread_area, 0.2 * edge) if lost > 0.0 else max(lost / spread_area, -0.2 * edge)
            for k in range(nv):
                a = np.sqrt(np.sum(area[k] ** 2))
                if a > 0.0 and weight[k] > 0.0:
                    for d in range(3):
                        position[k, d] += step * weight[k] * area[k, d] / a
            reach += abs(step)
        move = position - rest
        for k in range(nv):
            length = np.sqrt(np.sum(move[k] ** 2))
            if length > cap[i]:
                move[k] *= cap[i] / length
                figures.capped[i] += 1
        # the fold guard: a move that folds two faces (contacts that cannot all hold, a grain crossed deep
        # by another) is shortened as a whole, halving, until none does: what it leaves is overlap, measured
        scale = 1.0
        while settings.guard and scale > 0.05 and _folded(rest, rest + scale * move, faces, adjacent) > 0:
            scale *= 0.5
        if scale <= 0.05:
            scale = 0.0
        figures.folded[i] = _folded(rest, rest + scale * move, faces, adjacent)
        figures.shrunk[i] = 1.0 - scale
        for k in range(nv):
            for d in range(3):
                push[first + k, d] = scale * move[k, d]
        figures.final[i] = _volume(rest + scale * move, faces)
    return push, figures


def deform(aggregate, neighbours=(), free_space=None, settings: dict | None = None, contacts: bool = True):
    """The moves of ``aggregate``'s elements dented against each other and the ``neighbours``' elements (not moved
    here: deform them with this aggregate as their neighbour) when ``contacts``, and, with ``free_space`` (φ,
    origin, pitch of the colliders' free space), against the walls. ``settings``: clearance (element lengths,
    the median), share, cap and spread (each element's thickness), sweeps, rounds. Returns the dents and the
    figures (dented elements, moved vertices, dent depth, volume error, folded faces)."""
    import trimesh

    given = {"clearance": 0.005, "share": 0.5, "cap": 0.5, "spread": 0.1, "sweeps": 20, "rounds": 5, "guard": False}
    given |= settings or {}
    fields: dict[int, int] = {}
    shells: list = []
    rings_of: list = []
    faces_of: list = []

    def fields_of(mesh) -> int:
        key = id(mesh)
        if key not in fields:
            fields[key] = len(shells)
            used = outer_vertices(mesh)
            faces = np.asarray(mesh.faces if mesh.parts is None else mesh.faces[mesh.parts == 0], np.int64)
            remap = np.cumsum(used) - 1
            shells.append((mesh.vertices[used], remap[faces]))
            rings_of.append((len(mesh.vertices), faces))
            faces_of.append(faces)
        return fields[key]

    elements = _gather([aggregate, *neighbours], fields_of)
    own = len(aggregate.placement)
    world = np.concatenate(elements.world) if elements.world else np.zeros((0, 3))
    shell = np.concatenate(elements.shell) if elements.shell else np.zeros(0, bool)
    vstart = np.concatenate([[0], np.cumsum([len(w) for w in elements.world])]).astype(np.int64)
    length = float(np.median(np.ptp(np.stack([elements.lo, elements.hi]), axis=0).max(axis=1))) if own else 1.0
    gap = given["clearance"] * length
    nstart, near = _neighbour_lists(elements, own if contacts else 0, 2.0 * gap)
    if not contacts:
        nstart = np.zeros(own + 1, np.int64)
    pad = np.full(3, gap)
    maps = ElementMaps(
        elements.shape, elements.lin_inv, elements.rot, elements.bend, elements.t, elements.lo - pad, elements.hi + pad
    )
    if free_space is None:
        walls = Walls(np.full((2, 2, 2), np.inf), np.zeros(3), 1.0, 0.0)
    else:
        cphi, corigin, cpitch = free_space
        reach = 0.5 * float(np.min(elements.thickness[:own])) if own else 0.0
        walls = Walls(np.ascontiguousarray(cphi, np.float64), np.asarray(corigin, np.float64), float(cpitch), reach)
    thickness = float(np.median(elements.thickness[:own])) if own else 1.0
    solve = DeformSettings(
        gap,
        float(given["share"]),
        given["spread"] * thickness,
        int(given["sweeps"]),
        int(given["rounds"]),
        bool(given["guard"]),
    )
    face_start = np.concatenate([[0], np.cumsum([len(f) for f in faces_of])]).astype(np.int64)
    adjacency = [
        np.asarray(trimesh.Trimesh(np.zeros((f.max() + 1, 3)), f, process=False).face_adjacency) for f in faces_of
    ]
    pair_start = np.concatenate([[0], np.cumsum([len(a) for a in adjacency])]).astype(np.int64)
    shell_faces = ShellFaces(
        face_start,
        np.concatenate(faces_of) if faces_of else np.zeros((0, 3), np.int64),
        pair_start,
        np.concatenate(adjacency).astype(np.int64) if adjacency else np.zeros((0, 2), np.int64),
    )
    push, figures = deform_elements(
        ElementVertices(world, vstart, shell),
        ContactPairs(nstart, near),
        maps,
        shape_fields(shells),
        vertex_rings(rings_of),
        shell_faces,
        walls,
        solve,
        given["cap"] * elements.thickness[:own],
    )
    moved = np.flatnonzero(np.any(push != 0.0, axis=1))
    owner = np.searchsorted(vstart, moved, side="right") - 1
    dents = Dents(owner.astype(np.int64), (moved - vstart[owner]).astype(np.int64), push[moved])
    depth = np.linalg.norm(push[moved], axis=1) / length
    dented = figures.dented != figures.rest
    error = np.abs(figures.final / np.where(figures.rest != 0.0, figures.rest, 1.0) - 1.0)
    lost = np.abs(figures.dented / np.where(figures.rest != 0.0, figures.rest, 1.0) - 1.0)
    table = {
        "elements": own,
        "dented_elements": int(dented.sum()),
        "moved_vertices": len(moved),
        "dent_p50": float(np.percentile(depth, 50)) if len(depth) else 0.0,
        "dent_p95": float(np.percentile(depth, 95)) if len(depth) else 0.0,
        "dent_max": float(depth.max()) if len(depth) else 0.0,
        "volume_lost_max": float(lost.max()) if own else 0.0,
        "volume_error_p95": float(np.percentile(error, 95)) if own else 0.0,
        "volume_error_max": float(error.max()) if own else 0.0,
        "folded_faces": int(figures.folded.sum()),
        "capped_vertices": int(figures.capped.sum()),
        "guarded_elements": int(np.sum(figures.shrunk > 0.0)),
    }
    return dents, table
