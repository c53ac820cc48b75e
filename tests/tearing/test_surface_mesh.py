"""The splittable surface mesh (SPEC §5, U §3.2): construction errors, cuts, pending cracks, caps."""

import numpy as np
import pytest

from nodes.tearing.surface_mesh import SurfaceMesh, cube_surface, fan_caps

TETRA = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])


def _closed(faces):
    """Every directed edge has exactly one reverse partner: a closed, oriented surface."""
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    fwd = {tuple(e) for e in directed}
    return len(fwd) == len(directed) and all((b, a) in fwd for a, b in directed)


@pytest.mark.parametrize("k", [1, 10, 15, 20, 25])
def test_cube_surface_has_u_table_vertex_counts_and_is_closed(k):
    vertices, faces = cube_surface(k, 2.0)
    assert len(vertices) == 6 * k * k + 2  # 602, 1,352, 2,402, 3,752 (U table 4.1)
    assert SurfaceMesh.from_faces(faces, len(vertices)).is_closed()
    import trimesh

    assert trimesh.Trimesh(vertices, faces, process=False).volume == pytest.approx(8.0)  # outward winding


def test_open_or_misoriented_meshes_are_refused():
    with pytest.raises(ValueError, match="not closed"):
        SurfaceMesh.from_faces(TETRA[:3], 4)
    flipped = TETRA.copy()
    flipped[0] = flipped[0, ::-1]
    with pytest.raises(ValueError, match="oriented"):
        SurfaceMesh.from_faces(flipped, 4)
    with pytest.raises(ValueError, match="indices"):
        SurfaceMesh.from_faces(TETRA, 3)
    with pytest.raises(ValueError, match="degenerate"):
        SurfaceMesh.from_faces([[0, 0, 1]], 2)


def test_one_broken_edge_is_a_pending_crack_two_open_a_slit_that_caps_closed():
    vertices, faces = cube_surface(4, 1.0)
    mesh = SurfaceMesh.from_faces(faces, len(vertices))
    # two edges in a row through an inner vertex of a cube side
    inner = int(np.flatnonzero((np.abs(vertices[:, 2] - 0.5) < 1e-9) & (np.abs(vertices[:, :2]).max(1) < 0.2))[0])
    out = np.flatnonzero(mesh.origin == inner)
    first = np.zeros(len(mesh.twin), bool)
    first[out[0]] = True
    one, source_one = mesh.cut(first | first[mesh.twin])  # half-edge indices stay; vertex ids may not
    assert one.n_vertices == mesh.n_vertices and one.is_closed() and one.cracked.sum() == 2
    # an opposite edge at the same vertex: the vertex splits, both pairs open, one slit loop of 4
    ends = mesh.dest[out]
    across = out[np.argmax(np.linalg.norm(vertices[ends] - vertices[ends[0]], axis=1))]
    second = np.zeros(len(mesh.twin), bool)
    second[across] = True
    two, source = one.cut(second | second[one.twin])
    assert two.n_vertices == mesh.n_vertices + 1 and np.count_nonzero(source_one[source] == inner) == 2
    start, loop = two.boundary_loops()
    assert np.diff(start).tolist() == [4] and not two.cracked.any()
    assert np.all(np.bincount(two.components()) > 0) and two.components().max() == 0  # a crack, one piece
    capped = np.concatenate([two.faces, fan_caps(start, loop, two.n_vertices)])
    assert _closed(capped)


def test_cutting_every_edge_leaves_every_triangle_alone():
    vertices, faces = cube_surface(3, 1.0)
    mesh = SurfaceMesh.from_faces(faces, len(vertices))
    cut, source = mesh.cut(np.ones(len(mesh.twin), bool))
    assert cut.n_vertices == 3 * len(faces) and np.all(cut.twin < 0)
    assert np.array_equal(source[cut.faces], faces)  # every corner keeps its old vertex
    labels = cut.components()
    assert len(np.unique(labels)) == len(faces)
    start, loop = cut.boundary_loops()
    assert np.all(np.diff(start) == 3)
    assert _closed(np.concatenate([cut.faces, fan_caps(start, loop, cut.n_vertices)]))


def test_a_vertex_in_no_face_survives_a_cut_alone():
    mesh = SurfaceMesh.from_faces(TETRA, 5)  # vertex 4 is in no face
    cut, source = mesh.cut(np.ones(12, bool))
    assert source[-1] == 4 and cut.n_vertices == 13
    labels = cut.components()
    assert np.count_nonzero(labels == labels[-1]) == 1
