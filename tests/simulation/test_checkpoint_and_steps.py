"""A long simulation resumes from its checkpoint bit for bit; the recording shows each step's state."""

import datafusion
import numpy as np
import pytest
from rerun.chunk import RrdReader
from scene_builders import rice_bowl

from nodegraph.checkpoint import Checkpoint
from nodegraph.context import Context
from nodegraph.rerun_log import RunRecording
from nodes.simulation.xpbd import xpbd

EFFECTS = ("gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping")


class StopAfter(Checkpoint):
    """Saves every frame, then stops the run as Ctrl-C would, after frame ``stop``."""

    def __init__(self, path, stop):
        super().__init__(path, interval=0.0)
        self.stop = stop

    def save(self, value):
        super().save(value)
        if value.frames_done == self.stop:
            raise KeyboardInterrupt


def run(aggregate, colliders, checkpoint=None, **params):
    ctx = Context.standalone(node_type="xpbd", effects=EFFECTS)
    ctx.checkpoint = checkpoint
    return xpbd(
        ctx, aggregate=aggregate, colliders=colliders, **xpbd.resolve_params({"frames": 8, "substeps": 4, **params})
    )


def test_an_interrupted_simulation_resumes_bit_for_bit(tmp_path):
    aggregate, colliders = rice_bowl(40, seed=2)
    straight = run(aggregate, colliders)
    path = tmp_path / "ck.npz"
    with pytest.raises(KeyboardInterrupt):
        run(aggregate, colliders, StopAfter(path, stop=3))
    assert path.is_file()
    resumed_checkpoint = Checkpoint(path, interval=1e9)
    resumed = run(aggregate, colliders, resumed_checkpoint)
    for name in ("positions", "velocities"):
        assert np.array_equal(getattr(resumed["particles"], name), getattr(straight["particles"], name))
    assert np.array_equal(resumed["aggregate"].placement.rotations, straight["aggregate"].placement.rotations)
    # the checkpoint holds the frame it was taken at
    with pytest.raises(KeyboardInterrupt):
        run(aggregate, colliders, StopAfter(tmp_path / "other.npz", stop=5))
    assert Checkpoint(tmp_path / "other.npz").load().frames_done == 5


def test_a_damaged_checkpoint_is_ignored_and_removed(tmp_path):
    aggregate, colliders = rice_bowl(20, seed=3)
    path = tmp_path / "ck.npz"
    path.write_bytes(b"not a checkpoint")
    out = run(aggregate, colliders, Checkpoint(path, interval=1e9), frames=2)
    assert not path.exists()
    assert np.array_equal(out["particles"].positions, run(aggregate, colliders, frames=2)["particles"].positions)


def test_the_recording_shows_each_steps_particles(tmp_path):
    aggregate, colliders = rice_bowl(30, seed=1)
    recording = RunRecording(tmp_path / "sim.rrd", "sim")
    ctx = Context.standalone(node_type="xpbd", effects=EFFECTS)
    ctx.rerun = recording.logger("/sim/log")
    xpbd(
        ctx,
        aggregate=aggregate,
        colliders=colliders,
        **xpbd.resolve_params({"frames": 6, "substeps": 4, "log_every": 1, "sleep_speed": 0.0}),
    )
    recording.close()
    session = datafusion.SessionContext()  # must outlive the query
    table = (
        RrdReader(str(tmp_path / "sim.rrd"))
        .stream()
        .collect()
        .reader("sim_step", contents="/sim/log/particles", ctx=session)
        .to_arrow_table()
    )
    steps = table.column("sim_step").to_pylist()
    assert steps == [0, 4, 8, 12, 16, 20, 24]  # the start and after each frame
    logged = {
        s: np.asarray(p, np.float32).reshape(-1, 3)
        for s, p in zip(steps, table.column("/sim/log/particles:Points3D:positions").to_pylist())
    }
    for frames in (1, 4):
        alone = run(aggregate, colliders, frames=frames, sleep_speed=0.0)["particles"].positions.astype(np.float32)
        assert np.array_equal(logged[4 * frames], alone)  # the state after that many frames, exactly
    assert np.abs(logged[4] - logged[24]).max() > 0.05  # the grains moved between an early and a late step
