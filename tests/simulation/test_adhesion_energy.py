"""A sticky clump at rest gains no energy at 4× the default substeps: adhesion bonds are critically damped
(``adhesion.adhesion_project``). Undamped, the bonds and the contacts traded energy every substep, and at 40
substeps a 30-grain clump at rest by 0.4 s (kinetic energy 1.5 g·mm²/s²) heated up to 47 and its grains moved
0.6 mm in the next 0.25 s; a 250-grain clump crept flat (H/R 44° at 10 substeps, 21° at 40), where it now stands
at 45.7° and 44.1° from 1 s to 7 s."""

import numpy as np
from scene_builders import box_mesh, rice_library
from scipy.spatial.transform import Rotation

from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, Placement

EFFECTS = frozenset({"gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping"})


def sticky_clump(n: int = 30, seed: int = 7) -> Aggregate:
    """n japonica grains on a jittered 4.3 mm grid inside a ball, its bottom 3 mm above the ground."""
    rng = np.random.default_rng(seed)
    axis = np.arange(-4, 5) * 4.3
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    x = grid[np.argsort(np.linalg.norm(grid, axis=1), kind="stable")][:n] + rng.uniform(-0.4, 0.4, (n, 3))
    x[:, 2] += 3.0 - x[:, 2].min()
    placement = Placement(
        x,
        np.tile([0.0, 0.0, 1.0], (n, 1)),
        Rotation.random(n, random_state=3).as_matrix(),
        variants=(np.arange(n) % 4).astype(np.int32),
        kind_names=("japonica",),
    )
    return Aggregate(placement, (rice_library(),))


def test_a_sticky_clump_at_rest_gains_no_energy_at_4x_the_substeps():
    frames = 40
    params = XpbdParams(**xpbd.resolve_params({"frames": frames, "substeps": 40, "log_every": 0}))
    sim = build_simulation(sticky_clump(), [box_mesh([-60, -60, -5], [60, 60, 0], "floor")], EFFECTS, params)
    for f in range(1, frames + 1):
        sim.frame()
        if f == 25:
            rested = sim.model.centres(sim.state.x)[:, :3].copy()
    drift = np.linalg.norm(sim.model.centres(sim.state.x)[:, :3] - rested, axis=1)
    energy = sim.solver.diagnostics.kinetic_energy
    assert drift.max() < 0.1, f"a grain of the rested clump moved {drift.max():.2f} mm in 0.25 s"
    assert max(energy[25:]) < 10.0, f"kinetic energy rose to {max(energy[15:]):.0f} g·mm²/s² after rest"
