"""The solver's scratch between kernels and the ``Contacts`` — SPEC §3: typed, and allocated only for what
runs (no shape matching: no λ; no pair effect: no neighbour lists; no 'adhesion': no Jacobi copy).

``Contacts`` (Newton's name) are the neighbour lists and the data each pair keeps across substeps (friction
anchors and loads, tolerated overlaps): they follow the particles of the ``State`` they were built for, and
``XpbdSolver.step`` takes them as an argument.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .friction import FORCE, NO_GROUPS, RUBBED, ContactGroups
from .model import Model
from .parting import NO_ENTRIES, NO_PAIRS
from .settings import PAIR_EFFECTS, SolverSettings


class Tracking(NamedTuple):
    """The Verlet-list displacement check folded into ``integrate.predict`` / ``update_velocity``: the positions
    at the last build and per-particle scratch; both empty without neighbour lists (``NO_TRACKING``)."""

    x_built: np.ndarray  # (n, 3), or (0, 3): no check
    moved: np.ndarray  # (n,)


NO_TRACKING = Tracking(np.empty((0, 3)), np.empty(0))


class ListRows(NamedTuple):
    """The neighbour lists' rows and whose they are (``NeighbourLists.csr``): row p lists the partners of
    particle ``order[p]``."""

    nbr_start: np.ndarray  # (n + 1,)
    nbr: np.ndarray
    order: np.ndarray  # (n,)


@dataclass(frozen=True, eq=False)
class ClusterBuffers:
    """XPBD λ of the cluster constraints, accumulated over a substep's iterations (SPEC §5)."""

    lam: np.ndarray  # (n, 3) shape matching
    bend_lam: np.ndarray | None  # (t, 3) bend constraints, None without them

    @classmethod
    def allocate(cls, model: Model) -> ClusterBuffers | None:
        """None without shape matching (then there are no bend constraints either)."""
        if model.moments is None:
            return None
        bend = np.zeros((len(model.bend.triples), 3)) if model.bend is not None else None
        return cls(np.zeros_like(model.x0), bend)

    def clear(self) -> None:
        self.lam[:] = 0.0
        if self.bend_lam is not None:
            self.bend_lam[:] = 0.0


@dataclass(frozen=True, eq=False)
class NeighbourLists:
    """CSR lists of the particles of other elements within reach, and the grid they were found in
    (``spatial_hash.neighbour_lists``), which is also the contacts' colouring. ``half``: each pair
    listed once (the Gauss–Seidel contacts); full rows for the Jacobi adhesion. Row p lists the
    partners of particle ``order[p]`` (rows in the grid's sorted order)."""

    nbr_start: np.ndarray  # (n + 1,) by sorted position
    nbr: np.ndarray  # particle ids
    at: np.ndarray  # the same partners' rows (sorted positions)
    half: bool
    cell_start: np.ndarray
    order: np.ndarray  # (n,) the particle id of each row
    dims: np.ndarray

    @classmethod
    def empty(cls, n: int, half: bool) -> NeighbourLists:
        none = np.zeros(0, np.int64)
        return cls(np.zeros(n + 1, np.int64), none, none, half, none, np.arange(n, dtype=np.int64), none)

    def csr(self) -> ListRows:
        """(nbr_start, nbr, order): the rows and whose they are."""
        return ListRows(self.nbr_start, self.nbr, self.order)

    def rows(self):
        """(nbr_start, nbr, half, order): what the pair kernels read of the lists."""
        return self.nbr_start, self.nbr, self.half, self.order

    def sweep_rows(self):
        """(nbr_start, nbr, half, order, at): the rows as the sweep reads them (``contact_constraints.PairRows``)."""
        return self.nbr_start, self.nbr, self.half, self.order, self.at

    def grid(self):
        """(cell_start, order, dims): the colouring of ``contact_constraints.contact_sweep``."""
        return self.cell_start, self.order, self.dims


@dataclass(eq=False)
class Contacts:
    """Verlet neighbour lists and what each listed pair keeps across substeps; allocated with a pair effect.

    The lists hold pairs within contact (+ capture with 'adhesion') + ``skin`` and are rebuilt only
    once some particle has moved half the skin since the last build: ``displacement`` is that
    largest move, measured by predict / update_velocity from ``x_built`` (``moved``: their per-particle
    scratch), inf before the first build."""

    lists: NeighbourLists
    skin: float
    reach: float  # list reach beyond r_i + r_j
    cell: float  # grid cell size, ≥ 2·max r + reach
    x_built: np.ndarray  # (n, 3) positions at the last build
    moved: np.ndarray  # (n,)
    allowance: np.ndarray  # per list entry, the tolerated overlap (``contact_constraints``); empty without 'contact'
    scratch: np.ndarray | None  # (n, 3) the Jacobi adhesion's output ('adhesion'), swapped with the positions
    # per list entry, where the pair began sticking (``friction``), NaN = not; carried over rebuilds
    anchor: np.ndarray
    # per list entry, the normal correction of this substep so far (anchored friction's load, ``friction``)
    load: np.ndarray
    # per list entry, its contact's mean load over the last substep and its friction mode
    # (``friction.pool_contacts``), and what friction removed this substep (``friction.RUBBED`` columns)
    held: np.ndarray
    mode: np.ndarray
    rubbed: np.ndarray
    force: np.ndarray  # per list entry, its contact's remembered force (``friction.FORCE`` columns)
    # compliant contacts (``squeeze_strain``), per list entry: the elastic overlap its compliance holds this substep
    # (``contact_constraints.compliant_push``); empty with rigid contacts
    spring: np.ndarray
    # which contact each entry belongs to (``friction.contact_groups``)
    groups: ContactGroups = NO_GROUPS
    displacement: float = np.inf
    # element pairs placed inside one another, not yet parted, and per list entry whether it is one of theirs
    # (``parting``): they part without friction between them
    deep: np.ndarray = field(default_factory=NO_PAIRS.copy)
    parting: np.ndarray = field(default_factory=NO_ENTRIES.copy)

    @classmethod
    def allocate(cls, model: Model, settings: SolverSettings) -> Contacts | None:
        """None without a pair effect (contact, friction, adhesion)."""
        effects = settings.effects
        if not PAIR_EFFECTS & effects:
            return None
        skin = 0.5 * float(model.r[: model.n_moving].max())
        reach = (settings.capture if "adhesion" in effects else 0.0) + skin
        x = model.x0
        return cls(
            NeighbourLists.empty(len(x), half="adhesion" not in effects),
            skin,
            reach,
            2.0 * float(model.r.max()) + reach,
            np.full_like(x, np.inf),
            np.zeros(len(x)),
            np.empty(0),
            np.zeros_like(x) if "adhesion" in effects else None,
            np.empty((0, 3)),
            np.empty(0),
            np.empty(0),
            np.empty(0, np.int8),
            np.empty((0, RUBBED)),
            np.empty((0, FORCE)),
            np.empty(0),
        )

    def stale(self) -> bool:
        """Some particle moved more than half the skin since the last build (or none was built)."""
        return self.displacement > 0.5 * self.skin

    def tracking(self) -> Tracking:
        """(x_built, moved): the displacement check folded into predict / update_velocity."""
        return Tracking(self.x_built, self.moved)
