"""What each substep changes — SPEC §3: positions, velocities, cluster rotations, sleeping flags,
yolks, time (the ``State`` of Newton's Model / State split; ``Model.state()`` makes the first)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .shape_matching import quat_to_matrix


@dataclass(eq=False)
class YolkState:
    """Buoyant yolks (``buoyancy``): positions, velocities, positions at the substep start."""

    x: np.ndarray  # (k, 3)
    v: np.ndarray
    x_prev: np.ndarray


@dataclass(eq=False)
class State:
    """Particle and cluster state; rows as in the ``Model`` (static obstacles last, never moved).

    Sleeping (``integrate.wake_flags``, ``integrate.sleep_clusters``): ``asleep`` per element,
    ``awake`` per particle (solved this substep), ``pushed`` per particle (an asleep one a fast awake
    partner ran into), ``x_start`` the positions at the substep start, or for an asleep particle
    when it fell asleep: the sleep test's reference (untouched without sleeping). Friction against
    the walls is anchored (``wall_anchor``); the pairs' anchors follow the neighbour lists
    (``buffers.PairBuffers``)."""

    x: np.ndarray  # (n, 3)
    v: np.ndarray  # (n, 3)
    x_prev: np.ndarray  # (n, 3) positions before the substep's prediction
    quats: np.ndarray  # (m, 4) warm-started cluster rotations, w-x-y-z
    x_start: np.ndarray  # (n, 3)
    asleep: np.ndarray  # (m,) bool
    awake: np.ndarray  # (n,) bool
    pushed: np.ndarray  # (n,) bool
    wall_anchor: np.ndarray  # (n, 3) where each particle began sticking to a wall, NaN = not (``friction``)
    yolks: YolkState | None = None
    glued: np.ndarray | None = None  # (L,) bool: which glue links still hold (``glue``); None without glue
    glue_quats: np.ndarray | None = None  # (m, 4) warm-started rotations of the glued regions
    time: float = 0.0
    substeps_done: int = 0

    def rotations(self) -> np.ndarray:
        """Current cluster rotations (m, 3, 3) from the warm-started quaternions."""
        out = np.empty((len(self.quats), 3, 3))
        for c in range(len(self.quats)):
            quat_to_matrix(self.quats[c], out[c])
        return out
