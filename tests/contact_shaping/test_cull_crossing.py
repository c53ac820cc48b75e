"""``cull_crossing`` (issue 25): elements whose meshes still cut into a neighbour or a wall deeper than the threshold
are removed, deepest first, and no more than that; thin plates crossing as an X are what the contact step cannot
part within a dent budget."""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from nodegraph.values import Mesh
from nodes.contact_shaping.cull_crossing import crossed_elements, cull_crossing, wall_depths
from nodes.values import Aggregate, ElementLibrary, Placement


def plates(positions, degrees) -> Aggregate:
    """Plates 3 × 2 × 0.4 mm (like the kakigori's flakes) at ``positions``, turned about x by ``degrees``."""
    box = trimesh.creation.box([3.0, 2.0, 0.4])
    mesh = trimesh.Trimesh(*trimesh.remesh.subdivide_to_size(box.vertices, box.faces, max_edge=0.1))  # as a flake's
    library = ElementLibrary("ice_flake", (Mesh.from_trimesh(mesh, name="plate"),))
    n = len(positions)
    rotations = Rotation.from_euler("x", np.asarray(degrees, float)[:, None], degrees=True).as_matrix()
    placement = Placement(np.asarray(positions, float), np.tile([0.0, 0.0, 1.0], (n, 1)), kind_names=("ice_flake",))
    placement = Placement(placement.positions, placement.normals, rotations=rotations, kind_names=("ice_flake",))
    return Aggregate(placement, (library,))


def run(aggregate, **given):
    return cull_crossing.call(aggregate=aggregate, **given)


def test_plates_crossed_as_an_x_lose_one():
    out = run(plates([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [8.0, 0.0, 0.0]], [0.0, 90.0, 0.0]))
    table = {k: float(v[0]) for k, v in out["table"].columns.items()}
    assert table["removed"] == 1 and len(out["aggregate"].placement) == 2
    assert table["deepest_before"] > 0.05 and table["deepest_after"] == 0.0
    assert 8.0 in out["aggregate"].placement.positions[:, 0]  # the plate apart from both stays


def test_plates_that_touch_stay():
    stacked = plates([[0.0, 0.0, 0.0], [0.3, 0.1, 0.41], [0.0, 0.0, -0.405]], [0.0, 0.0, 0.0])
    out = run(stacked)
    assert float(out["table"].columns["removed"][0]) == 0
    assert out["aggregate"] is stacked


def test_a_plate_through_a_wall_goes_with_colliders_only():
    wall = Mesh.from_trimesh(trimesh.creation.box([10.0, 10.0, 1.0]).apply_translation([0.0, 0.0, -1.5]), name="floor")
    through = plates([[0.0, 0.0, -0.2], [5.0, 0.0, 1.0]], [60.0, 0.0])  # the first one's edge dips 0.17 mm in
    assert float(run(through)["table"].columns["removed"][0]) == 0
    out = run(through, colliders=[wall])
    assert float(out["table"].columns["in_walls"][0]) == 1
    assert np.allclose(out["aggregate"].placement.positions, [[5.0, 0.0, 1.0]])


def test_the_element_in_more_deep_pairs_goes_first():
    """A plate crossing two others goes alone; a greedy pair by pair would keep it and drop both others."""
    pairs = np.array([[0, 1], [1, 2]])
    gone = crossed_elements(pairs, np.array([0.3, 0.2]), 0.01, 3)
    assert gone.tolist() == [False, True, False]


def test_a_vertex_in_the_middle_of_a_wall_is_half_its_thickness_deep():
    """The deepest a point can be inside a closed mesh (the middle of its thinnest side) is looked up: the lookup
    stops at a bound, and a bound of half the side lost the middle."""
    wall = trimesh.creation.box([10.0, 10.0, 1.0]).apply_translation([0.0, 0.0, -1.5])  # z from −2 to −1
    plate = trimesh.creation.box([3.0, 2.0, 0.5]).apply_translation([0.0, 0.0, -1.25])  # its underside at z = −1.5
    depth = wall_depths([Mesh.from_trimesh(plate, name="plate")], [Mesh.from_trimesh(wall, name="wall")])
    assert np.allclose(depth, [0.5], atol=1e-6)
