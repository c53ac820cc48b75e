"""Contact deformation: the soft grains' meshes dented smoothly where they press together, their volume kept —
SPEC §3 (G: each grain an elastic body, the low-resolution simulation carrying the high-resolution grain).

The XPBD run resolves contacts between particle clusters that leave a grain's surface uncovered, so the meshes
of touching grains still cut into each other (issue 17). Pressing the cut-in vertices onto a plane
(``contact_flattening``) folds faces at the patch's rim and loses volume; moving them one by one, however
smoothly relaxed afterwards, folds a bumpy skin wherever some vertices are held and their neighbours are not
(docs/contact.md). Here each element is moved by *smooth maps of space* instead, never vertex by vertex:

- **dent** (per contact): x ↦ x − n · A · g(r⊥/b) · T((top − n·x)/ℓ), with g(t) = (1 − t²)² a bump of radius b
  across the contact's axis n and T a smoothstep fading over depth ℓ into the element. A and b are the
  smallest that push every cut-in vertex k its required distance s_k (A·g(r_k/b) ≥ s_k), b at least 2.5 × the
  cut-in patch's radius (the patch stays convex), with the map's shear
  A·max|g'|/b ≤ ``slope``; ℓ ≥ 2A keeps det(∇map) = 1 − A·g·|T'| ≥ ¼. A map with a positive Jacobian turns
  no face over, so the dented mesh stays fold-free and closed whatever its skin's bumps;
- **bulge** (per element, between dents): the volume the dents took back as a move u_k = min(β, limit_k) along
  the outward normal of the element's ellipsoid (a smooth field). The limit keeps bulges from meeting: ⅔ of the
  vertex's distance to each plane the element stays under — its lenses' planes, and towards a neighbour whose rest
  surface is near but does not overlap, the separating plane halfway across their closest approach (both sides
  find the same one) — and ⅔ of the distance to the walls. Each side stays under its own planes however often it
  bulges. A plane's distance is linear in position, so the limit is a lower envelope of linear functions: where
  it holds the bulge back the skin bends outward (a ridge), never inward. A share of the distance to a
  neighbour's *surface* copied that convex surface into the skin as a hollow (skin score 0.11 on the main job's
  rice, 0.074 with the planes), and a plane applied only near its neighbour stepped where the search stopped (the
  rice bowl 0.119, 0.095 with every plane everywhere). β is the one that gives the element its rest volume back
  (bisection: volume grows with β). Cooked rice is nearly incompressible: a pressed grain bulges.

The contacts: between two elements the plane across their overlap's lens, each element giving way its
``share`` (``contact_flattening.neighbour_pushes`` flattens onto the same plane), but all of it where the other has
no vertex inside it (a dent moves the vertices that cut in: a coarse chestnut piece whose face a fine grain's tip
pokes into cannot give way, and half the depth was left; deform_contacts v5); between elements whose rest
surfaces did not overlap but whose moved ones come near, the other's rest surface; against a wall or mould the
wall's distance field (walls do not give). Dent–bulge rounds repeat, the last one dents only.

An element boxed in so tightly that no bulge gives its volume back (more than ``STARVED`` short after the rounds)
gives way less on another pass: its lenses with the others of its aggregate split by how readily each side gives
way, so its neighbours, which have room outside, take more of the depth (up to ``STARVED_PASSES`` passes, only the
starved elements and their neighbours recomputed). The rice bowl had two such grains 6 and 13 % short, the onigiri
two 5 % short; a ball pressed by fourteen others lost 31 % (tests/contact_shaping/test_deform_contacts.py).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import numpy as np
from numba import get_num_threads, njit

from ..simulation.collider import sample_phi
from .contact_flattening import (
    ContactPairs,
    Dents,
    ElementMaps,
    ElementVertices,
    InsideVertices,
    ShapeFields,
    _gather,
    _neighbour_lists,
    lens_axis,
    near_surface,
    outer_vertices,
    shape_fields,
    vertex_rings,
)

# max |g'(t)| of the bump g(t) = (1 − t²)², at t = 1/√3
BUMP_SLOPE = 8.0 / (3.0 * np.sqrt(3.0))
# widths tried for a dent's bump, in units of its cut-in patch's radius a: √2 would press a paraboloid cap exactly
# flat; from 2.5 a dent takes at most 2/2.5² = 32 % of the cap's curvature, so the patch stays convex (a flat patch
# turns half the skin's small bumps concave)
BUMP_WIDTHS = (2.5, 3.0, 4.0, 5.0)
# dent passes per round at most: each pass meets every contact in turn; later dents rarely undo earlier ones
DENT_PASSES = 8
# sweeps of ``_unfold`` at most: each averages a fold's corners with their rings
UNFOLD_SWEEPS = 8
# a volume this close to the rest volume needs no bulge (a fiftieth of the 2 % bar)
VOLUME_TOLERANCE = 4e-4
# a bulge takes at most this share of the room (less the clearance) before a neighbour's surface or a wall: two
# bulges never meet, and the room is looked for up to this many bulges (plus the clearance) away
ROOM_SHARE = 1.0 / 3.0
# an element boxed in so tightly that its bulge cannot give back more than this share of its volume gives way less
# in its lenses on the next pass (its give × STARVED_GIVE), its neighbours in the aggregate more: they have room
STARVED = 0.01
STARVED_GIVE = 0.25
STARVED_PASSES = 3


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
    """The solve's settings, world lengths: gap left between surfaces, each element's share of a lens, the dents'
    largest shear, the largest bulge, dent–bulge rounds."""

    clearance: float
    share: float
    slope: float
    bulge: float
    rounds: int
    near: bool  # a plane holds only the vertices under it or near its neighbour (``_held``)


class Lenses(NamedTuple):
    """Element i's lens contacts, one row per neighbour whose rest surface overlaps i's: the pair's row in the
    neighbour lists, the lens' axis n (out of i) and the plane n·x = p that i's vertices stay under."""

    pair: np.ndarray  # (most,) int64
    normal: np.ndarray  # (most, 3)
    plane: np.ndarray  # (most,)


class Cap(NamedTuple):
    """Scratch of one dent: the rows of the cut-in vertices, how far each must go along −n, and which shell
    vertices are past a lens' plane (only those are looked up in the neighbour's field)."""

    rows: np.ndarray  # (most,) int64
    need: np.ndarray  # (most,)
    past: np.ndarray  # (element's vertices,) bool


class Surroundings(NamedTuple):
    """What an element is dented against: the neighbour lists, every element's map and shape field, the walls."""

    pairs: ContactPairs
    maps: ElementMaps
    fields: ShapeFields
    walls: Walls


class Scratch(NamedTuple):
    """One element's working arrays: vertices found near a neighbour, a dent's cap, each contact's dent so far
    (lenses first, then the neighbour pairs, the walls last)."""

    found: InsideVertices
    cap: Cap
    spent: np.ndarray


class Budgets(NamedTuple):
    """Per element: the longest move of a vertex, the mean edge length of its mesh (a dent's patch is never
    narrower) and how readily it gives way in a lens against the others of its aggregate (``_lenses``)."""

    cap: np.ndarray
    edge: np.ndarray
    give: np.ndarray


class Figures(NamedTuple):
    """Per element: rest volume, volume after the first dents and at the end, folded faces, dents whose push
    reached the cap, the bulge's β of the last round."""

    rest: np.ndarray
    dented: np.ndarray
    final: np.ndarray
    folded: np.ndarray
    capped: np.ndarray
    bulge: np.ndarray


@njit(cache=True, error_model="numpy")
def _lenses(vertices, i, pairs, maps, fields, settings, give, found, out):
    """Element i's lens contacts (``Lenses``, from row 0): per neighbour j whose rest surface overlaps i's (a vertex
    of either inside the other), the lens' axis n and the plane at a − share·(a − b) − e along it, [b, a] how far
    the two sides reach into each other (j computes the same plane from its side). Against an element of the same
    aggregate that gives way less readily (``give``), i takes e = (s − share)·min(a − b, bulge) more, s =
    2·share·give_i / (give_i + give_j): e is 0 when both give alike, −e is j's, and no more than a bulge's depth
    changes hands, so a deep interlock still splits evenly within both sides' dent budgets. Returns how many."""
    world, vstart = vertices.world, vertices.start
    found_x, found_y = found
    own = world[vstart[i] : vstart[i + 1]]
    own_shell = vertices.shell[vstart[i] : vstart[i + 1]]
    clearance = settings.clearance
    n = np.empty(3)
    count = 0
    for q in range(pairs.start[i], pairs.start[i + 1]):
        j = pairs.index[q]
        # only vertices truly inside (depth > 0): a near-touching one's normal and place say nothing of the lens
        cx = near_surface(own, own_shell, j, maps, fields, 0.0, found_x, 0)
        other = world[vstart[j] : vstart[j + 1]]
        cy = near_surface(other, vertices.shell[vstart[j] : vstart[j + 1]], i, maps, fields, 0.0, found_y, 0)
        if cx + cy == 0:
            continue
        if not lens_axis(found_x, cx, found_y, cy, n):
            continue
        top, bottom = -np.inf, np.inf
        for k in range(cx):
            h = own[found_x.rows[k], 0] * n[0] + own[found_x.rows[k], 1] * n[1] + own[found_x.rows[k], 2] * n[2]
            top = max(top, h)
            if cy == 0:
                bottom = min(bottom, h - found_x.depth[k])
        for k in range(cy):
            h = other[found_y.rows[k], 0] * n[0] + other[found_y.rows[k], 1] * n[1] + other[found_y.rows[k], 2] * n[2]
            bottom = min(bottom, h)
            if cx == 0:
                top = max(top, h + found_y.depth[k])
        out.pair[count] = q
        out.normal[count, 0], out.normal[count, 1], out.normal[count, 2] = n[0], n[1], n[2]
        # a dent moves the vertices that cut in: a side none of whose vertices lies inside the other (a coarse chestnut
        # piece whose face a fine grain's tip pokes into) cannot give way, so the other takes the whole depth (j, from
        # its side, finds the same plane and takes none); it kept half (0.31 mm) before
        share = 1.0 if cy == 0 else (0.0 if cx == 0 else settings.share)
        extra = 0.0
        if j < give.shape[0]:
            extra = (2.0 * give[i] / (give[i] + give[j]) - 1.0) * share * min(top - bottom, settings.bulge)
        out.plane[count] = top - share * (top - bottom) - extra - 0.5 * clearance
        count += 1
    return count


@njit(cache=True, error_model="numpy", inline="always")
def _bump(t):
    """g(t) = (1 − t²)² for |t| < 1, else 0: smooth, flat at its top, zero slope at its rim."""
    if t >= 1.0:
        return 0.0
    s = 1.0 - t * t
    return s * s


@njit(cache=True, error_model="numpy", inline="always")
def _fade(depth, length):
    """T: 1 above the dent's top (depth ≤ 0), a smoothstep down to 0 at ``length`` below it."""
    if depth <= 0.0:
        return 1.0
    if depth >= length:
        return 0.0
    t = depth / length
    return 1.0 - t * t * (3.0 - 2.0 * t)


@njit(cache=True, error_model="numpy")
def dent(position, shell, cap, count, n, slope, edge, most):
    """The smooth dent of the module docstring for the cut-in vertices ``cap`` (rows, need along −n), applied to
    every vertex of the element (an inner part moves with it). The bump's width is the one of ``BUMP_WIDTHS``
    that takes the least volume (∝ A·b²) with shear ≤ ``slope``; its amplitude is at most ``most``. Returns A."""
    rows, need = cap.rows, cap.need
    centre = np.zeros(3)
    total = 0.0
    top = np.inf
    for c in range(count):
        k = rows[c]
        total += need[c]
        for a in range(3):
            centre[a] += need[c] * position[k, a]
        top = min(top, n[0] * position[k, 0] + n[1] * position[k, 1] + n[2] * position[k, 2])
    for a in range(3):
        centre[a] /= total
    radial = np.empty(count)
    patch = edge  # a one-vertex patch is still an edge wide
    for c in range(count):
        k = rows[c]
        d0, d1, d2 = position[k, 0] - centre[0], position[k, 1] - centre[1], position[k, 2] - centre[2]
        h = d0 * n[0] + d1 * n[1] + d2 * n[2]
        r2 = d0 * d0 + d1 * d1 + d2 * d2 - h * h
        radial[c] = np.sqrt(max(r2, 0.0))
        patch = max(patch, radial[c])
    best_a, best_b, best_cost = np.inf, 0.0, np.inf
    for w in BUMP_WIDTHS:
        b = w * patch
        amp = 0.0
        for c in range(count):
            amp = max(amp, need[c] / _bump(radial[c] / b))
        amp = min(amp, most)
        while BUMP_SLOPE * amp / b > slope:  # too steep: wider (covers more, so no larger amplitude)
            b *= 1.25
        cost = amp * b * b
        if cost < best_cost:
            best_a, best_b, best_cost = amp, b, cost
    amp, b = best_a, best_b
    # the fade's depth: half the element's extent below the dent's top, and ≥ 2A (det ≥ 1 − 1.5·A/ℓ ≥ ¼)
    bottom = np.inf
    for k in range(position.shape[0]):
        if shell[k]:
            bottom = min(bottom, n[0] * position[k, 0] + n[1] * position[k, 1] + n[2] * position[k, 2])
    length = max(0.5 * (top - bottom), 2.0 * amp)
    for k in range(position.shape[0]):
        d0, d1, d2 = position[k, 0] - centre[0], position[k, 1] - centre[1], position[k, 2] - centre[2]
        h = d0 * n[0] + d1 * n[1] + d2 * n[2]
        r = np.sqrt(max(d0 * d0 + d1 * d1 + d2 * d2 - h * h, 0.0))
        if r >= b:
            continue
        move = amp * _bump(r / b) * _fade(top - (h + n[0] * centre[0] + n[1] * centre[1] + n[2] * centre[2]), length)
        for a in range(3):
            position[k, a] -= move * n[a]
    return amp


@njit(cache=True, error_model="numpy")
def _plane_cap(position, shell, j, maps, fields, margin, normal, plane, found, cap):
    """The cut-in vertices of a lens contact: near j's rest surface (within ``margin``, the clearance) and above its
    plane."""
    past = cap.past
    above = 0
    for k in range(position.shape[0]):
        h = normal[0] * position[k, 0] + normal[1] * position[k, 1] + normal[2] * position[k, 2]
        past[k] = shell[k] and h > plane + 1e-3 * margin  # past it by more than rounding: no push is exact
        above += past[k]
    if above == 0:
        return 0
    cx = near_surface(position, past, j, maps, fields, margin, found, 0)
    for c in range(cx):
        k = found.rows[c]
        cap.rows[c] = k
        cap.need[c] = normal[0] * position[k, 0] + normal[1] * position[k, 1] + normal[2] * position[k, 2] - plane
    return cx


@njit(cache=True, error_model="numpy")
def _surface_cap(found, cx, clearance, n, cap):
    """The cut-in vertices of a contact with a rest surface (``found``: depth and outward normal there): the
    axis n (into the surface, depth-weighted) into ``n``, and how far each must go along −n to be ``clearance``
    outside. Returns how many, 0 when the normals cancel."""
    for a in range(3):
        n[a] = 0.0
    for c in range(cx):
        w = found.depth[c] + clearance
        for a in range(3):
            n[a] -= w * found.normal[c, a]
    norm = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    if not norm > 0.0:
        return 0
    for a in range(3):
        n[a] /= norm
    count = 0
    for c in range(cx):
        if found.depth[c] + clearance <= 1e-3 * clearance:  # out by the clearance but for rounding
            continue
        cosine = -(n[0] * found.normal[c, 0] + n[1] * found.normal[c, 1] + n[2] * found.normal[c, 2])
        cap.rows[count] = found.rows[c]
        cap.need[count] = (found.depth[c] + clearance) / max(cosine, 0.5)
        count += 1
    return count


@njit(cache=True, error_model="numpy")
def _wall_found(position, shell, walls, clearance, found):
    """Shell vertices inside the walls (φ < clearance, no deeper than the reach) as ``near_surface`` gives them:
    depth −φ and the wall's outward normal (∇φ: into the free space)."""
    count = 0
    for k in range(position.shape[0]):
        if not shell[k]:
            continue
        val, gx, gy, gz = sample_phi(
            walls.phi, walls.origin, walls.pitch, position[k, 0], position[k, 1], position[k, 2]
        )
        if not val < clearance or val < -walls.reach:
            continue
        g = np.sqrt(gx * gx + gy * gy + gz * gz)
        if not g > 0.0:
            continue
        found.rows[count] = k
        found.depth[count] = -val
        found.normal[count, 0], found.normal[count, 1], found.normal[count, 2] = gx / g, gy / g, gz / g
        count += 1
    return count


@njit(cache=True, error_model="numpy", inline="always")
def _is_lens(lenses, count, q):
    """Whether pair row q is one of the first ``count`` lenses."""
    for c in range(count):
        if lenses.pair[c] == q:
            return True
    return False


@njit(cache=True, error_model="numpy")
def _gap_planes(rest, shell, i, around, lenses, count, settings, found, out):
    """Element i's separating planes (``Lenses`` rows from 0) towards each neighbour whose rest surface is within
    reach but does not overlap i's: the plane halfway across their closest approach, normal to j's surface there
    (n out of i), less half the clearance. j computes the same plane from its side (the closest pair is the same),
    so bulges held under their own side's plane never meet. Returns how many."""
    pairs, maps, fields = around.pairs, around.maps, around.fields
    reach = settings.bulge / ROOM_SHARE + settings.clearance
    made = 0
    for q in range(pairs.start[i], pairs.start[i + 1]):
        if _is_lens(lenses, count, q):
            continue
        cx = near_surface(rest, shell, pairs.index[q], maps, fields, reach, found, 0)
        if cx == 0:
            continue
        best = 0
        for c in range(1, cx):
            if found.depth[c] > found.depth[best]:
                best = c
        k = found.rows[best]
        n = -found.normal[best]
        out.pair[made] = q
        out.normal[made, 0], out.normal[made, 1], out.normal[made, 2] = n[0], n[1], n[2]
        across = n[0] * rest[k, 0] + n[1] * rest[k, 1] + n[2] * rest[k, 2]
        out.plane[made] = across - 0.5 * found.depth[best] - 0.5 * settings.clearance
        made += 1
    return made


@njit(cache=True, error_model="numpy")
def _held(rest, shell, around, planes_of, many, settings, found, held):
    """How each plane holds each shell vertex (``held[c, k]``): −1, by ⅔ of its distance to the plane (vertices under
    it at rest, and over it within reach r of the neighbour's rest surface: the lens' cap); a fixed ⅔·(d − r) for
    a vertex over it at rest a distance d ∈ (r, 2r] from the neighbour; not at all (∞) beyond. A vertex over the
    plane far from the neighbour is where a curled or bumpy element bends across the plane's extension: held by
    the plane it could never bulge (curled ice flakes lost their volume so), and its cap grows from 0 at the reach
    continuously, so the limit has no step."""
    pairs, maps, fields = around.pairs, around.maps, around.fields
    reach = settings.bulge / ROOM_SHARE + settings.clearance
    for c in range(many):
        n = planes_of.normal[c]
        for k in range(rest.shape[0]):
            below = planes_of.plane[c] - (n[0] * rest[k, 0] + n[1] * rest[k, 1] + n[2] * rest[k, 2])
            held[c, k] = -1.0 if below >= 0.0 else np.inf
        cx = near_surface(rest, shell, pairs.index[planes_of.pair[c]], maps, fields, 2.0 * reach, found, 0)
        for e in range(cx):
            k = found.rows[e]
            if held[c, k] > 0.0:
                far = -found.depth[e] - reach
                held[c, k] = -1.0 if far <= 0.0 else (1.0 - ROOM_SHARE) * far


@njit(cache=True, error_model="numpy")
def _bulge_limit(position, shell, walls, planes, counts, held, settings, limit):
    """Per shell vertex the most it may bulge this round (``bulge`` at most, 0 off the shell): ⅔ of its distance to
    every plane that holds it (``_held``) — its lenses' planes (``planes[0]``) and the separating planes halfway to
    its near neighbours (``planes[1]``, ``_gap_planes``) — and ⅔ of its distance to the walls less the clearance.
    Neither side crosses its plane however often it bulges, so a few rounds give the volume back. The limit is the lower
    envelope of linear functions of position, so the bulge it holds back bends outward only (a ridge, never a
    crease): a share of the distance to a neighbour's surface copied that convex surface into the skin as a hollow,
    and a plane applied only near the neighbour stepped where the search stopped (docs/contact.md).
    """
    lenses, gaps = planes
    count, gap_count = counts
    for k in range(position.shape[0]):
        limit[k] = settings.bulge if shell[k] else 0.0
    for planes_of, many, holds in ((lenses, count, held[0]), (gaps, gap_count, held[1])):
        for c in range(many):
            n = planes_of.normal[c]
            for k in range(position.shape[0]):
                if not shell[k]:
                    continue
                if holds[c, k] >= 0.0:
                    limit[k] = min(limit[k], holds[c, k])
                    continue
                below = planes_of.plane[c] - (n[0] * position[k, 0] + n[1] * position[k, 1] + n[2] * position[k, 2])
                limit[k] = min(limit[k], (1.0 - ROOM_SHARE) * below)
    for k in range(position.shape[0]):
        if shell[k]:
            val, _, _, _ = sample_phi(
                walls.phi, walls.origin, walls.pitch, position[k, 0], position[k, 1], position[k, 2]
            )
            limit[k] = max(0.0, min(limit[k], (1.0 - ROOM_SHARE) * (val - settings.clearance)))


@njit(cache=True, error_model="numpy")
def _volume(points, faces):
    """Enclosed volume of a closed shell (divergence theorem)."""
    total = 0.0
    for f in range(faces.shape[0]):
        a, b, c = points[faces[f, 0]], points[faces[f, 1]], points[faces[f, 2]]
        total += (
            a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
        )
    return total / 6.0


@njit(cache=True, error_model="numpy")
def _outward(position, lin_inv, t, shell, out):
    """Per vertex: the outward unit normal of the element's ellipsoid (its shell's extents in its local frame)
    at the vertex — a smooth direction field for the bulge, unlike the bumpy skin's own normals."""
    nv = position.shape[0]
    local = np.empty((nv, 3))
    extent = np.full(3, 1e-300)
    for k in range(nv):
        for a in range(3):
            local[k, a] = (
                lin_inv[a, 0] * (position[k, 0] - t[0])
                + lin_inv[a, 1] * (position[k, 1] - t[1])
                + lin_inv[a, 2] * (position[k, 2] - t[2])
            )
            if shell[k]:
                extent[a] = max(extent[a], abs(local[k, a]))
    for k in range(nv):
        g0 = local[k, 0] / (extent[0] * extent[0])
        g1 = local[k, 1] / (extent[1] * extent[1])
        g2 = local[k, 2] / (extent[2] * extent[2])
        norm = 0.0
        for a in range(3):  # ∇ₓ = (∂u/∂x)ᵀ ∇ᵤ
            out[k, a] = lin_inv[0, a] * g0 + lin_inv[1, a] * g1 + lin_inv[2, a] * g2
            norm += out[k, a] * out[k, a]
        norm = np.sqrt(norm)
        for a in range(3):
            out[k, a] = out[k, a] / norm if norm > 0.0 else 0.0


@njit(cache=True, error_model="numpy")
def _bulged(position, shell, outward, limit, beta, out):
    """``position`` with each shell vertex moved min(β, its limit) along ``outward``."""
    for k in range(position.shape[0]):
        move = min(beta, limit[k]) if shell[k] else 0.0
        for a in range(3):
            out[k, a] = position[k, a] + move * outward[k, a]


@njit(cache=True, error_model="numpy")
def bulge(position, shell, faces, outward, limit, target, most):
    """The element's volume back to ``target`` by the bulge of the module docstring: β by bisection in [0, most]
    (the volume grows with β). Moves ``position``; returns β (``most`` when even that is not enough)."""
    trial = np.empty_like(position)
    if _volume(position, faces) >= target:
        return 0.0
    _bulged(position, shell, outward, limit, most, trial)
    lo, hi = 0.0, most
    if _volume(trial, faces) > target:
        for _ in range(20):  # to a millionth of the largest bulge
            mid = 0.5 * (lo + hi)
            _bulged(position, shell, outward, limit, mid, trial)
            if _volume(trial, faces) < target:
                lo = mid
            else:
                hi = mid
    _bulged(position, shell, outward, limit, hi, position)  # in place: each row reads only itself
    return hi


@njit(cache=True, error_model="numpy")
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


@njit(cache=True, error_model="numpy")
def _unfold(rest, position, faces, pairs, rings, row):
    """Where the moves sharpened two faces past 150° (a sliver of the library mesh, whose normal turns with any
    move that is not affine across it): the two faces' corners all given one move, the mean of their rings' moves,
    so that the pair is carried as it is (a translation keeps its rest angle) and its neighbours, far wider than
    the sliver, bend by the small difference. Repeated until none is left or ``UNFOLD_SWEEPS`` sweeps. Returns the
    folds left."""
    limit = np.cos(np.radians(150.0))
    common = np.empty(3)
    for _ in range(UNFOLD_SWEEPS):
        left = 0
        for q in range(pairs.shape[0]):
            f, g = faces[pairs[q, 0]], faces[pairs[q, 1]]
            if not _cosine(position, f, g) < limit or _cosine(rest, f, g) < limit:
                continue
            left += 1
            common[:] = 0.0
            count = 0
            for corner in range(6):
                v = f[corner] if corner < 3 else g[corner - 3]
                for e in range(rings.start[row + v], rings.start[row + v + 1]):
                    u = rings.ring[e]
                    for a in range(3):
                        common[a] += position[u, a] - rest[u, a]
                    count += 1
            for corner in range(6):
                v = f[corner] if corner < 3 else g[corner - 3]
                for a in range(3):
                    position[v, a] = rest[v, a] + common[a] / max(count, 1)
        if left == 0:
            return 0
    return _folded(rest, position, faces, pairs)


@njit(cache=True, error_model="numpy")
def _cosine(points, f, g):
    """Cosine of the angle between two faces' normals."""
    a0, a1, a2 = _normal(points, f)
    b0, b1, b2 = _normal(points, g)
    norm = np.sqrt((a0 * a0 + a1 * a1 + a2 * a2) * (b0 * b0 + b1 * b1 + b2 * b2))
    return (a0 * b0 + a1 * b1 + a2 * b2) / norm if norm > 0.0 else 1.0


@njit(cache=True, error_model="numpy", inline="always")
def _normal(points, f):
    """A face's area-weighted normal (p1 − p0) × (p2 − p0)."""
    u0, u1, u2 = points[f[1], 0] - points[f[0], 0], points[f[1], 1] - points[f[0], 1], points[f[1], 2] - points[f[0], 2]
    v0, v1, v2 = points[f[2], 0] - points[f[0], 0], points[f[2], 1] - points[f[0], 1], points[f[2], 2] - points[f[0], 2]
    return u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0


@njit(cache=True, error_model="numpy", inline="always")
def _budget(rest, shell, n, most):
    """How far one contact may dent an element in all: ``most``, and a quarter of the element's rest extent along
    n, so that the dent's depth fade (≥ 2A) stays within the element's near half and dents from opposite sides
    never push one another back and forth (a grain squeezed thinner than that keeps the rest as overlap)."""
    lo, hi = np.inf, -np.inf
    for k in range(rest.shape[0]):
        if shell[k]:
            h = n[0] * rest[k, 0] + n[1] * rest[k, 1] + n[2] * rest[k, 2]
            lo, hi = min(lo, h), max(hi, h)
    return min(most, (hi - lo) / 4.0)


@njit(cache=True, error_model="numpy")
def _dent_spent(position, rest, shell, cap, m, n, settings, edge, most, spent, slot):
    """One dent within what is left of contact ``slot``'s budget; returns 1 when the budget is spent."""
    total = _budget(rest, shell, n, most)
    if total - spent[slot] <= 1e-9 * edge:
        return 1
    spent[slot] += dent(position, shell, cap, m, n, settings.slope, edge, total - spent[slot])
    return int(total - spent[slot] <= 1e-9 * edge)


@njit(cache=True, error_model="numpy")
def _dent_pass(position, rest, shell, i, around, lenses, count, settings, edge, most, scratch):
    """One pass of dents over element i's contacts, in order: its lenses, the other neighbours' rest surfaces
    it came near, the walls. Returns how many dents it made and how many contacts' budgets are spent."""
    pairs, maps, fields = around.pairs, around.maps, around.fields
    found, cap, spent = scratch.found, scratch.cap, scratch.spent
    made = 0
    capped = 0
    n = np.empty(3)
    margin = settings.clearance
    for c in range(count):
        j = pairs.index[lenses.pair[c]]
        m = _plane_cap(position, shell, j, maps, fields, margin, lenses.normal[c], lenses.plane[c], found, cap)
        if m > 0:
            made += 1
            capped += _dent_spent(position, rest, shell, cap, m, lenses.normal[c], settings, edge, most, spent, c)
    for q in range(pairs.start[i], pairs.start[i + 1]):
        if _is_lens(lenses, count, q):
            continue
        cx = near_surface(position, shell, pairs.index[q], maps, fields, margin, found, 0)
        m = _surface_cap(found, cx, margin, n, cap) if cx > 0 else 0
        if m > 0:
            made += 1
            slot = count + q - pairs.start[i]
            capped += _dent_spent(position, rest, shell, cap, m, n, settings, edge, most, spent, slot)
    cx = _wall_found(position, shell, around.walls, margin, found)
    m = _surface_cap(found, cx, margin, n, cap) if cx > 0 else 0
    if m > 0:
        made += 1
        slot = spent.shape[0] - 1
        capped += _dent_spent(position, rest, shell, cap, m, n, settings, edge, most, spent, slot)
    return made, capped


@njit(cache=True, error_model="numpy")
def _dent_all(position, rest, shell, i, around, lenses, count, settings, edge, most, scratch):
    """Dent passes until none is needed (a dent along one contact's axis can push a vertex past another's plane)
    or every needed one's budget is spent, at most ``DENT_PASSES``. Returns the contacts whose budget ran out and
    how many dents were made."""
    capped = 0
    dents = 0
    for _ in range(DENT_PASSES):
        made, capped = _dent_pass(position, rest, shell, i, around, lenses, count, settings, edge, most, scratch)
        dents += made - capped
        if made == capped:
            break
    return capped, dents


@njit(cache=True, error_model="numpy")
def _deform_one(i, vertices, around, shells, rings, settings, budgets, push, figures):
    """Element i's dents and bulges (module docstring) into its rows of ``push`` and ``figures``."""
    pairs, maps, fields = around.pairs, around.maps, around.fields
    world, vstart = vertices.world, vertices.start
    first, last = vstart[i], vstart[i + 1]
    nv = last - first
    rest = world[first:last]
    shell = vertices.shell[first:last]
    s = maps.shape[i]
    faces = shells.faces[shells.start[s] : shells.start[s + 1]]
    most = 0  # the scratch holds any element's vertices (found in a neighbour are the neighbour's own rows)
    for q in range(pairs.start[i], pairs.start[i + 1]):
        j = pairs.index[q]
        most = max(most, vstart[j + 1] - vstart[j])
    most = max(most, nv)
    found = InsideVertices(np.empty(most, np.int64), np.empty(most), np.empty((most, 3)))
    other = InsideVertices(np.empty(most, np.int64), np.empty(most), np.empty((most, 3)))
    cap = Cap(np.empty(most, np.int64), np.empty(most), np.empty(nv, np.bool_))
    rows = pairs.start[i + 1] - pairs.start[i] + 1
    lenses = Lenses(np.empty(rows, np.int64), np.empty((rows, 3)), np.empty(rows))
    figures.rest[i] = _volume(rest, faces)
    count = _lenses(vertices, i, pairs, maps, fields, settings, budgets.give, (found, other), lenses)
    gaps = Lenses(np.empty(rows, np.int64), np.empty((rows, 3)), np.empty(rows))
    gap_count = _gap_planes(rest, shell, i, around, lenses, count, settings, found, gaps)
    held = (np.empty((rows, nv)), np.empty((rows, nv)))
    held[0][:] = -1.0
    held[1][:] = -1.0
    if settings.near:
        _held(rest, shell, around, lenses, count, settings, found, held[0])
        _held(rest, shell, around, gaps, gap_count, settings, found, held[1])
    position = rest.copy()
    outward = np.empty((nv, 3))
    limit = np.empty(nv)
    scratch = Scratch(found, cap, np.zeros(count + rows))
    for r in range(settings.rounds):
        figures.capped[i], dents = _dent_all(
            position, rest, shell, i, around, lenses, count, settings, budgets.edge[i], budgets.cap[i], scratch
        )
        volume = _volume(position, faces)
        if r == 0:
            figures.dented[i] = volume
        if r == settings.rounds - 1 or (dents == 0 and volume >= figures.rest[i] * (1.0 - VOLUME_TOLERANCE)):
            break  # the last round, or nothing left to dent or to give back
        if volume >= figures.rest[i] * (1.0 - VOLUME_TOLERANCE):
            continue
        _outward(position, maps.lin_inv[i], maps.t[i], shell, outward)
        _bulge_limit(position, shell, around.walls, (lenses, gaps), (count, gap_count), held, settings, limit)
        figures.bulge[i] = bulge(position, shell, faces, outward, limit, figures.rest[i], settings.bulge)
    adjacent = shells.pairs[shells.pair_start[s] : shells.pair_start[s + 1]]
    figures.folded[i] = _unfold(rest, position, faces, adjacent, rings, rings.row[s])
    figures.final[i] = _volume(position, faces)
    for k in range(nv):
        for d in range(3):
            push[first + k, d] = position[k, d] - rest[k, d]


@njit(cache=True, error_model="numpy", nogil=True)
def deform_elements(vertices, around, shells, rings, settings, budgets, order, push, figures):
    """Per vertex of each element of ``order`` (rows of ``around.pairs``): its move, the dents and bulges of the
    module docstring, into its rows of ``push`` and ``figures``. Each element reads the others' rest meshes and
    writes only its own rows, so the elements may run in any order and on any thread (``_deform_all``) with the
    same bits. Releases the GIL."""
    for i in order:
        _deform_one(i, vertices, around, shells, rings, settings, budgets, push, figures)


# elements per call of ``deform_elements`` on a thread: small enough that the threads finish together (an element
# costs from 0.1 to 30 ms), large enough that unboxing the arguments (≈ 0.1 ms) does not count
CHUNK = 32


def _deform_all(vertices, around, shells, rings, settings, budgets, todo):
    """``deform_elements`` over the elements marked in ``todo``, in chunks on numba's thread count of Python threads
    (the kernel releases the GIL; one compilation, where a numba parallel loop compiles its body twice: 79 CPU s).
    The others' rows stay 0. Returns the moves and the ``Figures``."""
    own = around.pairs.start.shape[0] - 1
    push = np.zeros((vertices.start[own], 3))
    figures = Figures(
        np.zeros(own), np.zeros(own), np.zeros(own), np.zeros(own, np.int64), np.zeros(own, np.int64), np.zeros(own)
    )
    order = np.flatnonzero(todo).astype(np.int64)
    chunks = [order[k : k + CHUNK] for k in range(0, len(order), CHUNK)]
    threads = min(get_num_threads(), len(chunks))
    if threads <= 1:
        deform_elements(vertices, around, shells, rings, settings, budgets, order, push, figures)
        return push, figures
    with ThreadPoolExecutor(threads) as pool:
        for _ in pool.map(
            lambda chunk: deform_elements(vertices, around, shells, rings, settings, budgets, chunk, push, figures),
            chunks,
        ):
            pass
    return push, figures


def _with_neighbours(marked: np.ndarray, start: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``marked`` and every element of the aggregate listed as a neighbour of a marked one."""
    out = marked.copy()
    for i in np.flatnonzero(marked):
        near = index[start[i] : start[i + 1]]
        out[near[near < len(marked)]] = True
    return out


def _mean_edge(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Mean edge length of a mesh (a dent's patch is never narrower)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return float(np.linalg.norm(vertices[edges[:, 0]] - vertices[edges[:, 1]], axis=1).mean())


def _ratio(volume, rest):
    """Each element's volume over its rest volume (1 where the rest volume is 0)."""
    return np.where(rest != 0.0, volume / np.where(rest != 0.0, rest, 1.0), 1.0)


def deform(aggregate, neighbours=(), free_space=None, settings: dict | None = None, contacts: bool = True):
    """The moves of ``aggregate``'s elements dented against each other and the ``neighbours``' elements (not moved
    here: deform them with this aggregate as their neighbour) when ``contacts``, and, with ``free_space`` (φ,
    origin, pitch of the colliders' free space), against the walls. ``settings``: clearance (element lengths,
    the median), share, cap and bulge (each element's thickness), slope, rounds. Returns the dents and the
    figures (dented elements, moved vertices, dent depth, volume error, folded faces)."""
    import trimesh

    given = {"clearance": 0.005, "share": 0.5, "cap": 0.5, "slope": 0.35, "bulge": 0.15, "rounds": 8, "near": False}
    given |= settings or {}
    fields: dict[int, int] = {}
    shells: list = []
    faces_of: list = []
    rings_of: list = []

    def fields_of(mesh) -> int:
        key = id(mesh)
        if key not in fields:
            fields[key] = len(shells)
            used = outer_vertices(mesh)
            faces = np.asarray(mesh.faces if mesh.parts is None else mesh.faces[mesh.parts == 0], np.int64)
            remap = np.cumsum(used) - 1
            shells.append((mesh.vertices[used], remap[faces]))
            faces_of.append(faces)
            rings_of.append((len(mesh.vertices), faces))
        return fields[key]

    elements = _gather([aggregate, *neighbours], fields_of)
    own = len(aggregate.placement)
    world = np.concatenate(elements.world) if elements.world else np.zeros((0, 3))
    shell = np.concatenate(elements.shell) if elements.shell else np.zeros(0, bool)
    vstart = np.concatenate([[0], np.cumsum([len(w) for w in elements.world])]).astype(np.int64)
    length = float(np.median(np.ptp(np.stack([elements.lo, elements.hi]), axis=0).max(axis=1))) if own else 1.0
    thickness = float(np.median(elements.thickness[:own])) if own else 1.0
    gap = given["clearance"] * length
    most_bulge = given["bulge"] * thickness
    reach = most_bulge / ROOM_SHARE + gap  # how far a bulge looks for its room
    nstart, near = _neighbour_lists(elements, own if contacts else 0, reach)
    if not contacts:
        nstart = np.zeros(own + 1, np.int64)
    pad = np.full(3, reach)
    maps = ElementMaps(
        elements.shape, elements.lin_inv, elements.rot, elements.bend, elements.t, elements.lo - pad, elements.hi + pad
    )
    if free_space is None:
        walls = Walls(np.full((2, 2, 2), np.inf), np.zeros(3), 1.0, 0.0)
    else:
        cphi, corigin, cpitch = free_space
        wall_reach = 0.5 * float(np.min(elements.thickness[:own])) if own else 0.0
        walls = Walls(
            np.ascontiguousarray(cphi, np.float64), np.asarray(corigin, np.float64), float(cpitch), wall_reach
        )
    solve = DeformSettings(
        gap, float(given["share"]), float(given["slope"]), most_bulge, int(given["rounds"]), bool(given["near"])
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
    edge_of = [_mean_edge(*shells[s]) for s in range(len(shells))]  # per mesh: an element moves it near rigidly
    edges = np.array([edge_of[s] for s in elements.shape[:own]], np.float64)
    vertices = ElementVertices(world, vstart, shell)
    around = Surroundings(ContactPairs(nstart, near), maps, shape_fields(shells), walls)
    rings = vertex_rings(rings_of)
    budgets = Budgets(given["cap"] * elements.thickness[:own], edges, np.ones(own))
    todo = np.ones(own, bool)
    push, figures = _deform_all(vertices, around, shell_faces, rings, solve, budgets, todo)
    for _ in range(STARVED_PASSES):
        starved = _ratio(figures.final, figures.rest) < 1.0 - STARVED  # short of volume, not over it
        if not starved.any():
            break
        budgets.give[starved] *= STARVED_GIVE
        todo = _with_neighbours(starved, nstart, near)
        again, redone = _deform_all(vertices, around, shell_faces, rings, solve, budgets, todo)
        rows = np.repeat(todo, np.diff(vstart[: own + 1]))
        push[rows] = again[rows]
        figures = Figures(*(np.where(todo, b, a) for a, b in zip(figures, redone)))
    moved = np.flatnonzero(np.any(push != 0.0, axis=1))
    owner = np.searchsorted(vstart, moved, side="right") - 1
    moves = push[moved]
    dents = Dents(owner.astype(np.int64), (moved - vstart[owner]).astype(np.int64), moves)
    depth = np.linalg.norm(moves, axis=1) / length
    dented = figures.dented != figures.rest
    error = np.abs(_ratio(figures.final, figures.rest) - 1.0)
    lost = np.abs(_ratio(figures.dented, figures.rest) - 1.0)
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
        "capped_dents": int(figures.capped.sum()),
        "bulge_max": float(figures.bulge.max() / thickness) if own else 0.0,
    }
    return dents, table
