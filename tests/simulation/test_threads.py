"""The solver's thread count: results independent of it; fewer threads when other processes hold the cores."""

import hashlib
import os
import subprocess
import sys
import time

import numba
import pytest
from scene_builders import rice_bowl

from nodes.simulation.settings import XpbdParams
from nodes.simulation.setup import build_simulation
from nodes.simulation.threads import WINDOW_S, FreeCores
from nodes.simulation.xpbd import xpbd

RICE = frozenset({"gravity", "contact", "friction", "adhesion", "collider", "moisture", "damping"})


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="numba has one thread: nothing to compare")
def test_results_do_not_depend_on_the_thread_count():
    aggregate, colliders = rice_bowl(150, seed=2)
    params = XpbdParams(**xpbd.resolve_params({"frames": 4, "substeps": 5}))
    digests = []
    for threads in (1, 2):
        sim = build_simulation(aggregate, colliders, RICE, params, threads=threads)
        assert sim.solver.threads == threads  # the contact sweep splits into this many runs of slabs
        for _ in range(4):
            sim.frame()
        digests.append(hashlib.sha256(sim.state.x.tobytes() + sim.state.v.tobytes()).hexdigest())
    assert digests[0] == digests[1]


def test_free_cores_drop_to_one_thread_while_other_processes_fill_the_machine():
    cores = len(os.sched_getaffinity(0))
    free = FreeCores(cores)
    spin = "print('spinning', flush=True)\nwhile True: pass"
    busy = [subprocess.Popen([sys.executable, "-c", spin], stdout=subprocess.PIPE, text=True) for _ in range(cores)]
    try:
        for proc in busy:  # each busy loop has started (not a guess at how long starting takes)
            assert proc.stdout.readline() == "spinning\n"
        free.threads()  # opens a window while they run
        time.sleep(2 * WINDOW_S)
        assert free.threads() == 1
    finally:
        for proc in busy:
            proc.kill()
            proc.wait()
            proc.stdout.close()
