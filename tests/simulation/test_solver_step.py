"""Newton's shape of the solver (issue 45): ``XpbdSolver.step(state_in, state_out, control, contacts, dt)``
steps one state into another as it steps one in place, bit for bit; ``Control`` is what a caller changes
between steps; ``dt`` is the solve the settings fix."""

import numpy as np
import pytest
from scene_builders import stack_column


def test_step_into_another_state_matches_in_place():
    a, _, _ = stack_column(2)
    b, _, _ = stack_column(2)
    solver_b, h = b.solver, b.solver.coefficients.h
    states = [b.state, b.model.state()]
    for i in range(2 * a.solver.steps):
        a.step()
        solver_b.step(states[i % 2], states[(i + 1) % 2], solver_b.default_control, solver_b.contacts, h)
    out = states[0]  # an even number of steps ends in the first
    assert a.state.x.tobytes() == out.x.tobytes() and a.state.v.tobytes() == out.v.tobytes()
    assert a.state.quats.tobytes() == out.quats.tobytes()


def test_control_is_what_a_caller_changes_between_steps():
    run, _, _ = stack_column(2)
    s = run.solver
    control = s.control()
    control.accel[:] = 0.0  # gravity off: the stack, dropped 0.1 r apart, does not fall
    z0 = run.state.x[:, 2].copy()
    for _ in range(s.steps):
        s.step(run.state, run.state, control, s.contacts, s.coefficients.h)
    assert np.abs(run.state.x[:, 2] - z0).max() < 1e-9
    assert s.default_control.accel[0, 2] == -s.settings.gravity  # the solver's own control is untouched


def test_step_refuses_another_dt():
    run, _, _ = stack_column(2)
    s = run.solver
    with pytest.raises(ValueError, match="dt"):
        s.step(run.state, run.state, s.default_control, s.contacts, 2 * s.coefficients.h)
