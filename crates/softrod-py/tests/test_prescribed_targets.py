"""Prescribed-joint targets as inputs (``Simulation.step(...,
prescribed_targets=...)``, ``BatchStepper``, the envs' actions).

Checked against closed forms of the commanded profile (PT1 of
softrod.control.targets: the cubic Hermite from the position and rate at
the period's start to the target at rest at its end), against a rigid
link's equation of motion about its hinge (the drive's torque), against
stepping copies one by one (bit for bit) and against Gymnasium's checker.
"""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest

import softrod

# A clamped rod (a model needs one) beside a rigid link hinged to the world
# on a prescribed revolute joint about world y: mass m, centre of mass at
# ell along the link's x, inertia Ic about it.
M, ELL, IC_YY, G = 0.2, 0.15, 3.0e-4, 9.81
LINK = f"""
[world]
gravity = [0.0, 0.0, -{G}]

[[rod]]
name = "post"
length = 0.1
pieces = 1
strains = ["ky"]
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}

[[body]]
name = "link"
parent = "world"
base = {{ position = [0.5, 0.0, 0.0] }}
joint = {{ type = "revolute", axis = [0, 1, 0], prescribed = {{ times = [0.0], values = [0.1], bounds = [-1.0, 1.0] }} }}
mass = {M}
inertia = [2.0e-4, {IC_YY}, 2.0e-4]
center_of_mass = [{ELL}, 0.0, 0.0]

[run]
duration = 1.0
"""


def link_sim():
    return softrod.Simulation.from_toml(LINK)


def smoothstep(x0, x1, h, tau):
    """The profile from rest (PT1 with v0 = 0): value, rate, acceleration
    at tau in [0, h]."""
    s = tau / h
    return (
        x0 + (x1 - x0) * (3 * s**2 - 2 * s**3),
        (x1 - x0) * 6 * s * (1 - s) / h,
        (x1 - x0) * (6 - 12 * s) / h**2,
    )


def test_the_joint_follows_the_profile_and_ends_at_the_target_at_rest():
    sim = link_sim()
    st = sim.initial()
    h = 0.05
    x0 = 0.1
    for k, target in enumerate([0.5, -0.2, 0.9]):
        t0 = k * h
        st = sim.step(st, h, prescribed_targets=[target])
        assert np.array_equal(sim.prescribed_targets, [target])
        for tau in np.linspace(0.0, h, 7):
            x, v = sim.prescribed_state(t0 + tau)
            xe, ve, _ = smoothstep(x0, target, h, tau)
            assert abs(x[0] - xe) < 1e-14, (tau, x[0], xe)
            assert abs(v[0] - ve) < 1e-12, (tau, v[0], ve)
        x, v = sim.prescribed_state(t0 + h)
        assert abs(x[0] - target) < 1e-15 and abs(v[0]) < 1e-12
        # Held at rest afterwards.
        x, v = sim.prescribed_state(t0 + 3 * h)
        assert x[0] == target and v[0] == 0.0
        x0 = target
    sim.reset_prescribed()
    assert sim.prescribed_targets is None
    assert sim.prescribed_state(1.0)[0][0] == 0.1


def test_the_transition_starts_with_the_rate_of_the_motion_in_force():
    # C1 at the period's start: from a scene sinusoid, the cubic's rate
    # at t0 is the sinusoid's there; its value at the end the target.
    text = LINK.replace(
        "prescribed = { times = [0.0], values = [0.1], bounds = [-1.0, 1.0] }",
        "prescribed = { sine = { amplitude = 0.3, frequency = 2.0 }, bounds = [-1.0, 1.0] }",
    )
    assert text != LINK
    sim = softrod.Simulation.from_toml(text)
    t0, h = 0.1, 0.04
    w = 2 * np.pi * 2.0
    q0, qd0 = sim.initial_state()
    sim.step(softrod.State(t0, q0, qd0), h, prescribed_targets=[0.25])
    x, v = sim.prescribed_state(t0)
    assert abs(x[0] - 0.3 * np.sin(w * t0)) < 1e-15
    assert abs(v[0] - 0.3 * w * np.cos(w * t0)) < 1e-12
    x, v = sim.prescribed_state(t0 + h)
    assert abs(x[0] - 0.25) < 1e-15 and abs(v[0]) < 1e-12


def test_the_drive_torque_is_the_links_equation_of_motion():
    # The link about its hinge: I θ̈ = τ + (moment of gravity), with
    # I = Ic + m ℓ² and the centre of mass at R_y(θ)(ℓ, 0, 0) =
    # (ℓ cos θ, 0, −ℓ sin θ): gravity's moment about +y is m g ℓ cos θ, so
    # τ = I θ̈ − m g ℓ cos θ along the profile.
    sim = link_sim()
    h = 0.05
    st = sim.initial()
    q, qd = st.q, st.qdot
    sim.step(st, h, prescribed_targets=[0.7])
    inertia = IC_YY + M * ELL**2
    for tau in np.linspace(0.0, h, 9):
        th, _, thdd = smoothstep(0.1, 0.7, h, tau)
        expected = inertia * thdd - M * G * ELL * np.cos(th)
        f = sim.prescribed_forces(tau, q, qd)
        assert abs(f[0] - expected) < 1e-10 * max(1.0, abs(expected)), (tau, f[0], expected)


def test_bad_targets_raise_naming_the_coordinate():
    sim = link_sim()
    st = sim.initial()
    with pytest.raises(softrod.InputError, match=r"link\.joint\.theta.*finite"):
        sim.step(st, 0.05, prescribed_targets=[np.nan])
    with pytest.raises(softrod.InputError, match=r"link\.joint\.theta.*outside.*bounds"):
        sim.step(st, 0.05, prescribed_targets=[1.5])
    with pytest.raises(softrod.InputError, match="prescribed_targets"):
        sim.step(st, 0.05, prescribed_targets=[0.1, 0.2])
    # Nothing was commanded by the refused calls.
    assert sim.prescribed_targets is None
    plain = softrod.Simulation.from_file(_reach_scene())
    with pytest.raises(softrod.InputError, match="no prescribed joint"):
        plain.step(plain.initial(), 0.05, [0.0, 0.0], prescribed_targets=[0.1])
    with pytest.raises(softrod.InputError, match="no actuated joint"):
        plain.step(plain.initial(), 0.05, [0.0, 0.0], joint_forces=[0.1])


def _reach_scene():
    se = pytest.importorskip("softrod.envs")
    return se.REACH_SCENE


def test_joint_force_errors_name_the_joint():
    text = LINK.replace(
        "prescribed = { times = [0.0], values = [0.1], bounds = [-1.0, 1.0] }",
        "actuator = { force = 0.0, max_force = 1.0 }",
    )
    sim = softrod.Simulation.from_toml(text)
    assert sim.joint_input_names == ["link.joint.theta"]
    with pytest.raises(softrod.InputError, match=r"joint_forces\[0\] \(link\.joint\.theta\)"):
        sim.step(sim.initial(), 0.05, joint_forces=[np.inf])


def swing_sims(n):
    se = pytest.importorskip("softrod.envs")
    sims = []
    for i in range(n):
        s = softrod.Simulation.from_file(se.SWING_REACH_SCENE)
        s.settings = s.settings.replace(rtol=se.TASK_RTOL)
        sims.append(s)
    return sims


def test_batched_targets_equal_single_steps_bit_for_bit():
    n, steps, dt = 3, 4, 0.05
    rng = np.random.default_rng(4)
    singles = swing_sims(n)
    stepper = softrod.BatchStepper(swing_sims(n), threads=2)
    assert stepper.n_prescribed == 1
    q0, qd0 = singles[0].initial_state()
    q = np.tile(q0, (n, 1))
    qd = np.tile(qd0, (n, 1))
    qs, qds = q.copy(), qd.copy()
    for k in range(steps):
        u = rng.uniform(0.0, 3.0, (n, 2))
        p = rng.uniform(-0.3, 0.3, (n, 1))
        q, qd, errors = stepper.step(k * dt, q, qd, u, dt, prescribed_targets=p)
        assert errors == [None] * n
        for i, s in enumerate(singles):
            st = s.step(softrod.State(k * dt, qs[i], qds[i]), dt, u[i], prescribed_targets=p[i])
            qs[i], qds[i] = st.q, st.qdot
        assert np.array_equal(q, qs) and np.array_equal(qd, qds)
        assert np.array_equal(stepper.prescribed_targets, p)
    # The drive moved the arm.
    assert np.max(np.abs(q - q0)) > 1e-3
    stepper.reset_prescribed(1)
    assert np.isnan(stepper.prescribed_targets[1, 0])
    with pytest.raises(softrod.InputError, match=r"prescribed_targets\[2\]\[0\] \(arm\.joint\.theta\)"):
        stepper.step(0.0, q, qd, np.zeros((n, 2)), dt,
                     prescribed_targets=np.array([[0.0], [0.0], [0.5]]))
    with pytest.raises(softrod.InputError, match="shape"):
        stepper.step(0.0, q, qd, np.zeros((n, 2)), dt, prescribed_targets=np.zeros((n, 2)))


def test_a_pickle_keeps_the_held_joint_forces_and_the_targets():
    text = LINK.replace(
        'name = "post"\nlength = 0.1',
        'name = "post"\nlength = 0.1\njoint = { type = "revolute", axis = [1, 0, 0], '
        'stiffness = 0.5, actuator = { force = 0.0, max_force = 1.0 } }',
    )
    assert text != LINK
    sim = softrod.Simulation.from_toml(text)
    st = sim.step(sim.initial(), 0.05, [], joint_forces=[0.2], prescribed_targets=[0.4])
    loaded = pickle.loads(pickle.dumps(sim))
    assert np.array_equal(loaded.prescribed_targets, [0.4])
    state = pickle.loads(pickle.dumps(sim)).__reduce__()[1][0]
    assert state["joint_forces"] == [0.2]
    # Both continue the held drive the same way, bit for bit.
    a = sim.step(st, 0.05, [])
    b = loaded.step(st, 0.05, [])
    assert np.array_equal(a.q, b.q) and np.array_equal(a.qdot, b.qdot)
    assert np.array_equal(sim.prescribed_state(0.07)[0], loaded.prescribed_state(0.07)[0])


def test_an_env_needs_target_bounds():
    se = pytest.importorskip("softrod.envs")
    text = open(se.SWING_REACH_SCENE).read().replace(", bounds = [-0.3, 0.3]", "")
    sim = softrod.Simulation.from_toml(text)
    with pytest.raises(softrod.InputError, match=r"arm\.joint\.theta.*joint\.prescribed\.bounds"):
        se.RodEnv(sim, se.ReachTask())


def test_swing_reach_env_actions_and_checker():
    gymnasium = pytest.importorskip("gymnasium")
    se = pytest.importorskip("softrod.envs")
    env = gymnasium.make("softrod/SwingReach-v0")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # unbounded observation boxes
        from gymnasium.utils.env_checker import check_env

        check_env(env.unwrapped, skip_render_check=True)
    raw = env.unwrapped
    assert raw.action_space.shape == (3,)
    assert np.array_equal(raw.action_space.low, [0.0, 0.0, -0.3])
    assert np.array_equal(raw.action_space.high, [3.0, 3.0, 0.3])
    assert "prescribed" in raw.observe
    obs, info = env.reset(seed=1)
    obs, r, term, trunc, info = env.step(np.array([0.0, 0.0, 0.5]))
    assert info["action_clipped"]
    sl = raw.observation_slices["prescribed"]
    assert abs(obs[sl][0] - 0.3) < 1e-15
    with pytest.raises(softrod.InputError, match=r"prescribed-joint targets \(arm\.joint\.theta\)"):
        env.step(np.array([0.0, 0.0, np.nan]))
    strict = se.swing_reach_env(action_policy="reject")
    strict.reset(seed=0)
    with pytest.raises(softrod.InputError, match=r"outside \[-0\.3, 0\.3\].*arm\.joint\.theta"):
        strict.step(np.array([0.0, 0.0, -0.31]))


def test_swing_reach_targets_are_equilibria_of_their_constant_action():
    # The task's target is the statics' tip (Newton) under the drawn base
    # angle and tensions; started there with the drive held at the angle,
    # the integrated dynamics under that constant action stays there.
    se = pytest.importorskip("softrod.envs")
    env = se.swing_reach_env()
    env.reset(seed=3)
    task = env.task
    assert abs(task.target_prescribed[0]) > 0.05
    env.sim.hold_prescribed(task.target_prescribed)
    st = env.sim.statics(tensions=task.target_tensions)
    env.q, env.qdot = np.array(st.q), np.zeros(env.n_dof)
    a = np.concatenate([task.target_tensions, task.target_prescribed])
    for _ in range(20):
        obs, r, term, trunc, info = env.step(a)
        assert not term
        assert info["distance"] < 1e-6 * env.length, info["distance"]


def test_batched_swing_env_equals_single_envs():
    se = pytest.importorskip("softrod.envs")
    n = 2
    venv = se.swing_reach_vector_env(n, threads=2)
    singles = [se.swing_reach_env() for _ in range(n)]
    obs, _ = venv.reset(seed=5)
    for i, e in enumerate(singles):
        o, _ = e.reset(seed=5 + i)
        assert np.array_equal(o, obs[i])
    rng = np.random.default_rng(0)
    for _ in range(4):
        acts = np.column_stack([rng.uniform(0, 3, (n, 2)), rng.uniform(-0.4, 0.4, n)])
        obs, rew, term, trunc, _ = venv.step(acts)
        for i, e in enumerate(singles):
            o, r, te, tr, _ = e.step(acts[i])
            assert np.array_equal(o, obs[i]) and r == rew[i] and te == term[i]
