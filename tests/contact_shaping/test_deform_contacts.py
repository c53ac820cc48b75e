"""The deform_contacts node (issue 25): overlapping element meshes dented smoothly where they press, so they touch
without cutting into each other by either inside test (winding number, pseudonormal), keep their volume (a
pressed grain bulges), and no face turns over. Each of these fails on the flattening it replaced
(``flatten_contacts``, set as PRESS: 7 of the 10 fail — volume lost 3–11 %, faces turned over, depths left)."""

import dataclasses

import igl
import numba
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from nodegraph import codec
from nodegraph.values import Mesh
from nodes.contact_shaping.deform_contacts import deform_contacts
from nodes.values import Aggregate, ElementLibrary, Placement

PRESS = deform_contacts  # the node under test (flatten_contacts here shows what each test catches)


def elements(positions, shape="ball", rotations=None) -> Aggregate:
    """Balls 2 mm across, or grains (ellipsoids 6 × 3 × 2 mm) turned by ``rotations`` (3 × 3 each)."""
    mesh = trimesh.creation.icosphere(4)
    if shape == "grain":
        mesh.apply_scale([3.0, 1.5, 1.0])
    positions = np.asarray(positions, float)
    n = len(positions)
    rotations = np.tile(np.eye(3), (n, 1, 1)) if rotations is None else np.asarray(rotations, float)
    library = ElementLibrary("rice", (Mesh.from_trimesh(mesh, name=shape),))
    placement = Placement(positions, np.tile([0.0, 0.0, 1.0], (n, 1)), kind_names=("rice",))
    return Aggregate(dataclasses.replace(placement, rotations=rotations), (library,))


def turned(degrees) -> np.ndarray:
    """Rotations from x-y-z Euler angles in degrees, one row each."""
    return Rotation.from_euler("xyz", degrees, degrees=True).as_matrix()


def deepest(aggregate: Aggregate, sign: str) -> float:
    """The deepest vertex of any element inside another (mm; libigl on the meshes, signed by ``sign``)."""
    kind = {
        "winding": igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER,
        "pseudonormal": igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL,
    }
    meshes = [aggregate.element_mesh(i) for i in range(len(aggregate.placement))]
    worst = 0.0
    for i, a in enumerate(meshes):
        for j, b in enumerate(meshes):
            if i != j:
                d = igl.signed_distance(a.vertices, b.vertices, b.faces, sign_type=kind[sign])[0]
                worst = max(worst, -float(d.min()))
    return worst


def volume_errors(after: Aggregate, before: Aggregate) -> np.ndarray:
    """Each element's |volume / rest volume − 1|."""
    out = []
    for i in range(len(before.placement)):
        a, b = after.element_mesh(i), before.element_mesh(i)
        out.append(trimesh.Trimesh(a.vertices, a.faces).volume / trimesh.Trimesh(b.vertices, b.faces).volume - 1.0)
    return np.abs(np.array(out))


def turned_faces(after: Aggregate, before: Aggregate) -> int:
    """Faces whose normal the contact turned over (against their rest normal): folds a renderer shows as creases
    and that fool a pseudonormal inside test."""
    count = 0
    for i in range(len(before.placement)):
        a, b = after.element_mesh(i), before.element_mesh(i)
        count += int(np.sum(np.einsum("ij,ij->i", normals(a), normals(b)) < 0.0))
    return count


def normals(mesh) -> np.ndarray:
    x, f = mesh.vertices, mesh.faces
    return np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]])


def run(aggregate, effects=("contact",), **given):
    return PRESS.call(aggregate=aggregate, effects=effects, **given)


def test_two_balls_touch_and_keep_their_volume():
    before = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0]])  # 0.4 mm deep
    after = run(before)["aggregate"]
    for sign in ("winding", "pseudonormal"):
        assert deepest(after, sign) < 0.01, sign  # was 0.4: touching (clearance 0.005 element lengths = 0.01 mm)
    assert volume_errors(after, before).max() < 0.005  # the flattening lost 2.9 %
    assert turned_faces(after, before) == 0


def test_a_ball_squeezed_from_both_sides_bulges_back_to_its_volume():
    before = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0], [3.2, 0.0, 0.0]])
    out = run(before)
    after = out["aggregate"]
    assert deepest(after, "winding") < 0.01
    assert volume_errors(after, before).max() < 0.02  # the flattening lost 5.9 % of the middle ball
    assert float(out["table"].columns["volume_error_max"][0]) < 0.02
    middle = after.element_mesh(1).vertices
    assert np.ptp(middle[:, 1]) > np.ptp(before.element_mesh(1).vertices[:, 1]) + 0.01  # it bulges sideways


@pytest.mark.parametrize(
    "offset, degrees",
    [
        ([0.4, 2.6, 0.3], [[0, 0, 0], [0, 0, 30]]),  # side by side at 30°: the flattening turned 3 faces over
        ([0.0, 0.0, 1.5], [[0, 0, 0], [0, 0, 60]]),
        ([5.6, 0.3, 0.2], [[0, 0, 0], [0, 0, 0]]),  # tip to tip
    ],
)
def test_grains_pressed_at_angles_touch_without_turning_a_face(offset, degrees):
    before = elements([[0.0, 0.0, 0.0], offset], shape="grain", rotations=turned(degrees))
    assert deepest(before, "winding") > 0.3
    out = run(before)
    after = out["aggregate"]
    assert deepest(after, "winding") < 0.01 and deepest(after, "pseudonormal") < 0.01
    assert turned_faces(after, before) == 0 and int(out["table"].columns["folded_faces"][0]) == 0
    assert volume_errors(after, before).max() < 0.01  # the flattening lost 4–5 %


def test_a_tilted_contact_does_not_fool_the_pseudonormal_test():
    """Two grains turned at odd angles, 0.5 mm into each other: the flattening's crease left a vertex 0.027 mm deep
    by the pseudonormal test (0 by the winding number); a smooth dent leaves the two tests agreeing."""
    direction = np.array([-0.5848856137381767, -0.06167398638015923, -0.8087676664197797])
    rotations = turned([[-67.238173, 4.350987, 29.437077], [-107.303609, 62.05617, 94.65305]])
    before = elements([[0.0, 0.0, 0.0], 3.646 * direction], shape="grain", rotations=rotations)
    assert deepest(before, "winding") > 0.3
    after = run(before)["aggregate"]
    assert deepest(after, "pseudonormal") < 0.005 and deepest(after, "winding") < 0.005
    assert volume_errors(after, before).max() < 0.01


def test_apart_nothing_moves():
    before = elements([[0.0, 0.0, 0.0], [2.5, 0.0, 0.0]])
    out = run(before)
    assert len(out["aggregate"].dent_element) == 0
    for i in range(2):
        assert np.array_equal(out["aggregate"].element_mesh(i).vertices, before.element_mesh(i).vertices)


def test_a_wall_pushes_vertices_out_and_the_ball_keeps_its_volume():
    ground = Mesh.from_trimesh(trimesh.creation.box([20.0, 20.0, 2.0]).apply_translation([0, 0, -1.8]))
    before = elements([[0.0, 0.0, 0.0]])  # 0.2 mm into the ground's top at z = −0.8
    after = run(before, effects=("collider",), colliders=[ground])["aggregate"]
    assert after.element_mesh(0).vertices[:, 2].min() > -0.8 - 0.01
    assert volume_errors(after, before).max() < 0.01


def test_deterministic():
    before = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0], [3.2, 0.0, 0.0]])
    assert codec.encode(run(before)["aggregate"]) == codec.encode(run(before)["aggregate"])


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="numba has one thread: nothing to compare")
def test_the_moves_do_not_depend_on_the_thread_count(monkeypatch):
    """The elements run in chunks on numba's thread count of Python threads (``_deform_all``): each writes only its
    own rows, so one thread and two give the same bits (chunks of 2 here: six chunks for twelve pressed balls)."""
    from nodes.contact_shaping import contact_deformation

    monkeypatch.setattr(contact_deformation, "CHUNK", 2)
    before = elements([[1.6 * x, 1.6 * y, 0.0] for x in range(6) for y in range(2)])
    encoded = []
    threads = numba.get_num_threads()
    try:
        for count in (1, 2):
            numba.set_num_threads(count)
            encoded.append(codec.encode(run(before)["aggregate"]))
    finally:
        numba.set_num_threads(threads)
    assert encoded[0] == encoded[1]


def bumpy_grains(positions, rotations) -> Aggregate:
    """Grains 6 × 3 × 2 mm whose skin carries 4 % sinusoidal bumps (the skin score's calibration shape): the skin
    on which pressing vertices one by one folded faces (docs/contact.md)."""
    mesh = trimesh.creation.icosphere(4)
    x = mesh.vertices
    bumps = 1.0 + 0.04 * np.sin(9.0 * x[:, 0]) * np.sin(9.0 * x[:, 1]) * np.sin(9.0 * x[:, 2] + 0.5)
    mesh = trimesh.Trimesh(x * bumps[:, None] * [3.0, 1.5, 1.0], mesh.faces, process=False)
    library = ElementLibrary("rice", (Mesh.from_trimesh(mesh, name="bumpy"),))
    n = len(positions)
    placement = Placement(np.asarray(positions, float), np.tile([0.0, 0.0, 1.0], (n, 1)), kind_names=("rice",))
    return Aggregate(dataclasses.replace(placement, rotations=np.asarray(rotations, float)), (library,))


def folded_pairs(aggregate: Aggregate) -> int:
    """Edge-adjacent face pairs more than 150° apart: the checkers' fold."""
    count = 0
    for i in range(len(aggregate.placement)):
        m = aggregate.element_mesh(i)
        count += int(
            np.sum(trimesh.Trimesh(m.vertices, m.faces, process=False).face_adjacency_angles > np.radians(150))
        )
    return count


def test_bumpy_grains_squeezed_from_three_sides_keep_a_sound_mesh():
    """A bumpy grain pressed up to 0.8 mm deep by three others at odd angles: no folded face pair on any grain,
    both inside tests under 0.01 mm, every grain within 2 % of its volume (the flattening left 0.024 mm and lost
    11 % of the middle grain)."""
    positions = [[0.0, 0.0, 0.0], [0.5, 2.2, 0.3], [-0.4, -2.3, -0.2], [5.5, 0.4, 0.3]]
    before = bumpy_grains(positions, turned([[0, 0, 0], [10, 20, 25], [-15, 10, -30], [0, 30, 10]]))
    assert deepest(before, "winding") > 0.5 and folded_pairs(before) == 0
    after = run(before)["aggregate"]
    assert folded_pairs(after) == 0
    assert deepest(after, "winding") < 0.01 and deepest(after, "pseudonormal") < 0.01
    assert volume_errors(after, before).max() < 0.02


def test_a_free_vertex_bulges_the_full_bulge():
    """One bulge (``rounds`` 2: dent, bulge, dent) too small to give the squeezed middle ball its volume back: its
    free side moves out the whole ``bulge`` (0.02 × 2 mm), which needs room looked for up to three bulges away
    (each side takes a third of a gap; looking two away capped it at ⅔ of the bulge). The outer balls are another
    aggregate's, so the middle one keeps its half of each lens (a boxed-in element of the same aggregate would
    hand its share to them)."""
    middle = elements([[1.6, 0.0, 0.0]])
    after = run(middle, neighbours=[elements([[0.0, 0.0, 0.0], [3.2, 0.0, 0.0]])], bulge=0.02, rounds=2)["aggregate"]
    rest, moved = middle.element_mesh(0).vertices, after.element_mesh(0).vertices
    side = np.abs(rest[:, 0] - 1.6) < 0.3  # the free belt, far from both dents
    outward = np.einsum("ij,ij->i", moved[side] - rest[side], rest[side] - [1.6, 0.0, 0.0])
    assert outward.max() == pytest.approx(0.04, rel=0.02)


def test_a_sliver_turned_by_an_uneven_move_is_unfolded():
    """A needle pair of faces (an edge a fiftieth of its neighbours', as in the library's meshes) turned past 150° by
    a move that is not affine across it (its short edge turned 120° on top of an affine move): ``_unfold`` leaves no
    fold (each folded pair is carried by one move, which keeps its rest angle)."""
    from nodes.contact_shaping.contact_deformation import _folded, _unfold
    from nodes.contact_shaping.contact_flattening import vertex_rings

    sphere = trimesh.creation.icosphere(3)
    rest = np.array(sphere.vertices)
    faces = np.asarray(sphere.faces, np.int64)
    a, b = sphere.edges_unique[0]
    rest[b] = rest[a] + 0.02 * (rest[b] - rest[a])
    mesh = trimesh.Trimesh(rest, faces, process=False)
    pairs = np.asarray(mesh.face_adjacency, np.int64)
    moved = rest + rest @ np.array([[0.3, 0.4, 0.0], [-0.2, 0.1, 0.5], [0.1, -0.3, 0.2]]).T
    axis = rest[a] / np.linalg.norm(rest[a])
    moved[b] = moved[a] + Rotation.from_rotvec(np.radians(120.0) * axis).apply(moved[b] - moved[a])
    assert _folded(rest, moved, faces, pairs) > 0
    rings = vertex_rings([(len(rest), faces)])
    assert _unfold(rest, moved, faces, pairs, rings, rings.row[0]) == 0
    assert _folded(rest, moved, faces, pairs) == 0


def test_a_packed_grain_keeps_a_smooth_skin():
    """A smooth grain pressed by six others at odd angles: the step adds little concave curvature (skin score,
    ``nodes/quality/skin.py``: 0 at rest). A bulge held to a third of the room to each neighbour's surface copied the
    neighbours' convex shapes into the skin as hollows (0.162); held by the lens' planes only near the neighbour, it
    stepped where that search stopped (0.046); held by every plane everywhere, its limit is a lower envelope of
    linear functions and bends outward only (0.026)."""
    from nodes.quality.skin import skin_score

    positions = [[0, 0, 0], [0.5, 2.5, 0.3], [-0.4, -2.5, -0.2], [5.6, 0.4, 0.3], [-5.6, -0.3, 0.1]]
    positions += [[0.2, 0.3, 1.8], [-0.3, 0.2, -1.8]]
    degrees = [[0, 0, 0], [10, 20, 25], [-15, 10, -30], [0, 30, 10], [5, -20, 15], [0, 10, -10], [20, 0, 5]]
    before = elements(positions, shape="grain", rotations=turned(degrees))
    assert deepest(before, "winding") > 0.5
    after = run(before)["aggregate"]
    middle = after.element_mesh(0)
    assert skin_score(middle.vertices, middle.faces) < 0.035
    assert deepest(after, "winding") < 0.01 and deepest(after, "pseudonormal") < 0.01
    assert volume_errors(after, before).max() < 0.02 and folded_pairs(after) == 0


def test_a_ball_boxed_in_by_fourteen_keeps_its_volume():
    """A ball pressed 0.5 mm deep by six balls along the axes and 0.2 mm by eight on the diagonals has no room to
    bulge: giving way its half of every lens, it lost 31 % of its volume. A boxed-in element gives way less on a
    second pass and its neighbours, which have room outside, more."""
    axes = np.vstack([np.eye(3), -np.eye(3)])
    diagonals = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float) / np.sqrt(3.0)
    before = elements(np.vstack([[0.0, 0.0, 0.0], 1.5 * axes, 1.8 * diagonals]))
    after = run(before)["aggregate"]
    assert volume_errors(after, before).max() < 0.02
    assert deepest(after, "winding") < 0.01 and deepest(after, "pseudonormal") < 0.01
    assert turned_faces(after, before) == 0 and folded_pairs(after) == 0


def test_a_bulge_stops_halfway_to_a_near_neighbour():
    """A ball pressed 0.4 mm deep from one side bulges back; 0.06 mm off its other side lies a ball of another
    aggregate that it does not touch. The separating plane halfway across that gap (less half the clearance) holds
    the bulge: it meets nothing there, where without the plane it swelled into the gap and was dented back flat
    against the neighbour's surface."""
    pressed = elements([[0.0, 0.0, 0.0], [1.6, 0.0, 0.0]])
    near = elements([[-2.06, 0.0, 0.0]])
    after = run(pressed, neighbours=[near])["aggregate"]
    ball = after.element_mesh(0).vertices
    clearance = 0.005 * 2.0
    assert ball[:, 0].min() >= -1.0 - 0.5 * (0.06 - clearance) - 1e-6
    assert ball[:, 0].min() < -1.0 - 0.005  # it does bulge that way
    assert volume_errors(after, pressed).max() < 0.02
