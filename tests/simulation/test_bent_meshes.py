"""Bent grains: with the quadratic goal the high-resolution meshes follow the cluster's bend
(``Aggregate.bends``, SPEC §5 quadratic shape matching); the linear path stays straight and unchanged."""

import hashlib
import io
import json
import zipfile

import numpy as np
import trimesh
from scene_builders import long_grain
from scipy.spatial.transform import Rotation

from nodegraph import codec
from nodes.simulation.aggregate import DeformedAggregate
from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation, snapshot_aggregate
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, ElementLibrary, Placement

BEND_RADIUS = 10.0  # mm, arc the particles are laid on (sag ≈ 1.6 mm over the grain)
ROTATION = Rotation.from_euler("zyx", [30.0, 10.0, -20.0], degrees=True).as_matrix()
ORIGIN = np.array([3.0, -2.0, 5.0])


def aggregate(mesh=None) -> Aggregate:
    placement = Placement(ORIGIN[None], np.array([[0.0, 0.0, 1.0]]), ROTATION[None], kind_names=("long",))
    return Aggregate(placement, (ElementLibrary("long", [mesh or long_grain()]),))


def params(**given) -> XpbdParams:
    return XpbdParams(
        **xpbd.resolve_params({"frames": 1, "particles_per_element": 16, "linear_deformation": 1.0, **given})
    )


def arc(local):
    """Bend local points about the y axis onto a circle of radius BEND_RADIUS (ends go up: +z)."""
    u, v, w = local[:, 0], local[:, 1], local[:, 2]
    theta = u / BEND_RADIUS
    radius = BEND_RADIUS - w
    return np.stack([radius * np.sin(theta), v, BEND_RADIUS - radius * np.cos(theta)], axis=1)


def bent_snapshot(deformation):
    """Lay the element's particles on the arc (in its own frame) and read the aggregate back."""
    sim = build_simulation(aggregate(), [], frozenset(), params(deformation=deformation))
    rest_local = sim.model.q_rest + sim.local_centre[0]
    sim.state.x[:] = arc(rest_local) @ ROTATION.T + ORIGIN
    return sim, snapshot_aggregate(sim)


def local_frame(points):
    return (points - ORIGIN) @ ROTATION


def sag(local_rest, local_now):
    """Height of the ends above the middle along the grain's centre line (element frame)."""
    u = np.abs(local_rest[:, 0])
    middle, ends = u < 0.2 * u.max(), u > 0.75 * u.max()
    return local_now[ends, 2].mean() - local_now[middle, 2].mean()


def test_long_grain_cluster_gets_the_quadratic_goal():
    sim = build_simulation(aggregate(), [], frozenset(), params(deformation="quadratic"))
    assert sim.model.quadratic.flags.all()


def test_quadratic_mesh_follows_the_arc_linear_mesh_stays_straight():
    rest = long_grain().vertices
    expected = sag(rest, arc(rest))
    assert expected > 1.0
    _, bent = bent_snapshot("quadratic")
    assert bent.bends is not None and bent.bends.shape == (1, 3, 6)
    mesh = bent.element_mesh(0)
    assert abs(sag(rest, local_frame(mesh.vertices)) - expected) < 0.1 * expected
    # every vertex near the arc, far closer than the straight mesh
    error = np.linalg.norm(local_frame(mesh.vertices) - arc(rest), axis=1)
    _, straight = bent_snapshot("linear")
    assert straight.bends is None
    flat = straight.element_mesh(0)
    flat_error = np.linalg.norm(local_frame(flat.vertices) - arc(rest), axis=1)
    assert abs(sag(rest, local_frame(flat.vertices))) < 0.1 * expected
    assert error.max() < 0.25 * flat_error.max()


def test_bent_map_passes_closer_through_the_particles():
    """The element's map at the particles' rest positions lands near the bent particles."""
    misfit = {}
    for mode in ("quadratic", "linear"):
        sim, snapshot = bent_snapshot(mode)
        mapped = snapshot.element_points(0, sim.model.q_rest + sim.local_centre[0])
        misfit[mode] = np.abs(mapped - sim.state.x).max()
    assert misfit["quadratic"] < 0.2 * misfit["linear"]


def test_bent_normals_stay_unit_and_follow_the_bend():
    rest_mesh = long_grain()
    _, bent = bent_snapshot("quadratic")
    mesh = bent.element_mesh(0)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)
    # reference: normals of the exactly bent surface (trimesh's vertex normals of the arc-mapped mesh)
    exact = trimesh.Trimesh(arc(rest_mesh.vertices), rest_mesh.faces, process=False).vertex_normals
    cosine = np.einsum("ij,ij->i", mesh.normals @ ROTATION, exact)
    assert cosine.min() > 0.95
    rotated_only = np.einsum("ij,ij->i", rest_mesh.normals, exact)
    assert cosine.mean() > rotated_only.mean()


def test_linear_path_is_bit_identical_to_the_rigid_map():
    """bends None: element_mesh is exactly v·(D·R)ᵀ + t with R-rotated normals, as before the field."""
    _, straight = bent_snapshot("linear")
    base = long_grain()
    p = straight.placement
    mesh = straight.element_mesh(0)
    assert np.array_equal(mesh.vertices, base.vertices @ (straight.deformations[0] @ p.rotations[0]).T + p.positions[0])
    assert np.array_equal(mesh.normals, base.normals @ p.rotations[0].T)


def test_bent_snapshot_is_deterministic():
    digests = []
    for _ in range(2):
        _, bent = bent_snapshot("quadratic")
        digests.append(hashlib.sha256(np.ascontiguousarray(bent.element_mesh(0).vertices).tobytes()).hexdigest())
        digests.append(codec.content_hash(bent))
    assert digests[0] == digests[2] and digests[1] == digests[3]


def test_codec_round_trips_bends_and_old_entries_without_the_field():
    _, bent = bent_snapshot("quadratic")
    back = codec.decode(codec.encode(bent), Aggregate)
    assert np.array_equal(back.bends, bent.bends)
    assert np.array_equal(back.element_mesh(0).vertices, bent.element_mesh(0).vertices)
    # an entry written before the field existed: no 'bends' in the stored field tree
    old = Aggregate(bent.placement, bent.libraries, bent.deformations)
    raw = codec.encode(old)
    with zipfile.ZipFile(io.BytesIO(raw)) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    tree = json.loads(members["__meta__.json"])
    del tree["fields"]["bends"]
    members["__meta__.json"] = json.dumps(tree, sort_keys=True, separators=(",", ":")).encode()
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    legacy = codec.decode(buffer.getvalue(), Aggregate)
    assert legacy.bends is None
    assert np.array_equal(legacy.element_mesh(0).vertices, old.element_mesh(0).vertices)


def test_yolk_offsets_still_move_the_part_faces_of_a_bent_element():
    """DeformedAggregate (ikura yolk) adds its part offsets on top of the bent map."""
    from scene_builders import ikura_mesh

    egg = ikura_mesh()
    placement = Placement(ORIGIN[None], np.array([[0.0, 0.0, 1.0]]), ROTATION[None], kind_names=("ikura",))
    bends = np.random.default_rng(0).normal(0.0, 0.02, (1, 3, 6))
    libraries = (ElementLibrary("ikura", [egg]),)
    bent = Aggregate(placement, libraries, np.eye(3)[None] * 1.1, bends)
    offset = np.array([0.0, 0.0, 0.7])
    shifted = DeformedAggregate(placement, libraries, bent.deformations, bends, part_offsets=offset[None])
    yolk = np.zeros(len(egg.vertices), bool)
    yolk[np.unique(egg.faces[egg.parts == 1])] = True
    moved = shifted.element_mesh(0).vertices - bent.element_mesh(0).vertices
    assert np.allclose(moved[yolk], offset) and np.all(moved[~yolk] == 0.0)
    assert not np.allclose(
        bent.element_mesh(0).vertices, Aggregate(placement, libraries, bent.deformations).element_mesh(0).vertices
    )  # the bend is applied under the offsets
