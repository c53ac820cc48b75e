"""A light recording: a simulation's steps as poses of library meshes logged once, and a dented aggregate as
instances (its dented surfaces are the shaded scene's, logged once) instead of every element's vertices."""

import numpy as np
from rerun.chunk import RrdReader
from scipy.spatial.transform import Rotation

from nodegraph.context import EntityLogger, LogIndex
from nodegraph.rerun_log import RunRecording, log_value
from nodegraph.values import Mesh
from nodes.element_poses import log_element_poses
from nodes.simulation.aggregate import DeformedAggregate
from nodes.values import Aggregate, ElementLibrary, Placement


def _aggregate(n: int = 20, seed: int = 0) -> Aggregate:
    rng = np.random.default_rng(seed)
    sphere = Mesh(*_icosahedron())
    placement = Placement(
        rng.normal(size=(n, 3)) * 5, np.tile([0.0, 0.0, 1.0], (n, 1)), Rotation.random(n, random_state=seed).as_matrix()
    )
    return Aggregate(placement, (ElementLibrary("grain", (sphere,)),))


def _icosahedron():
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=2)
    return mesh.vertices, mesh.faces


def _columns(path):
    """Entity path → list of (component column → number of rows logged), one per chunk."""
    out = {}
    for chunk in RrdReader(str(path)).stream().collect().stream():
        batch = chunk.to_record_batch()
        for column in batch.schema.names:
            if ":" in column:
                rows = sum(1 for v in batch.column(column).to_pylist() if v is not None)
                out.setdefault(chunk.entity_path, {}).setdefault(column, 0)
                out[chunk.entity_path][column] += rows
    return out


def test_simulation_steps_log_each_mesh_once_and_a_pose_per_step(tmp_path):
    recording = RunRecording(tmp_path / "s.rrd", "sim")
    log = recording.logger("/sim/log")
    steps = [0, 10, 20]
    for k, step in enumerate(steps):
        log.set_time("sim_step", step)
        assert log_element_poses(log, _aggregate(seed=k), static=False)
    recording.close()
    columns = _columns(tmp_path / "s.rrd")["/sim/log/elements/grain/000"]
    assert columns["Mesh3D:vertex_positions"] == 1  # the library mesh once
    assert columns["InstancePoses3D:translations"] == len(steps)  # a pose batch per step
    size = (tmp_path / "s.rrd").stat().st_size
    world = RunRecording(tmp_path / "w.rrd", "sim")  # the old way: every element's vertices per step
    wlog = world.logger("/sim/log")
    for k, step in enumerate(steps):
        wlog.set_time("sim_step", step)
        log_value(_aggregate(seed=k).combined_mesh(), wlog.child("elements"))
    world.close()
    assert size < (tmp_path / "w.rrd").stat().st_size / 3


def test_without_an_index_the_meshes_are_logged_every_step():
    logged = []

    class Recording:
        def log(self, path, archetype, static=False):
            logged.append((path, type(archetype).__name__, static))

    log = EntityLogger(Recording(), "/sim")
    for _ in range(2):
        log_element_poses(log, _aggregate(), static=False)
    assert [k for _, k, _ in logged].count("Mesh3D") == 2
    logged.clear()
    indexed = EntityLogger(Recording(), "/sim", LogIndex())
    for _ in range(2):
        log_element_poses(indexed, _aggregate(), static=False)
    assert [k for _, k, _ in logged].count("Mesh3D") == 1
    assert [s for _, k, s in logged if k == "InstancePoses3D"] == [False, False]


def test_a_dented_aggregate_is_logged_as_instances(tmp_path):
    plain = _aggregate()
    dented = DeformedAggregate(
        plain.placement,
        plain.libraries,
        dent_element=np.array([0, 0, 3]),
        dent_vertex=np.array([1, 2, 5]),
        dent_offset=np.full((3, 3), -0.05),
    )
    recording = RunRecording(tmp_path / "d.rrd", "d")
    log_value(dented, recording.logger("/flatten/aggregate"))
    recording.close()
    paths = set(_columns(tmp_path / "d.rrd"))
    assert "/flatten/aggregate/elements/grain/000" in paths and "/flatten/aggregate/elements" not in paths


def test_the_logger_digest_covers_the_shared_drawing_helper(monkeypatch):
    """A change to ``element_poses`` (not itself a registered logger) must stop cached fragments replaying."""
    import inspect
    from pathlib import Path

    import nodes.element_poses
    from nodegraph.rerun_log import logger_digest

    before = logger_digest()
    source = Path(inspect.getsourcefile(nodes.element_poses))
    real = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda self: real(self) + (b"#" if self == source else b""))
    assert logger_digest() != before


def _shaded_scene():
    """Grains, eggs of two parts, two ice flakes of two syrup grades and a bowl, as ``shade`` names them."""
    from nodes.values import Material, ShadedScene

    vertices, faces = _icosahedron()
    rng = np.random.default_rng(1)
    names = [f"japonica/{k:04d}" for k in range(5)] + ["ikura/0000/membrane", "ikura/0000/yolk"]
    names += ["ikura/0001/membrane", "ikura/0001/yolk", "ice/0000", "ice/0001", "bowl_container"]
    materials = [Material(name=n) for n in ("rice", "ikura_membrane", "ikura_yolk", "syrup 1", "syrup 2", "ceramic")]
    material_of = [0] * 5 + [1, 2, 1, 2, 3, 4, 5]
    meshes = [
        Mesh(vertices + rng.normal(size=3) * 4, faces, name=n, normals=vertices, colors=rng.random((len(vertices), 3)))
        for n in names
    ]
    return ShadedScene(meshes, materials, material_of)


def _meshes(path):
    """Entity path → (vertex positions, triangle indices) of each Mesh3D logged."""
    out = {}
    for chunk in RrdReader(str(path)).stream().collect().stream():
        batch = chunk.to_record_batch()
        if "Mesh3D:vertex_positions" in batch.schema.names:
            positions = np.array(batch.column("Mesh3D:vertex_positions").to_pylist()[0])
            triangles = np.array(batch.column("Mesh3D:triangle_indices").to_pylist()[0])
            out[chunk.entity_path] = positions, triangles
    return out


def test_a_shaded_scene_is_one_mesh_per_part_and_material(tmp_path):
    """The final meshes once, merged per element part and material: the grains one mesh, the eggs' membranes and
    yolks one each, the ice one per syrup grade; the same triangles in the same places."""
    from nodes.rerun_loggers import scene_groups

    scene = _shaded_scene()
    recording = RunRecording(tmp_path / "s.rrd", "shade")
    log_value(scene, recording.logger("/shade/scene"))
    recording.close()
    meshes = _meshes(tmp_path / "s.rrd")
    parts = ["japonica", "ikura/membrane", "ikura/yolk", "ice/syrup_1", "ice/syrup_2", "bowl_container"]
    assert sorted(meshes) == sorted(f"/shade/scene/{p}" for p in parts)
    groups = scene_groups(scene)
    assert groups["japonica"] == [0, 1, 2, 3, 4] and groups["ikura/yolk"] == [6, 8]
    for path, members in groups.items():
        positions, triangles = meshes[f"/shade/scene/{path}"]
        expected = np.concatenate([scene.meshes[i].vertices[scene.meshes[i].faces] for i in members])
        assert np.allclose(positions[triangles], expected, atol=1e-5)
