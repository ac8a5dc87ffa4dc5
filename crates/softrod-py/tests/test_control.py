"""Cable tensions from a controller in the loop, and the step API."""

from __future__ import annotations

import numpy as np
import pytest

import softrod
from conftest import rod

CABLES = [(0.0, 0.008), (0.0, -0.008)]


def arm(tension=(0.0, 0.0)):
    cables = [softrod.Cable(offset=o, tension=t) for o, t in zip(CABLES, tension)]
    return softrod.Simulation(
        rods=[rod(pieces=4, strains=["ky", "qx", "qz"], viscosity=50.0, cables=cables)],
        gravity=[0, 0, -9.81])


TIGHT = dict(integrator="dopri5", rtol=1e-10, atol=1e-12)


def test_a_constant_controller_is_a_constant_tension():
    """u = (1.2, 0.3) held by the controller gives the run of cables
    scheduled at those tensions (the facade's path, another code path)."""
    # Both at rtol 1e-10: the runs agree to ~1e-9 of the motion (~1 cm).
    tip_tol = 1e-8
    want = arm((1.2, 0.3)).simulate(0.05, output_every=0.01, **TIGHT)
    sim = arm()
    got = sim.simulate(0.05, output_every=0.01, controller=lambda t, q, qd: [1.2, 0.3], **TIGHT)
    assert np.abs(got.tip_position - want.tip_position).max() < tip_tol
    np.testing.assert_array_equal(got.t, want.t)


def test_the_controller_is_sampled_and_held_every_control_period():
    calls = []

    def bang_bang(t, q, qd):
        calls.append((t, q.copy()))
        return [2.0, 0.0] if t < 0.02 else [0.0, 2.0]

    sim = arm()
    traj = sim.simulate(0.05, output_every=0.01, controller=bang_bang, control_every=0.01)
    times = [c[0] for c in calls]
    np.testing.assert_allclose(times, [0.0, 0.01, 0.02, 0.03, 0.04], atol=1e-15)
    # It sees the state at its own time: the samples there (the dense
    # output at a segment's end reproduces the step to round-off).
    for k, (t, q) in enumerate(calls):
        np.testing.assert_allclose(q, traj.q[k], rtol=0, atol=1e-12)
    # The hold is exact: the same run as a loop of steps with u held.
    st = sim.initial()
    for k in range(5):
        st = sim.step(st, 0.01, [2.0, 0.0] if k < 2 else [0.0, 2.0])
        np.testing.assert_allclose(st.q, traj.q[k + 1], rtol=0, atol=1e-12)
    assert st.t == pytest.approx(0.05, abs=1e-15)
    # The cable at z = +8 mm bends the base piece toward +z (ky below the
    # sag of the unactuated arm), then the one at -8 mm toward -z.
    free = sim.simulate(0.05, output_every=0.01, controller=lambda t, q, qd: [0.0, 0.0])
    assert traj.q[2, 0] < free.q[2, 0]
    assert traj.q[-1, 0] > free.q[-1, 0]


def test_per_step_control_is_called_once_per_accepted_step():
    n = [0]

    def count(t, q, qd):
        n[0] += 1
        return [0.5, 0.5]

    traj = arm().simulate(0.02, output_every=0.01, controller=count)
    assert n[0] == traj.stats["steps"] + 1


def test_controller_errors_end_the_run_and_propagate():
    sim = arm()
    with pytest.raises(ZeroDivisionError):
        sim.simulate(0.02, controller=lambda t, q, qd: [1 / 0, 0])
    with pytest.raises(softrod.InputError, match=r"controller's u must have shape \(2,\)"):
        sim.simulate(0.02, controller=lambda t, q, qd: [1.0, 2.0, 3.0])
    with pytest.raises(softrod.InputError, match="cannot push"):
        sim.simulate(0.02, controller=lambda t, q, qd: [1.0, -2.0])
    with pytest.raises(softrod.InputError, match="control_every"):
        sim.simulate(0.02, controller=lambda t, q, qd: [1.0, 2.0], control_every=0.0)
    # The simulation is still usable.
    assert sim.simulate(0.01).status == "completed"


def test_step_without_inputs_follows_the_scheduled_tensions():
    """Steps of 10 ms with the scheduled tensions reach the simulated state
    (each step restarts the integrator, so agreement is to tolerance)."""
    tol = 1e-8
    sim = arm((1.0, 0.0))
    sim.settings = softrod.Settings(**TIGHT)
    st = sim.initial()
    for _ in range(3):
        st = sim.step(st, 0.01)
    want = sim.simulate(0.03, output_every=0.03)
    assert np.abs(st.q - want.q[-1]).max() < tol
    with pytest.raises(softrod.InputError, match="state.q must have shape"):
        sim.step(softrod.State(0.0, np.zeros(3), np.zeros(3)), 0.01)
    with pytest.raises(softrod.InputError, match="step length"):
        sim.step(st, -1.0)
