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
