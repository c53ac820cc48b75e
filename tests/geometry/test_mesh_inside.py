"""The one inside test of a closed mesh (``nodes/mesh_inside.py``) as its three users see it — SPEC §1.3, §2.2,
§3: the voxeliser's cells, placement's columns and points, and the collider's φ < 0 region. They must fill
overlapping closed parts as their union and nested shells as solid, and agree exactly on grid points that lie
on the mesh's vertices and edges."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from nodegraph.values import Mesh
from nodes.elements.grain_shapes import icosphere
from nodes.elements.voxel_grid import Grid, mesh_occupancy
from nodes.mesh_inside import inside_columns, inside_points, point_winding
from nodes.simulation.collider import signed_distance_grid


def _side(vertices, faces, points):
    """max over the faces of a convex outward mesh of n·(p − a): < 0 inside, 0 on the surface, > 0 outside
    (exact for small integer coordinates)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    normals = np.cross(b - a, c - a)
    return np.einsum("pfk,fk->pf", points[:, None, :] - a[None], normals).max(axis=1)


def _concat(*parts):
    """Closed parts in one mesh, without a boolean union (what a recipe gets by concatenating meshes)."""
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    return (
        np.vstack([v for v, _ in parts]),
        np.vstack([np.asarray(f, np.int64) + o for (_, f), o in zip(parts, offsets)]),
    )


def _users(vertices, faces, origin, h, shape):
    """Inside of the grid points origin + (i, j, k)·h by the voxeliser, placement's columns and points, and
    the collider's φ on the same grid."""
    origin = np.asarray(origin, float)
    axes = [origin[d] + np.arange(shape[d]) * h for d in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    voxels = mesh_occupancy(Grid(origin, h, shape), vertices, faces)
    columns = inside_columns(vertices, faces, *axes)
    at_points = inside_points(vertices, faces, points).reshape(shape)
    phi, _, _ = signed_distance_grid([Mesh(vertices, faces)], origin, origin + (np.array(shape) - 1) * h, h)
    assert phi.shape == tuple(shape)
    return points, voxels, columns, at_points, phi


def _sphere(radius, centre, rotation):
    vertices, faces = icosphere(3)
    return vertices @ rotation.T * radius + centre, faces


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


@pytest.mark.parametrize("seed", [0, 1])
def test_overlapping_parts_are_filled_as_their_union(seed):
    a = _sphere(1.0, np.zeros(3), _rotation(seed))
    b = _sphere(0.8, np.array([0.9, 0.3, -0.2]), _rotation(seed + 10))
    vertices, faces = _concat(a, b)
    shape = (31, 23, 23)
    points, voxels, columns, at_points, phi = _users(vertices, faces, [-1.375, -1.375, -1.375], 0.125, shape)
    side_a, side_b = _side(*a, points).reshape(shape), _side(*b, points).reshape(shape)
    assert min(np.abs(side_a).min(), np.abs(side_b).min()) > 1e-9  # no grid point on a surface
    union = (side_a < 0) | (side_b < 0)
    assert ((side_a < 0) & (side_b < 0)).sum() > 200  # the shared region parity called outside
    for inside in (voxels, columns, at_points, phi < 0):
        assert (inside == union).all()
    assert (point_winding(vertices, faces, points).reshape(shape)[(side_a < 0) & (side_b < 0)] == 2).all()


@pytest.mark.parametrize("hollow", [False, True])
def test_nested_shells(hollow):
    """An outward shell inside another (ikura yolk in its membrane) is inside; an inward one is a cavity."""
    outer = _sphere(1.0, np.zeros(3), _rotation(3))
    inner = _sphere(0.5, np.array([0.1, 0.0, 0.05]), _rotation(4))
    vertices, faces = _concat(outer, (inner[0], inner[1][:, ::-1]) if hollow else inner)
    shape = (23, 23, 23)
    points, voxels, columns, at_points, phi = _users(vertices, faces, [-1.375, -1.375, -1.375], 0.125, shape)
    in_outer = _side(*outer, points).reshape(shape) < 0
    in_inner = _side(*inner, points).reshape(shape) < 0
    solid = in_outer & ~in_inner if hollow else in_outer
    for inside in (voxels, columns, at_points, phi < 0):
        assert (inside == solid).all()
    assert point_winding(vertices, faces, np.array([[0.1, 0.0, 0.05]]))[0] == (0 if hollow else 2)


@pytest.mark.parametrize("seed", range(4))
def test_users_agree_on_vertices_and_edges(seed):
    """Two overlapping convex hulls with vertices on the grid (A on integers, B on half-integers, grid pitch
    0.5): grid points on vertices, edges and faces of both. The winding number is exact (0 or 1 per part)
    everywhere, the users agree on every grid point, surface points included."""
    rng = np.random.default_rng(seed)
    hull_a = trimesh.convex.convex_hull(rng.integers(-4, 5, (14, 3)).astype(float))
    hull_b = trimesh.convex.convex_hull(rng.integers(-3, 5, (14, 3)) - 0.5)
    a = (np.asarray(hull_a.vertices), np.asarray(hull_a.faces))
    b = (np.asarray(hull_b.vertices), np.asarray(hull_b.faces))
    vertices, faces = _concat(a, b)
    shape = (21, 21, 21)
    points, voxels, columns, at_points, phi = _users(vertices, faces, [-5.0, -5.0, -5.0], 0.5, shape)
    side_a, side_b = _side(*a, points).reshape(shape), _side(*b, points).reshape(shape)
    on_surface = (side_a == 0) | (side_b == 0)
    assert (np.mod(2.0 * vertices, 1.0) == 0).all() and on_surface.sum() > 50  # vertices are grid points
    winding = point_winding(vertices, faces, points).reshape(shape)
    expected = (side_a < 0).astype(int) + (side_b < 0)
    off = ~on_surface
    assert (winding[off] == expected[off]).all()
    ties = (side_a == 0).astype(int) + (side_b == 0)  # a part whose surface holds the point counts 0 or 1
    assert ((winding >= expected) & (winding <= expected + ties)).all()
    assert (voxels == columns).all() and (columns == at_points).all() and (columns == (winding > 0)).all()
    strict_inside = (side_a < 0) | (side_b < 0)
    assert (phi[strict_inside & off] < 0).all() and (np.abs(phi[on_surface]) < 1e-12).all()
    assert (phi[~strict_inside & off] > 0).all()


@pytest.mark.parametrize("seed", range(3))
def test_lines_through_edges_count_each_crossing_once(seed):
    """Vertical lines through points computed on the edges of a generic convex mesh (not exactly on them:
    within an ulp, on either side): winding 0 above the mesh and 0 or 1 inside. The two faces of an edge
    evaluate its edge function with the same bits; evaluated from each face's own corner they disagree on
    ~15 % of these lines."""
    rng = np.random.default_rng(seed)
    hull = trimesh.convex.convex_hull(rng.normal(size=(60, 3)))
    vertices, faces = np.asarray(hull.vertices), np.asarray(hull.faces, np.int64)
    ends = vertices[hull.edges_unique]
    s = rng.random((len(ends), 4, 1))
    xy = (ends[:, None, 0] + s * (ends[:, None, 1] - ends[:, None, 0])).reshape(-1, 3)
    xy = np.vstack([xy, vertices])
    top, middle = vertices[:, 2].max() + 1.0, vertices[:, 2].mean()
    above = point_winding(vertices, faces, np.column_stack([xy[:, :2], np.full(len(xy), top)]))
    within = point_winding(vertices, faces, np.column_stack([xy[:, :2], np.full(len(xy), middle)]))
    assert (above == 0).all() and np.isin(within, [0, 1]).all()
    for p, w in zip(xy[:200], within[:200]):
        column = inside_columns(vertices, faces, p[:1], p[1:2], np.array([middle]))
        assert column[0, 0, 0] == (w > 0)
