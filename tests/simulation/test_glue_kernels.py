"""The glue's kernels (``glue``) against plain numpy references on a pressed block with some links torn: the region
fits (``glue_match``) and the pressed overlaps the glued contacts tolerate (``glued_floors`` once per build of the
lists, ``glued_allowance`` each substep), at one thread and at two."""

import numba
import numpy as np
import pytest
from scene_builders import GLUE_EFFECTS, pressed_block

from nodes.simulation import glue
from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.threads import thread_count
from nodes.simulation.xpbd import xpbd


@pytest.fixture(scope="module")
def torn():
    """A pressed block after one frame on its ground, a fifth of its links torn at random."""
    aggregate, colliders = pressed_block(3, 3, 4, press_frames=3)
    p = XpbdParams(**xpbd.resolve_params({"frames": 1, "glue": 1.0, "clumping": 0.5}))
    sim = build_simulation(aggregate, colliders, GLUE_EFFECTS, p, threads=1)
    sim.frame()
    g = sim.model.glue
    cut = np.random.default_rng(3).random(len(g.link_grain)) < 0.2
    sim.state.glued[cut & ~g.link_own] = False
    return sim


def reference_goals(x, w, g, intact):
    """Each membership's goal: the region's rigid fit (centre of mass plus R·rest offset), NaN where torn."""
    goal = np.full((len(g.member), 3), np.nan)
    for reg in range(len(g.region_start) - 1):
        links = np.arange(g.region_start[reg], g.region_start[reg + 1])
        if not (intact[links] & ~g.link_own[links]).any():
            continue
        slots = np.concatenate([np.arange(g.link_start[k], g.link_start[k + 1]) for k in links if intact[k]])
        m = 1.0 / w[g.member[slots]]
        p, q = x[g.member[slots]], g.rest[slots]
        c, c0 = m @ p / m.sum(), m @ q / m.sum()
        u, _, vt = np.linalg.svd(((p - c) * m[:, None]).T @ (q - c0))
        rot = u @ vt
        goal[slots] = c + (q - c0) @ rot.T
    return goal


@pytest.mark.parametrize("threads", [1, 2])
def test_glue_match_fits_each_region_rigidly(torn, threads):
    sim = torn
    g, st = sim.model.glue, sim.state
    goal = np.empty((len(g.member), 3))
    quats = st.glue_quats.copy()
    with thread_count(min(threads, numba.config.NUMBA_NUM_THREADS)):
        for _ in range(10):  # the rotations converge over calls (each starts from the last quaternion)
            arrays = glue.GlueArrays(st.glued.copy(), quats, goal)
            glue.glue_match(st.arrays(), sim.model.arrays(), g.rows(), arrays, glue.GlueRule(30, 1.0, 0.0), False)
    expected = reference_goals(st.x, sim.model.w, g, st.glued)
    assert np.array_equal(np.isnan(goal[:, 0]), np.isnan(expected[:, 0]))
    ok = ~np.isnan(expected[:, 0])
    assert ok.sum() > 0.5 * len(ok)
    np.testing.assert_allclose(goal[ok], expected[ok], atol=1e-6)


def reference_allowance(sim):
    """Per entry of the lists: the pressed overlap of a pair whose grains are still glued, else 0."""
    m, st, lists = sim.model, sim.state, sim.solver.contacts.lists
    g = m.glue
    floors = {}
    for i in range(len(g.floor_start) - 1):
        for f in range(g.floor_start[i], g.floor_start[i + 1]):
            floors[(i, int(g.floor_partner[f]))] = g.floor_depth[f]
    glued = {}
    for a in range(len(g.region_start) - 1):
        for k in range(g.region_start[a] + 1, g.region_start[a + 1]):
            glued[(a, int(g.link_grain[k]))] = bool(st.glued[k])
    out = np.zeros(len(lists.nbr))
    for p in range(len(lists.nbr_start) - 1):
        i = int(lists.order[p])
        for a in range(lists.nbr_start[p], lists.nbr_start[p + 1]):
            j = int(lists.nbr[a])
            if (not lists.half and j < i) or max(m.elem[i], m.elem[j]) >= m.elements:
                continue
            if glued.get((int(m.elem[i]), int(m.elem[j])), False):
                out[a] = floors.get((i, j), 0.0)
    return out


def test_glued_contacts_tolerate_their_pressed_overlap_while_glued(torn):
    sim = torn
    expected = reference_allowance(sim)
    assert (expected > 0).sum() >= 20  # pressed glued pairs (40 of 1,802 entries), torn ones left out
    allowance = sim.solver.contacts.allowance
    allowance[:] = 0.0
    sim.solver._pressed(sim.state, sim.solver.contacts)
    assert np.array_equal(allowance, expected)
    # a tear after the lists were built is seen without a new build; a larger allowance is kept
    g = sim.model.glue
    keep = np.flatnonzero(sim.state.glued & ~g.link_own)[::2]
    sim.state.glued[keep] = False
    allowance[:] = 0.0
    allowance[-1] = 5.0
    sim.solver._pressed(sim.state, sim.solver.contacts)
    expected = reference_allowance(sim)
    expected[-1] = max(expected[-1], 5.0)
    assert np.array_equal(allowance, expected)
