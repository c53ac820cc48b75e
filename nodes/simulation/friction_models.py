"""Friction models as strategies, chosen once from the ``xpbd`` node's ``friction_model`` — SPEC §3 (G Table 3:
μs = static threshold, μk = dynamic scale · μs).

Each model says what the solver does around the kernels of ``friction``: the rule the kernels take (a named
bundle, ``FrictionRule``), whether contacts keep per-pair anchors and loads across substeps and rebuilds of
the neighbour lists, whether pre-stabilisation rubs, and how much adhesion adds to a contact's load. The
kernels themselves are shared (``friction.friction_pair``, ``friction.friction_wall``): both models are the
same projection, measured from a different reference. numpy only, no numba: ``settings`` imports this at
registry time.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class FrictionRule(NamedTuple):
    """What the friction kernels take: the coefficients and where the slip is measured from."""

    mu_s: float  # static friction coefficient
    mu_k: float  # dynamic friction coefficient
    anchored: bool  # from each contact's anchor (``AnchoredFriction``), else from the substep's start


NO_FRICTION = FrictionRule(0.0, 0.0, False)  # μs = 0: the kernels skip friction and leave the anchors


class SubstepFriction:
    """Macklin et al. 2014 §6.1: static friction removes each substep's tangential slip below μs·d (d the
    contact's overlap), else scales it by min(μk·d/|Δx_t|, 1). Nothing is kept per contact; a lone grain on a
    slope rests, but rice heaps creep flat (12° at 2.5 s, 10° at 7 s; issue 24, docs/validation.md)."""

    name = "substep"
    rubs_in_prestabilisation = False  # pre-stabilisation moves no contact tangentially: nothing to hold

    def rule(self, mu_s: float, mu_k: float) -> FrictionRule:
        return FrictionRule(mu_s, mu_k, False)

    def cohesion(self, capture: float, h: float, adhesion_compliance: float) -> float:
        """Adhesion's pull as friction load (mm·g per unit of inverse mass): none, the load is the overlap."""
        return 0.0

    def lists_rebuilt(self, dispatch, old_lists, pairs, elem) -> None:
        """Nothing per pair to carry to the new neighbour lists."""

    def pool_loads(self, dispatch, pairs) -> None:
        """No loads kept."""


class AnchoredFriction:
    """Static friction restores the tangential drift since each contact began sticking (its anchor), against
    the normal load its contact carried in the last substep, pooled over the contact's particles (``friction``,
    Müller et al. 2020's λ_n test; ``friction.group_means``): slow slip cannot pile up, heaps rest and a grain on a
    plane holds to within 1° of atan μs (docs/validation.md)."""

    name = "anchored"
    rubs_in_prestabilisation = True  # the drift pre-stabilisation adds counts against the anchors

    def rule(self, mu_s: float, mu_k: float) -> FrictionRule:
        return FrictionRule(mu_s, mu_k, True)

    def cohesion(self, capture: float, h: float, adhesion_compliance: float) -> float:
        """Adhesion's pull at the capture distance as a friction load per unit of the pair's inverse mass
        (mm·g): F·h², F = capture / adhesion compliance (``contact_constraints._project_slab``)."""
        return capture * h * h / adhesion_compliance if adhesion_compliance > 0 else 0.0

    def lists_rebuilt(self, dispatch, old_lists, pairs, elem) -> None:
        """Carry each pair's anchor to its entry in the rebuilt lists (``friction.carry_anchors``); loads restart."""
        from .friction import carry_anchors, contact_groups

        anchor = np.empty((len(pairs.lists.nbr), 3))
        dispatch("friction", carry_anchors, old_lists.csr(), pairs.anchor, pairs.lists.csr(), anchor)
        pairs.anchor = anchor
        pairs.load = np.zeros(len(pairs.lists.nbr))
        pairs.held = np.zeros(len(pairs.lists.nbr))
        pairs.group, pairs.groups = contact_groups(pairs.lists, elem)

    def pool_loads(self, dispatch, pairs) -> None:
        """The last substep's loads pooled per contact (``friction.group_means``) into ``pairs.held``."""
        from .friction import group_means

        dispatch("friction", group_means, pairs.group, pairs.groups, pairs.load, pairs.held)


# the node's ``friction_model`` choices, by name
FRICTION_MODELS = {model.name: model for model in (SubstepFriction(), AnchoredFriction())}
