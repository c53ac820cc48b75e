"""What each substep changes — SPEC §3: positions, velocities, cluster rotations, sleeping flags,
yolks, time (the ``State`` of Newton's Model / State split; ``Model.state()`` makes the first)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .shape_matching import quat_to_matrix


class StateArrays(NamedTuple):
    """A ``State``'s arrays as the kernels take them: one named bundle (numba takes it as one argument; a kernel
    reads the fields it uses). ``State.arrays()`` builds it; rebuilt after the solver swaps an array (the
    adhesion's Jacobi copy becomes ``x``)."""

    x: np.ndarray  # (n, 3)
    v: np.ndarray  # (n, 3)
    x_prev: np.ndarray  # (n, 3)
    x_start: np.ndarray  # (n, 3)
    quats: np.ndarray  # (m, 4)
    asleep: np.ndarray  # (m,) bool
    awake: np.ndarray  # (n,) bool
    pushed: np.ndarray  # (n,) bool
    wall_anchor: np.ndarray  # (n, 3)
    wall_load: np.ndarray  # (n,)
    wall_mean: np.ndarray  # (m,)
    wall_mode: np.ndarray  # (m,) int8
    wall_rubbed: np.ndarray  # (n, friction.RUBBED)
    wall_force: np.ndarray  # (m, friction.FORCE)


class YolkArrays(NamedTuple):
    """A ``YolkState``'s arrays as the buoyancy kernels take them (``YolkState.arrays()``)."""

    x: np.ndarray  # (k, 3)
    v: np.ndarray
    x_prev: np.ndarray


@dataclass(eq=False)
class YolkState:
    """Buoyant yolks (``buoyancy``): positions, velocities, positions at the substep start."""

    x: np.ndarray  # (k, 3)
    v: np.ndarray
    x_prev: np.ndarray

    def arrays(self) -> YolkArrays:
        return YolkArrays(self.x, self.v, self.x_prev)


@dataclass(eq=False)
class State:
    """Particle and cluster state; rows as in the ``Model`` (static obstacles last, never moved).

    Sleeping (``integrate.wake_flags``, ``integrate.sleep_clusters``): ``asleep`` per element,
    ``awake`` per particle (solved this substep), ``pushed`` per particle (an asleep one a fast awake
    partner ran into), ``x_start`` the positions at the substep start, or for an asleep particle
    when it fell asleep: the sleep test's reference (untouched without sleeping). Friction against
    the walls is anchored (``wall_anchor``); the pairs' anchors follow the neighbour lists
    (``buffers.Contacts``)."""

    x: np.ndarray  # (n, 3)
    v: np.ndarray  # (n, 3)
    x_prev: np.ndarray  # (n, 3) positions before the substep's prediction
    quats: np.ndarray  # (m, 4) warm-started cluster rotations, w-x-y-z
    x_start: np.ndarray  # (n, 3)
    asleep: np.ndarray  # (m,) bool
    awake: np.ndarray  # (n,) bool
    pushed: np.ndarray  # (n,) bool
    wall_anchor: np.ndarray  # (n, 3) where each particle began sticking to a wall, NaN = not (``friction``)
    wall_load: np.ndarray  # (n,) the walls' normal pushes on each particle this substep (friction's load)
    wall_mean: np.ndarray  # (m,) each element's mean wall load over its touching particles, last substep
    wall_mode: np.ndarray  # (m,) int8: each element's friction mode against the walls (``friction.contact_mode``)
    wall_rubbed: np.ndarray  # (n, friction.RUBBED) what wall friction removed from each particle this substep
    wall_force: np.ndarray  # (m, friction.FORCE) each element's remembered force against the walls
    slow_steps: np.ndarray  # (m,) int: substeps each awake element has stayed still in a row (``sleep_clusters``)
    yolks: YolkState | None = None
    glued: np.ndarray | None = None  # (L,) bool: which glue links still hold (``glue``); None without glue
    glue_quats: np.ndarray | None = None  # (m, 4) warm-started rotations of the glued regions
    time: float = 0.0
    substeps_done: int = 0

    def assign(self, other: State) -> None:
        """Make this state a copy of ``other`` (same model), in place: ``XpbdSolver.step`` from one state into
        another."""
        for name in (
            "x",
            "v",
            "x_prev",
            "quats",
            "x_start",
            "asleep",
            "awake",
            "pushed",
            "wall_anchor",
            "wall_load",
            "wall_mean",
            "wall_mode",
            "wall_rubbed",
            "wall_force",
            "slow_steps",
        ):
            np.copyto(getattr(self, name), getattr(other, name))
        if other.yolks is not None:
            for name in ("x", "v", "x_prev"):
                np.copyto(getattr(self.yolks, name), getattr(other.yolks, name))
        if other.glued is not None:
            np.copyto(self.glued, other.glued)
            np.copyto(self.glue_quats, other.glue_quats)
        self.time, self.substeps_done = other.time, other.substeps_done

    def arrays(self) -> StateArrays:
        """The kernels' bundle of this state's arrays (``StateArrays``): build it again after swapping one."""
        return StateArrays(
            self.x,
            self.v,
            self.x_prev,
            self.x_start,
            self.quats,
            self.asleep,
            self.awake,
            self.pushed,
            self.wall_anchor,
            self.wall_load,
            self.wall_mean,
            self.wall_mode,
            self.wall_rubbed,
            self.wall_force,
        )

    def rotations(self) -> np.ndarray:
        """Current cluster rotations (m, 3, 3) from the warm-started quaternions."""
        out = np.empty((len(self.quats), 3, 3))
        for c in range(len(self.quats)):
            quat_to_matrix(self.quats[c], out[c])
        return out


@dataclass(eq=False)
class Control:
    """What a caller may change between steps (Newton's ``Control``): the external accelerations. The solver's
    ``control()`` gives the settings' own (gravity along −z with effect 'gravity', the yolks' buoyancy); the
    gravity-step check and the sleep and mass-scaling thresholds stay those of the settings."""

    accel: np.ndarray  # (1, 3) mm/s², on every moving particle (``integrate.predict``)
    yolk_accel: np.ndarray  # (3,) mm/s², on the yolks (``buoyancy.yolk_predict``)
