"""Closed target solids for aggregates — SPEC §2 (S fig. 10 onigiri, G fig. 4.3.1 lying cylinder, G bowls).

Pure functions returning ``trimesh.Trimesh`` (closed, outward normals). Solids of revolution
(bowl, its cavity) are built with manifold3d's ``revolve`` so they are valid manifolds by
construction; the onigiri is an icosphere mapped radially onto a star-shaped gauge surface, so it
is closed and evenly meshed without marching cubes.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import trimesh


def sphere(radius: float, subdivisions: int = 4) -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)


def box(extents: tuple[float, float, float]) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=extents)


def lying_cylinder(radius: float, length: float, sections: int = 48) -> trimesh.Trimesh:
    """A cylinder with its axis along x, lying on the table (G fig. 4.3.1)."""
    mesh = trimesh.creation.cylinder(radius=radius, height=length, sections=sections)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    return mesh


def _rounded_triangle_radius(roundness: float, samples: int = 720):
    """Boundary radius R(θ) of a unit-circumradius triangle whose corners are rounded (2-D Minkowski sum).

    Returns a function θ → R(θ) with max R = 1 (the corners' tips). Exact on the straight edges: the ray's
    distance to the hull's nearest supporting line (interpolating R linearly in θ between the hull's vertices,
    bows each straight edge out into an arc: the "triangle" becomes a near disc, 94 × 94 mm for a 47.3 mm
    circumradius at roundness 0.01, and reads as a dome from the front).
    """
    from scipy.spatial import ConvexHull

    corner_angles = np.pi / 2 + np.array([0.0, 2.0, 4.0]) * np.pi / 3
    inner = (1.0 - roundness) * np.stack([np.cos(corner_angles), np.sin(corner_angles)], axis=1)
    rho = roundness * 0.5  # inradius of the unit triangle is 1/2; rounding radius in those units
    circle = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    disc = rho * np.stack([np.cos(circle), np.sin(circle)], axis=1)
    points = (inner[:, None, :] + disc[None, :, :]).reshape(-1, 2)
    hull = ConvexHull(points)
    normals, offsets = hull.equations[:, :2], -hull.equations[:, 2]  # inside: normal · p <= offset (> 0)
    tip = np.linalg.norm(points[hull.vertices], axis=1).max()

    def radius(angles):
        directions = np.stack([np.cos(angles), np.sin(angles)], axis=-1)
        return 1.0 / ((directions @ normals.T) / offsets).max(axis=-1) / tip

    return radius


def onigiri(
    circumradius: float, thickness: float, roundness: float, bulge: float, subdivisions: int = 5
) -> trimesh.Trimesh:
    """A rounded-triangle rice ball (S fig. 10a) standing upright: triangle in the x–z plane, depth along y.

    The gauge ``G(p) = (q(p_xz)^m + |p_y / h|^m)^(1/m)`` (q: rounded-triangle gauge, h: half the
    thickness, m = 2 / bulge) is homogeneous of degree 1, so every icosphere direction u maps to
    ``u / G(u)`` on the surface. Scaled so the circumscribed radius about the centroid is exact.
    """
    boundary = _rounded_triangle_radius(roundness)
    ball = trimesh.creation.icosphere(subdivisions=subdivisions)
    u = np.asarray(ball.vertices)
    planar = np.hypot(u[:, 0], u[:, 2])
    q = planar / boundary(np.arctan2(u[:, 2], u[:, 0]))
    exponent = 2.0 / bulge
    half = 0.5 * thickness / circumradius
    gauge = (q**exponent + np.abs(u[:, 1] / half) ** exponent) ** (1.0 / exponent)
    vertices = u / gauge[:, None]
    vertices -= vertices.mean(axis=0)
    vertices *= circumradius / np.linalg.norm(vertices, axis=1).max()
    return trimesh.Trimesh(vertices, np.asarray(ball.faces), process=False)


def _revolve(profile: np.ndarray, segments: int) -> trimesh.Trimesh:
    """Solid of revolution about z of a closed (r, z) profile polygon (counter-clockwise)."""
    import manifold3d

    section = manifold3d.CrossSection([profile.astype(np.float64)])
    solid = manifold3d.Manifold.revolve(section, circular_segments=segments)
    out = solid.to_mesh()
    return trimesh.Trimesh(np.asarray(out.vert_properties)[:, :3], np.asarray(out.tri_verts), process=True)


def _quarter_ellipse(a: float, b: float, z_from: float, z_to: float, n: int) -> np.ndarray:
    """Points (r, z) on the ellipse (r/a)² + (z/b)² = 1 with z ≤ 0, from height z_from to z_to."""
    z = np.linspace(z_from, z_to, n)
    r = a * np.sqrt(np.clip(1.0 - (z / b) ** 2, 0.0, None))
    return np.stack([r, z], axis=1)


FOOT_HEIGHT = 0.1  # the foot ring's height, a share of the bowl's (8.5 mm on the 85 mm donburi: a 63 mm ring)
FOOT_WIDTH = 0.06  # the ring's width, a share of the bowl's height (5 mm)


def bowl(
    radius: float, depth: float, wall: float, fill: float, mound: float, segments: int = 96, rings: int = 32
) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A chawan/donburi and the rice region in it: ``(region, container)``.

    The cavity is the lower half of an ellipsoid (rim radius ``radius``, depth ``depth``, rim at
    z = 0); the region is the cavity filled to ``fill``·depth from the bottom plus a half-ellipsoid
    mound of height ``mound`` over the fill plane. The container wall has thickness ``wall``; the bowl stands on a
    foot ring (kōdai) ``FOOT_HEIGHT`` of its height tall and ``FOOT_WIDTH`` of it wide, its underside inside the
    ring raised half the wall, as a thrown and turned bowl's is; the ring's outer radius is the outer wall's there.
    """
    fill_z = -depth + fill * depth
    fill_r = radius * np.sqrt(max(1.0 - (fill_z / depth) ** 2, 0.0))
    cavity = _quarter_ellipse(radius, depth, -depth, fill_z, rings)
    phi = np.linspace(0.0, np.pi / 2, rings)[1:]
    cap = np.stack([fill_r * np.cos(phi), fill_z + mound * np.sin(phi)], axis=1)
    top_z = fill_z + mound
    region_profile = _dedupe(np.vstack([cavity, cap, [[0.0, top_z], [0.0, -depth]]]))
    region = _revolve(region_profile, segments)

    inner = _quarter_ellipse(radius, depth, 0.0, -depth, rings)
    bottom = -(depth + wall)
    outer = _quarter_ellipse(radius + wall, depth + wall, bottom + FOOT_HEIGHT * (depth + wall), 0.0, rings)
    foot_r = float(outer[0, 0])  # the foot ring's outer radius: where the outer wall meets its top
    ring_in = foot_r - min(FOOT_WIDTH * (depth + wall), 0.5 * foot_r)
    recess = 0.5 * wall  # the underside inside the ring, raised half the wall: the bowl stands on its ring
    foot = np.array([[0.0, bottom + recess], [ring_in, bottom + recess], [ring_in, bottom], [foot_r, bottom]])
    wall_profile = _dedupe(np.vstack([foot, outer, inner]))
    container = _revolve(wall_profile, segments)
    return region, container


def plate(
    radius: float, rim: float, thickness: float, well: float, segments: int = 96, rings: int = 16
) -> trimesh.Trimesh:
    """A round plate: a flat well (radius ``well``·``radius``, its top at z = 0, where food rests) whose rim
    rises to ``rim`` above the well at the outer ``radius`` along z = rim·t² (t from the well's edge to the rim:
    tangent to the well, steepest at the lip), ``thickness`` thick (measured along z). A solid of revolution,
    closed by construction."""
    inner = well * radius
    t = np.linspace(0.0, 1.0, rings)
    r = inner + (radius - inner) * t
    top = np.stack([r, rim * t**2], axis=1)
    under = top - [0.0, thickness]
    profile = np.vstack([[[0.0, -thickness]], under, top[::-1], [[0.0, 0.0]]])  # counter-clockwise in (r, z)
    return _revolve(_dedupe(profile), segments)


def _dedupe(profile: np.ndarray) -> np.ndarray:
    keep = np.ones(len(profile), bool)
    keep[1:] = np.linalg.norm(np.diff(profile, axis=0), axis=1) > 1e-9
    profile = profile[keep]
    if np.linalg.norm(profile[0] - profile[-1]) < 1e-9:
        profile = profile[:-1]
    return profile


def rounded_block(extents: tuple[float, float, float], exponent: float, subdivisions: int = 4) -> trimesh.Trimesh:
    """A rounded block (a nigiri's rice, a sushi mould's fill): the superellipsoid
    ``|x/a|^m + |y/b|^m + |z/c|^m = 1`` with half extents (a, b, c), ``m = exponent`` (2 an ellipsoid, larger
    towards a box). An icosphere mapped radially by the gauge, as ``onigiri``: closed and evenly meshed."""
    ball = trimesh.creation.icosphere(subdivisions=subdivisions)
    u = np.asarray(ball.vertices)
    half = 0.5 * np.asarray(extents, float)
    gauge = (np.abs(u / half) ** exponent).sum(axis=1) ** (1.0 / exponent)
    return trimesh.Trimesh(u / gauge[:, None], np.asarray(ball.faces), process=False)


def tray(extents: tuple[float, float, float], wall: float) -> trimesh.Trimesh:
    """An open-top box mould around a region of ``extents`` centred at the origin (inside = the region's
    bounding box; its rim at the region's top), as a closed solid (manifold3d difference)."""
    import manifold3d

    a, b, c = (float(e) for e in extents)
    outer = manifold3d.Manifold.cube([a + 2 * wall, b + 2 * wall, c + wall], center=True).translate([0, 0, -wall / 2])
    inner = manifold3d.Manifold.cube([a, b, c + wall], center=True).translate([0, 0, wall / 2])
    out = (outer - inner).to_mesh()
    return trimesh.Trimesh(np.asarray(out.vert_properties)[:, :3], np.asarray(out.tri_verts), process=True)


def first_hits(origins: np.ndarray, directions: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(distance, face) of each ray's nearest crossing of a triangle (Möller–Trumbore); inf and −1 for a miss."""
    a, edge1, edge2 = triangles[:, 0], triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    distance = np.full(len(origins), np.inf)
    face = np.full(len(origins), -1)
    for start in range(0, len(origins), 64):
        o, d = origins[start : start + 64, None, :], directions[start : start + 64, None, :]
        p = np.cross(d, edge2)
        det = np.einsum("rfk,fk->rf", p, edge1)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / det
            s = o - a
            u = np.einsum("rfk,rfk->rf", s, p) * inv
            q = np.cross(s, edge1)
            v = np.einsum("rfk,rfk->rf", d, q) * inv
            t = np.einsum("rfk,fk->rf", q, edge2) * inv
            hit = (np.abs(det) > 1e-12) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9)
        t = np.where(hit, t, np.inf)
        nearest = np.argmin(t, axis=1)
        distance[start : start + 64] = t[np.arange(len(t)), nearest]
        face[start : start + 64] = np.where(np.isfinite(distance[start : start + 64]), nearest, -1)
    return distance, face


class SheetSurface(NamedTuple):
    """What a wrapped sheet has besides its shape (``wrap_band``): ribs, crinkles and thickness, in mm."""

    ribs: float = 0.0
    rib_period: float = 1.6
    crinkle: float = 0.0
    thickness: float = 0.0
    seed: int = 0


PLAIN_SHEET = SheetSurface()  # no ribs, no crinkles, no thickness


def wrap_band(
    vertices: np.ndarray,
    faces: np.ndarray,
    width: float,
    height: float,
    gap: float,
    columns: int,
    rows: int,
    drape: np.ndarray | None = None,
    reach: float = 2.0,
    surface: SheetSurface = PLAIN_SHEET,
) -> tuple[np.ndarray, np.ndarray]:
    """A sheet folded round the bottom of a closed shape (faces along ±y): for each of ``columns + 1`` cuts across
    x (``width`` wide, centred), rays in the y–z plane from the point at ``height`` above the shape's lowest point
    sweep the half-turn below it (horizontal towards −y, down, horizontal towards +y); their first hits, moved
    ``gap`` out along the hit face's normal, are the sheet's vertices. Its edges: the cuts at ±width/2 and the
    plane at ``height``. Raises when the band would leave the shape (a ray from outside it, or a miss).

    With ``drape`` (points: the settled grains' vertices) the sheet lies on those points instead of the shape:
    ``gap`` beyond the farthest of them along each ray (``draped_distances``), never lower than the shape's lowest
    point less ``gap`` (it stays on the plate the shape was set on).

    ``ribs`` > 0: the sheet's fine ribbing (a nori sheet keeps the lines of the mat it dried on), ridges across the
    band every ``rib_period`` mm of its length, raised up to ``ribs`` mm outwards along the rays (never inwards:
    what the sheet covers stays covered).

    ``crinkle`` > 0: the dry sheet's crinkles and fibres (``crinkle_lift``), up to ``crinkle`` mm outwards along
    the rays, drawn from ``seed``. ``thickness`` > 0: the sheet is a closed thin solid, its inner face
    ``thickness`` inside the outer one along the rays and its four cut edges closed, so it shows an edge and the
    rice under it stays under it (the inner face is ``gap`` − ``thickness`` off what it lies on). These four and
    ``seed`` come in ``surface``."""
    ribs, rib_period, crinkle, thickness, seed = surface
    vertices, faces = np.asarray(vertices, np.float64), np.asarray(faces, np.int64)
    triangles = vertices[faces]
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    middle = 0.5 * (lo + hi)
    if not height < hi[2] - lo[2]:
        raise ValueError(f"height: {height:g} mm reaches over the shape ({hi[2] - lo[2]:g} mm tall)")
    xs = middle[0] + np.linspace(-0.5 * width, 0.5 * width, columns + 1)
    angles = np.linspace(-np.pi, 0.0, rows + 1)  # from −y round under the shape to +y
    near = (triangles[:, :, 0].max(axis=1) >= xs[0]) & (triangles[:, :, 0].min(axis=1) <= xs[-1])
    near &= triangles[:, :, 2].min(axis=1) <= lo[2] + height  # only faces the band can meet
    triangles, normals = triangles[near], normals[near]
    x, angle = (g.ravel() for g in np.meshgrid(xs, angles, indexing="ij"))  # column-major: rows vary fastest
    origins = np.stack([x, np.full_like(x, middle[1]), np.full_like(x, lo[2] + height)], axis=1)
    directions = np.stack([np.zeros_like(x), np.cos(angle), np.sin(angle)], axis=1)
    distance, face = np.full(len(x), np.inf), np.full(len(x), -1)
    lo_x, hi_x = triangles[:, :, 0].min(axis=1), triangles[:, :, 0].max(axis=1)
    for c, cut in enumerate(xs):  # a cut's rays lie in its plane: only the faces that cross it can meet them
        rays = slice(c * (rows + 1), (c + 1) * (rows + 1))
        crossing = np.flatnonzero((lo_x <= cut) & (hi_x >= cut))
        if not len(crossing):  # a cut beside the shape: its rays miss (refused below)
            continue
        d, f = first_hits(origins[rays], directions[rays], triangles[crossing])
        distance[rays], face[rays] = d, np.where(f >= 0, crossing[np.maximum(f, 0)], -1)
    if (face < 0).any() or (np.einsum("ij,ij->i", normals[face], directions) <= 0).any():
        raise ValueError(
            f"width: a band {width:g} mm wide and {height:g} mm high leaves the shape "
            f"({hi[0] - lo[0]:g} mm wide): make it narrower or lower"
        )
    if drape is None:
        points = origins + distance[:, None] * directions + gap * normals[face]
    else:
        along = draped_distances(
            np.asarray(drape, np.float64), xs, angles, (middle[1], lo[2] + height), reach, distance
        ).ravel()
        floor = lo[2] - gap  # the sheet under the shape stays above what the shape stands on
        down = directions[:, 2] < -1e-9
        along[down] = np.minimum(along[down] + gap, (lo[2] + height - floor) / -directions[down, 2])
        along[~down] += gap
        points = origins + along[:, None] * directions
    floor = lo[2] - gap  # under the shape no lower than its lowest point less the gap (the plate)
    if ribs > 0:
        length = _along(points, columns, rows).ravel()
        lift = 0.5 * ribs * (1.0 - np.cos(2.0 * np.pi * length / rib_period))
        points = _lifted(points, directions, lift, floor)
    if crinkle > 0:
        along = _along(points, columns, rows)
        across = np.broadcast_to((xs - xs[0])[:, None], along.shape)
        points = _lifted(points, directions, crinkle * crinkle_lift(across.ravel(), along.ravel(), seed), floor)
    k = np.arange((columns + 1) * (rows + 1)).reshape(columns + 1, rows + 1)
    a, b, c, d = k[:-1, :-1], k[1:, :-1], k[1:, 1:], k[:-1, 1:]
    quads = np.stack([a, b, c, d], axis=-1).reshape(-1, 4)
    triangles_out = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    outward = np.cross(
        points[triangles_out[:, 1]] - points[triangles_out[:, 0]],
        points[triangles_out[:, 2]] - points[triangles_out[:, 0]],
    )
    centre_normal = normals[face][triangles_out].sum(axis=1)
    if np.einsum("ij,ij->", outward, centre_normal) < 0:
        triangles_out = triangles_out[:, ::-1]
    if thickness > 0:
        return solidify(points, triangles_out, directions, k, thickness)
    return points, triangles_out


def _along(points: np.ndarray, columns: int, rows: int) -> np.ndarray:
    """(columns + 1, rows + 1): each point's distance along its cut of the band, from the cut's first point (mm)."""
    grid = points.reshape(columns + 1, rows + 1, 3)
    length = np.linalg.norm(np.diff(grid, axis=1), axis=2).cumsum(axis=1)
    return np.concatenate([np.zeros((columns + 1, 1)), length], axis=1)


def _lifted(points: np.ndarray, directions: np.ndarray, lift: np.ndarray, floor: float) -> np.ndarray:
    """``points`` moved outwards along their rays by ``lift``, those on downward rays no lower than ``floor``."""
    down = directions[:, 2] < -1e-9
    room = np.maximum(points[down, 2] - floor, 0.0) / -directions[down, 2]
    lift = lift.copy()
    lift[down] = np.minimum(lift[down], room)
    return points + lift[:, None] * directions


def crinkle_lift(across: np.ndarray, along: np.ndarray, seed: int) -> np.ndarray:
    """A nori sheet's relief in [0, 1] at points (mm across and along the band): its crinkles, the waves a dried
    sheet takes as it lies on moist rice (wavelengths 4–12 mm, two thirds of the relief), and its fibres, the
    torn laver pressed into it (0.5–1.5 mm, mostly along the mat's lines, a third). Each a sum of plane waves
    with random directions and phases from ``seed`` (the same seed, the same sheet), rescaled to [0, 1]."""
    rng = np.random.default_rng(seed)
    total = np.zeros_like(across, dtype=np.float64)
    for count, (short, long), weight, spread in ((12, (4.0, 12.0), 2.0, np.pi), (24, (0.5, 1.5), 1.0, 0.6)):
        heading = rng.uniform(-spread, spread, count) + (0.0 if spread >= np.pi else 0.5 * np.pi)
        wavelength = rng.uniform(short, long, count)
        phase = rng.uniform(0.0, 2.0 * np.pi, count)
        k = 2.0 * np.pi / wavelength
        waves = np.cos(np.outer(across, k * np.cos(heading)) + np.outer(along, k * np.sin(heading)) + phase)
        total += weight * waves.sum(axis=1) / np.sqrt(count)
    low, high = total.min(), total.max()
    return (total - low) / max(high - low, 1e-12)


def solidify(points: np.ndarray, faces: np.ndarray, directions: np.ndarray, grid: np.ndarray, thickness: float):
    """The open sheet ``points``/``faces`` (a (columns + 1) × (rows + 1) ``grid`` of vertex indices, outward
    ``faces``) as a closed thin solid: an inner copy ``thickness`` back along ``directions`` with its faces turned
    inwards, and a strip of faces along each of the grid's four borders joining the two, wound against the outer
    face beside it (each edge crossed once each way: a closed, consistently oriented surface)."""
    n = len(points)
    vertices = np.concatenate([points, points - thickness * directions])
    border = np.concatenate([grid[0, :], grid[1:, -1], grid[-1, -2::-1], grid[-2:0:-1, 0]])  # a loop round the sheet
    a, b = border, np.roll(border, -1)
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    forward = np.isin(a * n + b, directed[:, 0] * n + directed[:, 1])
    a, b = np.where(forward, b, a), np.where(forward, a, b)  # each border edge as the outer faces do not cross it
    strip = np.concatenate([np.stack([a, b, b + n], 1), np.stack([a, b + n, a + n], 1)])
    return vertices, np.concatenate([faces, faces[:, ::-1] + n, strip])


def draped_distances(
    points: np.ndarray,
    xs: np.ndarray,
    angles: np.ndarray,
    centre: tuple[float, float],
    reach: float,
    fallback: np.ndarray,
) -> np.ndarray:
    """Distances (columns, rows) along the band's rays (cut x ``xs``, angle ``angles`` in the y–z plane from
    ``centre``) at which a stiff sheet rests on ``points``: the farthest point within ``reach`` (mm) of each ray,
    spread over ``reach`` so the sheet spans the grains' tops instead of dipping between them. Rays no point lies
    near take their neighbours' along the band (``fallback``, the shape's own distance, where a whole cut is
    empty). Binned on the rays' grid — a max filter, not a search per ray."""
    from scipy import ndimage

    dx = xs[1] - xs[0] if len(xs) > 1 else 1.0
    da = angles[1] - angles[0]
    rel_y, rel_z = points[:, 1] - centre[0], points[:, 2] - centre[1]
    radius = np.hypot(rel_y, rel_z)
    angle = np.arctan2(rel_z, rel_y)
    angle = np.where(angle > 0.5 * np.pi, angle - 2.0 * np.pi, angle)  # above −y's horizontal: beside the −π end
    column = np.rint((points[:, 0] - xs[0]) / dx).astype(np.int64)
    row = np.rint((angle - angles[0]) / da).astype(np.int64)
    keep = (column >= 0) & (column < len(xs)) & (row >= 0) & (row < len(angles))
    farthest = np.full((len(xs), len(angles)), -np.inf)
    np.maximum.at(farthest, (column[keep], row[keep]), radius[keep])
    typical = np.median(radius[keep]) if keep.any() else 1.0
    size = (2 * int(np.ceil(reach / dx)) + 1, 2 * int(np.ceil(reach / max(typical * da, 1e-9))) + 1)
    spread = ndimage.maximum_filter(farthest, size=size, mode="nearest")
    fallback = np.asarray(fallback, np.float64).reshape(len(xs), len(angles))
    out = np.empty_like(spread)
    index = np.arange(len(angles))
    for c in range(len(xs)):
        known = np.isfinite(spread[c])
        out[c] = np.interp(index, index[known], spread[c, known]) if known.any() else fallback[c]
    smooth = ndimage.gaussian_filter(out, sigma=0.5 * (np.array(size) - 1) / 2, mode="nearest")
    return np.maximum(smooth, np.where(np.isfinite(farthest), farthest, -np.inf))
