"""Pickling softrod.Simulation (for Ray and multiprocessing) and the envs.

A pickle holds the scene text, the settings, the initial state and the
held tensions; a loaded copy must continue bit for bit as the original:
the same steps, the same runs (compared with the original itself, which
is the independent reference here: the claim is identity)."""

from __future__ import annotations

import multiprocessing
import pickle

import numpy as np
import pytest

import softrod
from conftest import EXAMPLES, rod

REACH = EXAMPLES / "cable_planar_arm.toml"


def steps(sim, n=5, dt=0.02):
    """n steps under varying tensions from the initial state: (q, q̇) each."""
    st = sim.initial()
    out = []
    for k in range(n):
        u = np.full(sim.n_cables, 0.5 * (k + 1)) if sim.n_cables else None
        st = sim.step(st, dt, u)
        out.append((st.q.copy(), st.qdot.copy()))
    return out


def assert_same_runs(a, b, duration=0.05):
    assert a.q_names == b.q_names
    for x, y in zip(a.initial_state(), b.initial_state()):
        np.testing.assert_array_equal(x, y)
    sa, sb = a.settings, b.settings
    for k in ("integrator", "rtol", "atol", "dt", "output_every"):
        assert getattr(sa, k) == getattr(sb, k), k
    for (qa, va), (qb, vb) in zip(steps(a), steps(b)):
        np.testing.assert_array_equal(qa, qb)
        np.testing.assert_array_equal(va, vb)
    ta, tb = a.simulate(duration), b.simulate(duration)
    np.testing.assert_array_equal(ta.t, tb.t)
    np.testing.assert_array_equal(ta.q, tb.q)
    np.testing.assert_array_equal(ta.qdot, tb.qdot)


@pytest.mark.parametrize(
    "build",
    [
        lambda: softrod.Simulation.from_file(REACH),
        lambda: softrod.Simulation.from_file(EXAMPLES / "arm_pushes_box.toml"),
        lambda: softrod.Simulation.from_toml(open(EXAMPLES / "arm_with_payload.toml").read()),
        lambda: softrod.Simulation.from_dict(
            {"rod": [{"name": "a", "length": 0.3, "pieces": 3, "section": {"shape": "circle", "radius": 0.01},
                      "material": {"density": 1000.0, "young": 1e6, "poisson": 0.5}}],
             "world": {"gravity": [0.0, 0.0, -9.81]}}),
        lambda: softrod.Simulation(rods=[rod(pieces=4)], gravity=[0.0, 0.0, -9.81]),
    ],
    ids=["from_file", "bodies_and_contact", "from_toml", "from_dict", "rods"],
)
def test_round_trip_continues_bit_for_bit(build):
    sim = build()
    copy = pickle.loads(pickle.dumps(sim))
    assert isinstance(copy, softrod.Simulation)
    assert copy.warnings == sim.warnings and copy.duration == sim.duration
    assert_same_runs(sim, copy)


def test_settings_initial_state_and_tensions_travel():
    sim = softrod.Simulation.from_file(REACH)
    sim.settings = softrod.Settings(integrator="radau5", rtol=1e-5, dt=1e-3, output_every=0.01)
    q0, qd0 = sim.initial_state()
    rng = np.random.default_rng(3)
    sim.set_initial_state(q0 + 0.01 * rng.standard_normal(q0.size), 0.1 * rng.standard_normal(q0.size))
    sim.step(sim.initial(), 0.01, [1.0, 2.0])  # holds u = (1, 2)
    copy = pickle.loads(pickle.dumps(sim))
    assert copy.settings.integrator == "radau5" and copy.settings.rtol == 1e-5
    assert_same_runs(sim, copy)
    # The held tensions are part of the state (what forward dynamics with
    # the inputs sees is the same) — and a copy of a copy is the same again.
    again = pickle.loads(pickle.dumps(copy))
    assert_same_runs(copy, again)


def _run_in_worker(blob):
    sim = pickle.loads(blob)
    return [q for q, _ in steps(sim)]


def test_a_pickled_simulation_runs_in_another_process_bit_for_bit():
    sim = softrod.Simulation.from_file(REACH)
    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: nothing shared
    with ctx.Pool(1) as pool:
        remote = pool.apply(_run_in_worker, (pickle.dumps(sim),))
    for (q, _), r in zip(steps(sim), remote):
        np.testing.assert_array_equal(q, r)


def test_unpicklable_state_is_refused_clearly():
    with pytest.raises(softrod.InputError, match="version"):
        softrod.Simulation._from_state({"version": 99})
    state = softrod.Simulation.from_file(REACH).__reduce__()[1][0]
    state["tensions"] = [1.0]
    with pytest.raises(softrod.InputError, match="tensions"):
        softrod.Simulation._from_state(state)


def test_envs_pickle_and_continue_bit_for_bit():
    se = pytest.importorskip("softrod.envs")
    for make in (se.reach_env, se.track_env):
        env = make()
        env.reset(seed=4)
        rng = np.random.default_rng(0)
        for _ in range(3):
            env.step(env.action_space.sample())
        copy = pickle.loads(pickle.dumps(env))
        for _ in range(4):
            a = rng.uniform(0.0, 3.0, env.action_space.shape)
            r1, r2 = env.step(a), copy.step(a)
            np.testing.assert_array_equal(r1[0], r2[0])
            assert r1[1:4] == r2[1:4]
        o1, _ = env.reset()
        o2, _ = copy.reset()
        np.testing.assert_array_equal(o1, o2)  # the same generator state
