"""A bed settled at 10 substeps and handed to a run at 40 (its aggregate, as one xpbd node hands it to the next)
expands to the finer run's smaller overlaps without being launched (``settings.HANDOFF_FRAMES``)."""

import numpy as np
from scene_builders import open_box, rice_library
from scipy.spatial.transform import Rotation

from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation, finish_simulation
from nodes.simulation.xpbd import xpbd
from nodes.values import Aggregate, Placement

EFFECTS = frozenset({"gravity", "contact", "friction", "collider", "damping"})


def _params(substeps):
    return XpbdParams(**xpbd.resolve_params({"substeps": substeps, "log_every": 0, "log_meshes_every": 0}))


def test_a_settled_bed_handed_to_finer_substeps_is_not_launched():
    n, rng = 150, np.random.default_rng(0)
    k = np.arange(n)
    x = np.stack([4 + (k % 4) * 6.2, 2.5 + ((k // 4) % 7) * 3.5, 3 + (k // 28) * 3.2], 1)
    turns = Rotation.from_euler("z", rng.uniform(-0.2, 0.2, (n, 1))).as_matrix()
    placement = Placement(x, np.tile([0, 0, 1.0], (n, 1)), turns, variants=k % 4, kind_names=("japonica",))
    box = open_box(26.0, 2.0, 40.0)
    coarse = build_simulation(Aggregate(placement, (rice_library(seed=0),)), box, EFFECTS, _params(10))
    for _ in range(60):
        coarse.frame()
    top = np.percentile(coarse.model.centres(coarse.state.x)[:, 2], 95)
    fine = build_simulation(finish_simulation(coarse)["aggregate"], box, EFFECTS, _params(40))
    rise, speed = [], []
    for _ in range(4):
        fine.frame()
        rise.append(np.percentile(fine.model.centres(fine.state.x)[:, 2], 95) - top)
        speed.append(np.linalg.norm(fine.state.v[: fine.model.n_moving], axis=1).mean())
    # measured: the top rises 0.18 mm at 8.6 mm/s mean speed in the first frame, 1.7 mm/s by the fourth; with the
    # depenetration speed unbounded (HANDOFF_FRAMES 0) 0.82 mm at 23 mm/s
    assert max(rise) < 0.4, rise
    assert max(speed) < 14.0, speed
