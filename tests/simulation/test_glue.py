"""Glued grains (``glue``): a pressed block of sticky rice stands under gravity, a loose one slumps; the paste
tears under a load it cannot carry; the glue runs only when asked for."""

import numpy as np
import pytest

from nodes.simulation.scenes import GLUE_EFFECTS, block_heights, pressed_block
from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.xpbd import xpbd

EFFECTS = GLUE_EFFECTS


@pytest.fixture(scope="module")
def block():
    return pressed_block()


def heights(block, glue, frames=40, **given):
    return block_heights(block, glue, frames, **given)


@pytest.fixture(scope="module")
def glued(block):
    return heights(block, 1.0, substeps=30)


def test_a_glued_block_stands_where_a_loose_one_slumps(block, glued):
    kept, sim = glued
    loose, _ = heights(block, 0.0, substeps=30)
    # every frame of the glued run (not only the last): ≥ 95 % of the height, as a pressed onigiri
    # (measured 0.958 at worst); the same block without glue flows into a heap: 0.80 when this was written, 0.856
    # with the packages of 2026-11-27 (the glued run unchanged), so the bound is the gap between the two
    assert kept.min() >= 0.95, kept.min()
    assert loose[-1] < 0.90 and loose[-1] < kept.min() - 0.08, (loose[-1], kept.min())
    links = ~sim.model.glue.link_own
    assert sim.state.glued[links].all()  # its own weight tears no paste


def test_a_grain_pulled_from_its_place_tears_off(block):
    aggregate, colliders = block
    p = XpbdParams(**xpbd.resolve_params({"frames": 1, "glue": 1.0}))
    # the neighbours' fits follow a pulled grain part of the way (3 of 4 grains in its region stay): at 1.5 r one
    # of its three links tore, at 3 r all
    for shift, torn in ((0.5, False), (3.0, True)):
        sim = build_simulation(aggregate, colliders, EFFECTS, p)
        m, st = sim.model, sim.state
        g = m.glue
        grain = 40  # inside the block: glued on every side
        st.x[m.start[grain] : m.start[grain + 1], 0] += shift * sim.solver.settings.glue_tear
        sim.solver._glue(st, tear=True)
        of_grain = (g.link_grain == grain) & ~g.link_own
        assert of_grain.sum() >= 3
        assert (~st.glued[of_grain]).all() if torn else st.glued[of_grain].all(), shift
        assert st.glued[~of_grain].all()  # the others hold


def test_glue_runs_only_with_adhesion():
    aggregate, colliders = pressed_block(2, 2, 2)
    p = XpbdParams(**xpbd.resolve_params({"frames": 1, "glue": 1.0}))
    without = build_simulation(aggregate, colliders, EFFECTS - {"adhesion"}, p)
    assert without.model.glue is None and without.state.glued is None
    without.frame()
    assert "glue" not in without.solver.dispatch.calls
    off = build_simulation(aggregate, colliders, EFFECTS, XpbdParams(**xpbd.resolve_params({"frames": 1})))
    assert off.model.glue is None
    on = build_simulation(aggregate, colliders, EFFECTS, p)
    on.frame()
    assert on.solver.dispatch.calls["glue"] > 0


def test_glued_runs_are_deterministic(block, glued):
    _, first = glued
    again = heights(block, 1.0, substeps=30)[1]
    assert np.array_equal(first.state.x, again.state.x)
    assert np.array_equal(first.state.glued, again.state.glued)
