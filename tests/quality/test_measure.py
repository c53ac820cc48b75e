"""The measure node reads overlaps from the element meshes: known depths of spheres, none when apart."""

import numpy as np
import pytest
import trimesh

from nodegraph.values import Mesh
from nodes.quality import measure
from nodes.values import Aggregate, ElementLibrary, Placement


def balls(*xs) -> Aggregate:
    """Unit spheres (2 mm across) on the x axis."""
    box = Mesh.from_trimesh(trimesh.creation.icosphere(4), name="box")
    positions = np.array([[x, 0.0, 0.0] for x in xs])
    return Aggregate(
        Placement(positions, np.tile([0.0, 0.0, 1.0], (len(xs), 1)), kind_names=("box",)),
        (ElementLibrary("box", (box,)),),
    )


def column(table, name):
    return float(table.columns[name][0])


def test_known_overlap_depth_in_element_lengths():
    table = measure.call(aggregates=[balls(0.0, 1.8)])
    assert column(table, "elements") == 2
    assert tuple(table.columns) == measure.outputs["table"].columns  # as declared: a sweep checks a metric by it
    assert np.isclose(column(table, "overlap_max"), 0.2 / 2.0, atol=0.003)  # 0.2 mm deep in balls 2 mm across
    assert np.isclose(column(table, "contacts_per_element"), 1.0)


def test_apart_touching_and_several_aggregates():
    assert column(measure.call(aggregates=[balls(0.0, 3.0)]), "overlap_max") == 0.0
    apart = measure.call(aggregates=[balls(0.0, 3.0)])
    assert column(apart, "contacts_per_element") == 0.0
    touching = measure.call(aggregates=[balls(0.0), balls(2.02)])  # 0.02 mm gap < 0.02 × 2 mm
    assert column(touching, "overlap_max") == 0.0 and column(touching, "contacts_per_element") == 1.0
    packed = measure.call(aggregates=[balls(0.0, 2.0, 4.0)])  # a capsule hull around three balls
    capsule = np.pi * (4.0 + 4.0 / 3.0)
    assert np.isclose(column(packed, "packing_fraction"), 3 * 4.0 / 3.0 * np.pi / capsule, rtol=0.02)
    assert np.isclose(column(packed, "fill_height"), 2.0, rtol=0.01)


def test_a_sample_is_drawn_from_the_seed():
    row = balls(*np.arange(20) * 1.9)
    a = measure.call(seed=1, aggregates=[row], sample=5)
    assert column(a, "sampled") == 5
    assert column(a, "overlap_max") == column(measure.call(seed=1, aggregates=[row], sample=5), "overlap_max")
    assert np.isclose(column(measure.call(aggregates=[row]), "overlap_p50"), 0.05, atol=0.003)


def test_elements_outside_their_vessel_are_counted_and_warned_about():
    """A ball in a bowl (rim radius 10 mm, 8 deep, 4 mm wall), one above its mound, one on its rim's lip (in), one
    past its wall, one under it: the two outside are counted in the table and a warning names them; without
    vessels nothing is tested."""
    from nodes.shapes import shape

    vessel = shape.call(kind="bowl", size=10.0, depth=8.0, resolution=2)["vessel"]
    inside = balls(0.0)  # at the rim's height, on the axis
    above = Aggregate(
        Placement(
            [[3.0, 0.0, 6.0], [12.0, 0.0, 1.0], [16.0, 0.0, 1.0], [0.0, 0.0, -12.5]], np.tile([0.0, 0.0, 1.0], (4, 1))
        ),
        inside.libraries,
    )
    assert column(measure.call(aggregates=[inside, above]), "outside_vessel") == 0  # no vessel given
    with pytest.warns(UserWarning, match="2 of 5 elements ended outside their vessel"):
        table = measure.call(aggregates=[inside, above], vessels=[vessel])
    assert column(table, "outside_vessel") == 2
    thrown = vessel.fill_z + vessel.mound + vessel.radius + 0.5  # over the heap's top by more than the rim's radius
    points = [[9.9, 0.0, 0.5], [0.0, 0.0, -7.9], [7.5, 0.0, -6.0], [0.0, 0.0, thrown], [0.0, 0.0, thrown - 1.0]]
    assert vessel.outside(np.array(points)).tolist() == [
        False,
        False,
        True,  # through the wall: (7.5/10)² + (6/8)² > 1
        True,  # thrown: over the axis, higher over the heap's top than the rim's radius
        False,  # a heap's steepest top
    ]


def test_skin_column_reads_the_element_meshes():
    assert column(measure.call(aggregates=[balls(0.0, 3.0)]), "skin") == 0.0  # convex spheres
    dented = trimesh.creation.icosphere(4)
    dented.vertices[dented.vertices[:, 2] > 0.8, 2] = 0.6  # a flat cap pushed in: concave rim edges
    aggregate = balls(0.0)
    library = ElementLibrary("box", (Mesh.from_trimesh(dented, name="box"),))
    assert column(measure.call(aggregates=[Aggregate(aggregate.placement, (library,))]), "skin") > 0.0


def test_volume_and_overlaps_are_those_of_trimesh_and_a_libigl_call_per_pair():
    """The fast paths give the very floats of what they replace: ``volume`` is trimesh's mass-properties volume,
    and one signed-distance call per neighbour (on every sampled element's points near it) gives each pair the
    depth of a call per pair."""
    import igl

    from nodes.quality.mesh_overlap import element_overlaps, volume

    rng = np.random.default_rng(3)
    sphere = trimesh.creation.icosphere(3)
    meshes = []
    for _ in range(40):
        vertices = sphere.vertices * rng.uniform(0.8, 1.2, 3) + rng.uniform(0.0, 6.0, 3)
        meshes.append((vertices, sphere.faces, float(np.ptp(vertices, axis=0).max())))
        assert volume(vertices, sphere.faces) == trimesh.Trimesh(vertices, sphere.faces, process=False).volume
    centres = np.array([0.5 * (v.min(0) + v.max(0)) for v, _, _ in meshes])
    radii = np.array([np.linalg.norm(v - c, axis=1).max() for (v, _, _), c in zip(meshes, centres)])
    sample = np.arange(0, 40, 2)
    stats = element_overlaps(meshes, centres, radii, sample)
    depths, contacts = [], np.zeros(len(sample), np.int64)  # a libigl call per pair, as before the grouping
    for row, i in enumerate(sample):
        vertices, _, length = meshes[i]
        for j in range(len(meshes)):
            if j == i or np.linalg.norm(centres[j] - centres[i]) > radii[i] + radii[j] + 0.02 * length:
                continue
            other = meshes[j][0]
            near = np.all((vertices >= other.min(0) - 0.02 * length) & (vertices <= other.max(0) + 0.02 * length), 1)
            if near.any():
                signed = igl.signed_distance(
                    vertices[near], other, meshes[j][1], sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER
                )[0]
                if signed.min() < 0.02 * length:
                    contacts[row] += 1
                    depths.append(max(0.0, -float(signed.min())) / length)
    assert len(depths) > 20 and max(depths) > 0.05  # overlapping blobs: the comparison is not vacuous
    assert sorted(stats.pair_depth.tolist()) == sorted(depths) and stats.contacts.tolist() == contacts.tolist()
