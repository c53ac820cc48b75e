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

    def lists_rebuilt(self, dispatch, old_lists, pairs, model) -> None:
        """Nothing per pair to carry to the new neighbour lists."""

    def pool_loads(self, dispatch, pairs, rule: FrictionRule, cohesion: float) -> None:
        """No loads kept."""


class AnchoredFriction:
    """Static friction restores the tangential drift since each contact began sticking (its anchor); whether a
    contact sticks or slides is decided per contact of two elements (or element and walls) from the corrections
    it needed over the substeps before (``friction.contact_mode``, Müller et al. 2020's λ_t < μs·λ_n): slow slip
    cannot pile up, and a grain on a plane holds to within 1° of atan μs at any substeps and iterations."""

    name = "anchored"
    rubs_in_prestabilisation = True  # the drift pre-stabilisation adds counts against the anchors

    def rule(self, mu_s: float, mu_k: float) -> FrictionRule:
        return FrictionRule(mu_s, mu_k, True)

    def cohesion(self, capture: float, h: float, adhesion_compliance: float) -> float:
        """Adhesion's pull at the capture distance as a friction load per unit of the pair's inverse mass
        (mm·g): F·h², F = capture / adhesion compliance (``contact_constraints._project_slab``)."""
        return capture * h * h / adhesion_compliance if adhesion_compliance > 0 else 0.0

    def lists_rebuilt(self, dispatch, old_lists, pairs, model) -> None:
        """Carry what each pair keeps across substeps (anchor, pooled load, mode, remembered force) to its entry in
        the rebuilt lists (``friction.entry_sources``); pairs new to the lists start afresh."""
        from .friction import ROLLS, RUBBED, carried, contact_groups, entry_sources

        source = np.empty(len(pairs.lists.nbr), np.int64)
        dispatch("friction", entry_sources, old_lists.csr(), pairs.lists.csr(), source)
        pairs.anchor = carried(pairs.anchor, source, np.nan)
        pairs.held = carried(pairs.held, source, 0.0)
        pairs.mode = carried(pairs.mode, source, 0)
        pairs.force = carried(pairs.force, source, 0.0)
        # this substep's sums restart: carried, the normal pushes that part overlapping elements (pre-stabilisation's
        # included) loaded a sticking contact that then restored a drift turned by them (fuzzed spheres gained 2 %)
        pairs.load = np.zeros(len(source))
        pairs.rubbed = np.zeros((len(source), RUBBED))
        pairs.groups = contact_groups(pairs.lists, model.elem, model.w)
        pairs.mode[pairs.groups.rolls] = ROLLS

    def pool_loads(self, dispatch, pairs, rule: FrictionRule, cohesion: float) -> None:
        """The last substep's loads and friction pooled per contact (``friction.pool_contacts``): ``pairs.held``
        and ``pairs.mode`` for the next substep."""
        from .friction import pool_contacts

        args = (pairs.groups, cohesion, rule.mu_s, pairs.load, pairs.rubbed, pairs.held, pairs.mode, pairs.force)
        dispatch("friction", pool_contacts, *args)


# the node's ``friction_model`` choices, by name
FRICTION_MODELS = {model.name: model for model in (SubstepFriction(), AnchoredFriction())}
