"""What both contact steps gather before their kernels (``contact_flattening``: the elements' world vertices, their
neighbour lists, the dents merged into the aggregate), SPEC §3: the same values as the per-element loops they
replace, without the per-element work those did (issue 27: the bunny's 4,952 grains spent ≈ 1 s of the step there)."""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.spatial
import trimesh

from nodegraph.values import Mesh
from nodes.contact_shaping.contact_flattening import Dents, _gather, _neighbour_lists, merged_dents
from nodes.simulation.aggregate import DeformedAggregate
from nodes.values import Aggregate, ElementLibrary, Placement


def scattered(n=60, seed=4, bent=False) -> Aggregate:
    """``n`` grains (ellipsoids with vertex normals) at random places and turns, bent when ``bent``."""
    rng = np.random.default_rng(seed)
    mesh = trimesh.creation.icosphere(2)
    mesh.apply_scale([3.0, 1.5, 1.0])
    library = ElementLibrary("rice", (Mesh.from_trimesh(mesh, name="grain"),))
    q, _ = np.linalg.qr(rng.normal(size=(n, 3, 3)))
    placement = Placement(rng.uniform(0.0, 14.0, (n, 3)), np.tile([0.0, 0.0, 1.0], (n, 1)), kind_names=("rice",))
    bends = rng.normal(scale=0.02, size=(n, 3, 6)) if bent else None
    return Aggregate(dataclasses.replace(placement, rotations=q), (library,), bends=bends)


def test_gathered_vertices_are_the_element_meshes_without_their_normals(monkeypatch):
    """Each element's world vertices are its mesh's, bit for bit, and no normal is rotated or bent on the way (the
    steps read positions only)."""
    aggregate = scattered(bent=True)
    expected = [aggregate.element_mesh(i).vertices for i in range(len(aggregate.placement))]

    def refuse(*args):
        raise AssertionError("the contact steps bent an element's normals they never read")

    monkeypatch.setattr(Aggregate, "_bent_normals", refuse)
    gathered = _gather([aggregate], lambda mesh: 0)
    assert all(a.tobytes() == b.tobytes() for a, b in zip(gathered.world, expected))


def test_neighbour_lists_are_the_overlapping_bounding_spheres_from_one_query(monkeypatch):
    """Element i's list: every other element whose bounding sphere comes within the margin, in index order, for the
    first ``own`` elements — found by one query of the tree for all of them."""
    aggregate = scattered(n=80)
    elements = _gather([aggregate], lambda mesh: 0)
    own, margin = 50, 0.3
    queries = []

    class Counted(scipy.spatial.cKDTree):
        def query_ball_point(self, *args, **kwargs):
            queries.append(args)
            return super().query_ball_point(*args, **kwargs)

    monkeypatch.setattr(scipy.spatial, "cKDTree", Counted)
    start, flat = _neighbour_lists(elements, own, margin)
    assert len(queries) == 1
    centre, radius = elements.centre, elements.radius
    for i in range(own):
        gap = np.linalg.norm(centre - centre[i], axis=1)
        near = np.flatnonzero((gap <= radius[i] + radius + margin) & (np.arange(len(centre)) != i))
        assert flat[start[i] : start[i + 1]].tolist() == near.tolist()
    assert start.dtype == np.int64 and flat.dtype == np.int64 and len(start) == own + 1
    empty_start, empty = _neighbour_lists(elements, 0, margin)
    assert empty_start.tolist() == [0] and len(empty) == 0


def test_merged_dents_sum_a_vertex_dented_twice_in_order():
    """A second step's dents add to the first's: a vertex moved by both gets their sum, taken in the order the
    moves come (the bits of ``np.add.at``), one row per vertex, sorted by element and vertex."""
    aggregate = scattered(n=5)
    rng = np.random.default_rng(8)
    first = Dents(np.array([0, 0, 2, 4]), np.array([3, 7, 1, 0]), rng.normal(size=(4, 3)))
    dented = DeformedAggregate(**{f.name: getattr(aggregate, f.name) for f in dataclasses.fields(aggregate)})
    dented = dataclasses.replace(dented, **merged_dents(dented, first))
    second = Dents(np.array([0, 2, 2, 3]), np.array([7, 1, 5, 2]), rng.normal(size=(4, 3)))
    merged = merged_dents(dented, second)
    element = np.concatenate([first.element, second.element])
    vertex = np.concatenate([first.vertex, second.vertex])
    offset = np.concatenate([first.offset, second.offset])
    key = element * (int(vertex.max()) + 1) + vertex
    unique, inverse = np.unique(key, return_inverse=True)
    summed = np.zeros((len(unique), 3))
    np.add.at(summed, inverse, offset)
    assert merged["dent_offset"].tobytes() == summed.tobytes()
    assert merged["dent_element"].tolist() == [0, 0, 2, 2, 3, 4]
    assert merged["dent_vertex"].tolist() == [3, 7, 1, 5, 2, 0]
