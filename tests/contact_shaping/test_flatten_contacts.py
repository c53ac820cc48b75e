"""The flatten_contacts node: overlapping element meshes pressed flat where they meet, so the mesh-level
measure finds them touching, not cutting into each other; nothing moves where nothing touches."""

import dataclasses

import igl
import numpy as np
import pytest
import trimesh

from nodegraph import codec
from nodegraph.values import Mesh
from nodes.contact_shaping.flatten_contacts import flatten_contacts
from nodes.placement.cut import cut
from nodes.quality import measure
from nodes.values import Aggregate, ElementLibrary, Placement


def elements(positions, shape="ball", turns=None, kind="rice") -> Aggregate:
    """Balls 2 mm across, or grains (ellipsoids 6 × 3 × 2 mm, turned about z by ``turns`` degrees)."""
    mesh = trimesh.creation.icosphere(4)
    if shape == "grain":
        mesh.apply_scale([3.0, 1.5, 1.0])
    positions = np.asarray(positions, float)
    n = len(positions)
    angles = np.radians(np.zeros(n) if turns is None else np.asarray(turns, float))
    c, s = np.cos(angles), np.sin(angles)
    rotations = np.zeros((n, 3, 3))
    rotations[:, 0, 0], rotations[:, 0, 1], rotations[:, 1, 0], rotations[:, 1, 1] = c, -s, s, c
    rotations[:, 2, 2] = 1.0
    library = ElementLibrary(kind, (Mesh.from_trimesh(mesh, name=shape),))
    placement = Placement(positions, np.tile([0.0, 0.0, 1.0], (n, 1)), kind_names=(kind,))
    return Aggregate(dataclasses.replace(placement, rotations=rotations), (library,))


def deepest(aggregate: Aggregate, others=()) -> float:
    """The deepest vertex of any element inside another element (mm, exact: libigl on the meshes)."""
    meshes = [a.element_mesh(i) for a in (aggregate, *others) for i in range(len(a.placement))]
    worst = 0.0
    for i, a in enumerate(meshes):
        for j, b in enumerate(meshes):
            if i != j:
                worst = max(worst, -float(igl.signed_distance(a.vertices, b.vertices, b.faces)[0].min()))
    return worst


def run(aggregate, effects=("contact",), **given):
    return flatten_contacts.call(aggregate=aggregate, effects=effects, **given)


def test_two_overlapping_balls_meet_on_the_bisector():
    before = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0]])  # 0.4 mm deep
    assert deepest(before) == pytest.approx(0.4, abs=0.01)
    out = run(before)
    flat = out["aggregate"]
    assert deepest(flat) < 0.01  # was 0.4: now touching (clearance 0.005 element lengths = 0.01 mm)
    moves = np.linalg.norm(flat.dent_offset, axis=1)
    assert moves.max() == pytest.approx(0.2 + 0.005, abs=0.01)  # half the depth each, no more
    row = measure.call(aggregates=[flat])
    assert float(row.columns["overlap_max"][0]) < 0.005 and float(row.columns["contacts_per_element"][0]) == 1.0
    assert float(out["table"].columns["dented_elements"][0]) == 2


def test_grains_crossing_at_angles_stop_cutting_into_each_other():
    """Thin grains (6 × 3 × 2 mm) lying on each other or side by side at angles, 0.3–0.7 mm into each other:
    the lens' axis from both sides' normals (the nearest-surface normals alone point sideways in a thin grain)."""
    cases = [([0.0, 0.0, 1.5], turn) for turn in (0.0, 30.0, 60.0, 90.0)]
    cases += [([0.4, 2.6, 0.3], 0.0), ([0.4, 2.6, 0.3], 30.0), ([5.6, 0.3, 0.2], 0.0)]
    for offset, turn in cases:
        before = elements([[0.0, 0.0, 0.0], offset], shape="grain", turns=[0.0, turn])
        assert deepest(before) > 0.3
        out = run(before)
        assert deepest(out["aggregate"]) < 0.01, (offset, turn)
        assert float(out["table"].columns["dent_max"][0]) * 6.0 < deepest(
            before
        )  # half each, plus the in-plane relaxing


def test_apart_nothing_moves_and_the_meshes_are_unchanged():
    before = elements([[0.0, 0.0, 0.0], [2.5, 0.0, 0.0]])
    out = run(before)
    assert len(out["aggregate"].dent_element) == 0
    for i in range(2):
        assert np.array_equal(out["aggregate"].element_mesh(i).vertices, before.element_mesh(i).vertices)


def test_without_the_effects_the_aggregate_passes_through():
    before = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0]])
    out = run(before, effects=())
    assert not out["aggregate"].dented
    assert deepest(out["aggregate"]) == pytest.approx(0.4, abs=0.01)


def test_a_neighbour_aggregate_is_pressed_on_but_not_moved():
    rice, egg = elements([[0.0, 0.0, 0.0]]), elements([[1.6, 0.0, 0.0]], kind="ikura")
    rice_flat = run(rice, neighbours=[egg])["aggregate"]
    egg_flat = run(egg, neighbours=[rice])["aggregate"]
    assert len(rice_flat.placement) == 1 and set(rice_flat.dent_element) == {0}  # its own element only
    assert deepest(rice_flat, [egg]) == pytest.approx(0.2, abs=0.02)  # half the way: the egg gives the rest
    assert deepest(rice_flat, [egg_flat]) < 0.01
    assert deepest(run(rice, neighbours=[egg], share=1.0)["aggregate"], [egg]) < 0.01


def test_a_wall_pushes_vertices_all_the_way_out():
    ground = Mesh.from_trimesh(trimesh.creation.box([20.0, 20.0, 2.0]).apply_translation([0, 0, -1.8]))
    balls = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0]])  # 0.2 mm into the ground's top at z = −0.8
    flat = run(balls, effects=("collider",), colliders=[ground])["aggregate"]
    assert balls.element_mesh(0).vertices[:, 2].min() == pytest.approx(-1.0, abs=0.01)
    assert flat.element_mesh(0).vertices[:, 2].min() > -0.8 - 0.01
    assert deepest(flat) == pytest.approx(0.4, abs=0.01)  # without 'contact' the balls keep their overlap
    assert np.abs(flat.dent_offset[:, 0]).max() < 1e-3  # only straight up (contact on with share 0 moved 0.005)


def test_dented_normals_face_the_contact():
    flat = run(elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0]]))["aggregate"]
    mesh = flat.element_mesh(0)
    tip = int(np.argmax(mesh.vertices[:, 0]))  # the middle of the first ball's flat patch
    assert mesh.normals[tip] @ [1.0, 0.0, 0.0] > 0.99
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)


def test_deterministic_cached_and_cut_keeps_the_dents():
    before = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0], [3.2, 0.0, 0.0]])
    a, b = run(before)["aggregate"], run(before)["aggregate"]
    assert codec.encode(a) == codec.encode(b)
    back = codec.decode(codec.encode(a), type(a))
    assert np.array_equal(back.element_mesh(1).vertices, a.element_mesh(1).vertices)
    kept = cut.call(aggregate=a, kind="plane", normal=(1.0, 0.0, 0.0), offset=1.0)  # drops the third ball
    assert len(kept.placement) == 2
    for i in range(2):
        assert np.array_equal(kept.element_mesh(i).vertices, a.element_mesh(i).vertices)
