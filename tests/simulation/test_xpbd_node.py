"""The xpbd node: effects gating, outputs, buoyant yolk, determinism, bad input, Rerun logging."""

import dataclasses
import hashlib

import numpy as np
import pytest
from scene_builders import box_mesh, ikura_mesh, rice_bowl

from nodegraph.context import Context, EntityLogger
from nodes.simulation.aggregate import DeformedAggregate
from nodes.simulation.settings import EFFECTS as ALL
from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, ElementLibrary, Placement


def params(**given):
    return xpbd.resolve_params({"frames": 10, "substeps": 5, "log_every": 5, **given})


def typed(**given) -> XpbdParams:
    return XpbdParams(**params(**given))


def test_typed_parameters_are_the_declared_ones():
    assert {f.name for f in dataclasses.fields(XpbdParams)} == set(xpbd.params)
    assert xpbd.effects == frozenset(ALL)


@pytest.fixture(scope="module")
def bowl():
    return rice_bowl(40, seed=3)


def test_absent_effects_allocate_nothing_and_run_no_kernel(bowl):
    aggregate, colliders = bowl
    lean = build_simulation(aggregate, colliders, frozenset({"gravity", "contact"}), typed())
    for _ in range(3):
        lean.frame()
    calls = lean.solver.dispatch.calls
    assert calls["contact"] > 0 and calls["shape_matching"] > 0
    for family in ("friction", "adhesion", "collider", "buoyancy"):
        assert calls[family] == 0, family
    assert lean.model.collider is None  # colliders were wired, but 'collider' was not asked: no SDF built
    assert lean.state.yolks is None and lean.solver.contacts.scratch is None  # no yolk state, no Jacobi copy
    full = build_simulation(aggregate, colliders, frozenset(ALL), typed())
    full.frame()
    for family in ("contact", "friction", "adhesion", "collider"):
        assert full.solver.dispatch.calls[family] > 0, family


def test_no_pair_effect_builds_no_neighbour_lists(bowl):
    aggregate, colliders = bowl
    sim = build_simulation(aggregate, colliders, frozenset({"gravity", "collider"}), typed())
    sim.frame()
    assert sim.solver.dispatch.calls["neighbours"] == 0 and sim.solver.contacts is None


def test_grains_settle_inside_the_bowl(bowl):
    aggregate, colliders = bowl
    out = xpbd.call(
        effects=("gravity", "contact", "friction", "collider", "damping"),
        aggregate=aggregate,
        colliders=colliders,
        **params(frames=40, substeps=8),
    )
    placement = out["aggregate"].placement
    assert placement.positions[:, 2].mean() < aggregate.placement.positions[:, 2].mean()  # fell
    assert np.linalg.norm(out["particles"].positions, axis=1).max() < 60.0 - 3.0 + 0.1  # inside the cavity
    det = np.linalg.det(out["aggregate"].deformations)
    assert np.all((det > 0.3) & (det < 3.0))
    rot = placement.rotations
    assert np.allclose(rot @ rot.transpose(0, 2, 1), np.eye(3), atol=1e-6)
    mesh = out["aggregate"].element_mesh(0)  # the high-resolution mesh follows its cluster
    centre = out["particles"].positions[out["particles"].element == 0].mean(axis=0)
    assert np.linalg.norm(mesh.vertices.mean(axis=0) - centre) < 1.5


def test_same_seed_is_bit_identical(bowl):
    aggregate, colliders = bowl
    digests = []
    for _ in range(2):
        out = xpbd.call(effects=ALL, aggregate=aggregate, colliders=colliders, **params())
        h = hashlib.sha256()
        for array in (out["particles"].positions, out["aggregate"].placement.positions, out["aggregate"].deformations):
            h.update(np.ascontiguousarray(array).tobytes())
        digests.append(h.hexdigest())
    assert digests[0] == digests[1]


def egg_on_ground():
    placement = Placement(np.array([[0.0, 0.0, 3.6]]), np.array([[0.0, 0.0, 1.0]]), kind_names=("ikura",))
    return Aggregate(placement, (ElementLibrary("ikura", [ikura_mesh(3.5)]),)), [box_mesh([-20, -20, -3], [20, 20, 0])]


def test_buoyant_yolk_rises_inside_its_egg():
    aggregate, colliders = egg_on_ground()
    out = xpbd.call(
        effects=("gravity", "collider", "buoyancy", "damping"),
        aggregate=aggregate,
        colliders=colliders,
        **params(frames=30, mass=190.0),
    )
    assert isinstance(out["aggregate"], DeformedAggregate)
    offset = out["aggregate"].part_offsets[0]
    assert offset[2] > 0.5  # rose by more than half a millimetre
    mesh = out["aggregate"].element_mesh(0)
    yolk = mesh.vertices[np.unique(mesh.faces[mesh.parts == 1])]
    white = mesh.vertices[np.unique(mesh.faces[mesh.parts == 0])]
    assert yolk[:, 2].max() <= white[:, 2].max()  # still inside the membrane
    out = xpbd.call(
        effects=("gravity", "collider", "damping"),
        aggregate=aggregate,
        colliders=colliders,
        **params(frames=5, mass=190.0),
    )
    assert not isinstance(out["aggregate"], DeformedAggregate)


def test_bad_input_is_reported():
    aggregate, colliders = egg_on_ground()
    effects = ("gravity", "collider")
    with pytest.raises(ValueError, match="colliders"):
        xpbd.call(effects=effects, aggregate=aggregate, colliders=[], **params())
    empty = Aggregate(aggregate.placement.subset(np.zeros(1, bool)), aggregate.libraries)
    with pytest.raises(ValueError, match="empty"):
        xpbd.call(effects=effects, aggregate=empty, colliders=colliders, **params())
    assert xpbd.check({"mode": "full", "frames": 10})


class Recorder:
    def __init__(self):
        self.paths = []
        self.archetypes = []

    def log(self, path, archetype, static=False):
        self.paths.append(path)
        self.archetypes.append(archetype)

    def set_time(self, timeline, sequence):
        assert timeline == "sim_step"

    def send_columns(self, path, indexes, columns):
        self.paths.append(path)


def test_logs_particles_and_step_scalars_to_rerun():
    aggregate, colliders = egg_on_ground()
    ctx = Context.standalone(effects=("gravity", "collider"))
    ctx.rerun = EntityLogger(Recorder(), "/sim")
    out = xpbd(ctx, aggregate=aggregate, colliders=colliders, **params())
    paths = ctx.rerun.recording.paths
    assert paths.count("/sim/particles") == 3  # the start, after frame 5 and after frame 10 (log_every 5)
    # the library mesh (static: once where the recording keeps an index), a pose per element at the start and
    # after the last frame (every 30)
    logged = [a for p, a in zip(paths, ctx.rerun.recording.archetypes) if p == "/sim/elements/ikura/000"]
    assert "Mesh3D" in [type(a).__name__ for a in logged]
    first, last = [a for a in logged if type(a).__name__ == "InstancePoses3D"]
    at = [np.asarray(a.translations.as_arrow_array().flatten()).reshape(-1, 3) for a in (first, last)]
    final = out["aggregate"].placement.positions.astype(np.float32)
    assert np.array_equal(at[1], final)  # the last frame's poses are the output's
    assert np.abs(at[0] - final).max() > 0.1  # the egg fell between the first log and the last
    assert np.abs(at[0] - aggregate.placement.positions).max() < 1e-3  # the first is the start, before any frame
    for name in ("penetration_over_radius", "residual", "kinetic_energy", "sleeping_share"):
        assert f"/sim/scalars/{name}" in paths


def test_registry_lists_xpbd_without_loading_kernels():
    import subprocess
    import sys

    code = (
        "import sys; from nodegraph.api import default_registry; r = default_registry(); "
        "print('xpbd' in r, 'numba' in sys.modules, 'nodes.simulation.solver' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out[0] == "True"  # the package namespace exposes the node to the registry
    assert out[2] == "False"  # kernels are imported only when the node runs
