"""Closed target solids for aggregates — SPEC §2 (S fig. 10 onigiri, G fig. 4.3.1 lying cylinder, G bowls).

Pure functions returning ``trimesh.Trimesh`` (closed, outward normals). Solids of revolution
(bowl, its cavity) are built with manifold3d's ``revolve`` so they are valid manifolds by
construction; the onigiri is an icosphere mapped radially onto a star-shaped gauge surface, so it
is closed and evenly meshed without marching cubes.
"""

from __future__ import annotations

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

    Returns a function θ → R(θ) with max R = 1 (the corners' tips).
    """
    corner_angles = np.pi / 2 + np.array([0.0, 2.0, 4.0]) * np.pi / 3
    inner = (1.0 - roundness) * np.stack([np.cos(corner_angles), np.sin(corner_angles)], axis=1)
    rho = roundness * 0.5  # inradius of the unit triangle is 1/2; rounding radius in those units
    circle = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    disc = rho * np.stack([np.cos(circle), np.sin(circle)], axis=1)
    points = (inner[:, None, :] + disc[None, :, :]).reshape(-1, 2)
    from scipy.spatial import ConvexHull

    hull = points[ConvexHull(points).vertices]
    theta = np.arctan2(hull[:, 1], hull[:, 0])
    radius = np.linalg.norm(hull, axis=1)
    order = np.argsort(theta)
    theta, radius = theta[order], radius[order]
    # Chord interpolation in polar coordinates: fine at 720 samples per corner circle.
    radius = radius / radius.max()
    return lambda angles: np.interp(angles, theta, radius, period=2 * np.pi)


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


def bowl(
    radius: float, depth: float, wall: float, fill: float, mound: float, segments: int = 96, rings: int = 32
) -> tuple[trimesh.Trimesh, trimesh.Trimesh]:
    """A chawan/donburi and the rice region in it: ``(region, container)``.

    The cavity is the lower half of an ellipsoid (rim radius ``radius``, depth ``depth``, rim at
    z = 0); the region is the cavity filled to ``fill``·depth from the bottom plus a half-ellipsoid
    mound of height ``mound`` over the fill plane. The container wall has thickness ``wall``.
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
    outer = _quarter_ellipse(radius + wall, depth + wall, -(depth + wall), 0.0, rings)
    wall_profile = _dedupe(np.vstack([outer, inner]))
    container = _revolve(wall_profile, segments)
    return region, container


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
