"""Stepped, controlled, batched and environment runs carry the contact state
(docs/theory-contact.md CT5 friction anchors, CT15 raised stiffnesses) from
accepted step to accepted step as ``simulate`` does, and start an episode
fresh when asked.

The physics check is Coulomb's law on a rod lying across a 20° incline with
mu = 0.5 > tan 20°: it must stay where it was put, its weight carried by
sticking contacts (their forces sum to m g). Without the commit the anchors
never form and the rod slid 1.7 cm in 0.1 s (g sin 20° t² / 2). The other
checks compare paths that must agree bit for bit: two ways of stepping, a
batch against its copies' own steps, an episode against a fresh one.
"""

from __future__ import annotations

import numpy as np
import pytest

import softrod
from test_contact_reset import INCLINE

_A = np.radians(20.0)
_DOWNHILL = np.array([np.cos(_A), 0.0, -np.sin(_A)])  # along the slope, down (normal (sin, 0, cos))
_MASS = np.pi * 0.01**2 * 0.2 * 1000.0  # the rod's: r = 0.01, L = 0.2, rho = 1000


def tip(sim, q):
    return sim.tip_pose(0, q)[:3, 3]


def steps(sim, state, k, dt=0.005, u=None):
    for _ in range(k):
        state = sim.step(state, dt, u)
    return state


def test_steps_stick_where_coulomb_holds_and_the_contacts_carry_the_weight():
    sim = softrod.Simulation.from_toml(INCLINE)
    q0, qd0 = sim.initial_state()
    s = steps(sim, softrod.State(0.0, q0, qd0), 20)
    assert np.linalg.norm(tip(sim, s.q) - tip(sim, q0)) < 1e-4
    # contacts() reports the state the steps committed: every contact
    # sticks, and together they carry the rod's weight.
    cs = sim.contacts(s.q, s.qdot, t=s.t)
    assert cs and all(c.sticking for c in cs)
    total = sum(c.force for c in cs)
    np.testing.assert_allclose(total, [0.0, 0.0, _MASS * 9.81], rtol=0, atol=1e-6 * _MASS * 9.81)
    # Along the slope they hold m g sin 20°, more than zero: friction.
    assert float(np.dot(total, -_DOWNHILL)) == pytest.approx(_MASS * 9.81 * np.sin(_A), rel=1e-6)


def test_steps_with_and_without_tensions_share_one_contact_state():
    """The step with ``u`` integrates another workspace than the one
    without; the contact state lives with the simulation, so mixing them
    gives the steps of one path bit for bit."""
    a = softrod.Simulation.from_toml(INCLINE)
    b = softrod.Simulation.from_toml(INCLINE)
    q0, qd0 = a.initial_state()
    sa = sb = softrod.State(0.0, q0, qd0)
    for k in range(12):
        sa = a.step(sa, 0.005)
        sb = b.step(sb, 0.005, None if k % 2 else np.zeros(0))
        np.testing.assert_array_equal(sa.q, sb.q)
        np.testing.assert_array_equal(sa.qdot, sb.qdot)


def test_reset_contact_starts_an_episode_as_a_fresh_simulation():
    fresh = softrod.Simulation.from_toml(INCLINE)
    q0, qd0 = fresh.initial_state()
    want = steps(fresh, softrod.State(0.0, q0, qd0), 8)
    sim = softrod.Simulation.from_toml(INCLINE)
    # An earlier episode launched down the slope: it slides, then sticks
    # elsewhere, leaving anchors that are not the initial state's.
    first = steps(sim, softrod.State(0.0, q0, qd0 + _shove_velocity(sim)), 8)
    assert np.linalg.norm(tip(sim, first.q) - tip(sim, q0)) > 1e-3
    stale = steps(sim, softrod.State(0.0, q0, qd0), 8)
    assert not np.array_equal(stale.q, want.q)  # the old anchors pull
    sim.reset_contact()
    got = steps(sim, softrod.State(0.0, q0, qd0), 8)
    np.testing.assert_array_equal(got.q, want.q)
    np.testing.assert_array_equal(got.qdot, want.qdot)


def _shove_velocity(sim):
    """Joint rates that move the tip at 0.2 m/s down the slope (the
    least-squares rates through the tip's Jacobian by central differences)."""
    q0 = sim.initial_state()[0]
    h = 1e-6
    jac = np.empty((3, sim.n_dof))
    for i in range(sim.n_dof):
        dq = np.zeros(sim.n_dof)
        dq[i] = h
        jac[:, i] = (tip(sim, q0 + dq) - tip(sim, q0 - dq)) / (2 * h)
    return np.linalg.lstsq(jac, 0.2 * _DOWNHILL, rcond=None)[0]


def test_a_controlled_run_sticks_and_leaves_its_contact_state():
    sim = softrod.Simulation.from_toml(INCLINE)
    q0, _ = sim.initial_state()
    tr = sim.simulate(controller=lambda t, q, qd: np.zeros(0))
    assert np.linalg.norm(tr.tip_position[-1] - tip(sim, q0)) < 1e-4
    cs = sim.contacts(tr.q[-1], tr.qdot[-1], t=tr.t[-1])
    assert cs and all(c.sticking for c in cs)
    np.testing.assert_allclose(
        sum(c.force for c in cs), [0.0, 0.0, _MASS * 9.81], rtol=0, atol=1e-6 * _MASS * 9.81
    )
    # It started fresh: the same run again repeats it bit for bit.
    again = sim.simulate(controller=lambda t, q, qd: np.zeros(0))
    np.testing.assert_array_equal(again.q, tr.q)


def test_batch_copies_carry_their_own_contact_state_and_reset_one():
    sims = [softrod.Simulation.from_toml(INCLINE) for _ in range(3)]
    singles = [softrod.Simulation.from_toml(INCLINE) for _ in range(3)]
    q0, qd0 = sims[0].initial_state()
    shove = _shove_velocity(sims[0])
    qd_start = np.array([qd0, qd0 + shove, qd0 + 0.5 * shove])
    batch = softrod.BatchStepper(sims, threads=2)
    q = np.array([q0] * 3)
    qd = qd_start.copy()
    t = np.zeros(3)
    states = [softrod.State(0.0, q0, v) for v in qd_start]
    u = np.zeros((3, 0))
    for _ in range(8):
        q, qd, errors = batch.step(t, q, qd, u, 0.005)
        assert errors == [None] * 3
        t = t + 0.005
        states = [s.step(st, 0.005) for s, st in zip(singles, states)]
        for i in range(3):
            np.testing.assert_array_equal(q[i], states[i].q)
            np.testing.assert_array_equal(qd[i], states[i].qdot)
    # Copy 1 starts over from the initial state; a fresh simulation's steps
    # are the reference.
    batch.reset_contact(1)
    fresh = softrod.Simulation.from_toml(INCLINE)
    ref = softrod.State(0.0, q0, qd0)
    qb = np.array([q0] * 3)
    qdb = np.array([qd0] * 3)
    tb = np.zeros(3)
    for _ in range(4):
        qb, qdb, _ = batch.step(tb, qb, qdb, u, 0.005, [False, True, False])
        tb = tb + 0.005
        ref = fresh.step(ref, 0.005)
    np.testing.assert_array_equal(qb[1], ref.q)
    with pytest.raises(softrod.InputError, match="out of range"):
        batch.reset_contact(3)


def test_an_env_reset_forgets_the_last_episodes_contact_state():
    """Push-v0's arm–box friction (mu 0.4): under 1 N on the first cable a
    contact sticks after 7 control periods. After ``reset`` the env's
    simulation must report, at that same state, the contact forces of a
    simulation that never ran (no anchor), and the episode must repeat."""
    se = pytest.importorskip("softrod.envs")
    env = se.push_env()

    def episode():
        obs, _ = env.reset(seed=3)
        out = [obs]
        for _ in range(7):
            out.append(env.step(np.array([1.0, 0.0]))[0])
        return np.array(out)

    first = episode()
    q, qd, t = env.q.copy(), env.qdot.copy(), env.t
    assert any(c.sticking for c in env.sim.contacts(q, qd, t=t))
    env.reset(seed=3)
    fresh = se.push_env().sim.contacts(q, qd, t=t)
    got = env.sim.contacts(q, qd, t=t)
    assert [c.force.tobytes() for c in got] == [c.force.tobytes() for c in fresh]
    assert not any(c.sticking for c in got)
    np.testing.assert_array_equal(episode(), first)


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_batched_push_env_equals_sync_vector_env_across_resets(mode):
    """Each copy's contact state is reset with its episode (the batched
    env's autoreset calls BatchStepper.reset_contact): the batched env
    stays equal to Gymnasium's SyncVectorEnv over the same envs, bit for
    bit, across episodes that end at different steps."""
    se = pytest.importorskip("softrod.envs")
    from gymnasium.vector import SyncVectorEnv

    fns = [lambda k=k: se.push_env(episode_steps=k) for k in (5, 8)]
    sync = SyncVectorEnv(fns, autoreset_mode=mode)
    batched = se.BatchedVectorEnv(fns, threads=2, autoreset_mode=mode)
    np.testing.assert_array_equal(sync.reset(seed=2)[0], batched.reset(seed=2)[0])
    a = np.array([[1.0, 0.0], [1.0, 0.5]])
    for _ in range(14):
        for x, y in zip(sync.step(a)[:4], batched.step(a)[:4]):
            np.testing.assert_array_equal(x, y)
