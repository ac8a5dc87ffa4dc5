"""softrod.envs (Gymnasium environments) and softrod.BatchStepper.

The batched physics is checked against the single copies' own
``Simulation.step`` (bit for bit), the batched vector env against
Gymnasium's own SyncVectorEnv over the same envs (its autoreset semantics),
the envs against Gymnasium's checker, and the Reach task's targets against
the equilibrium the statics solver finds under a constant action held long
enough (an independent path: integration vs Newton).
"""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

import softrod

gymnasium = pytest.importorskip("gymnasium")
se = pytest.importorskip("softrod.envs")

RK4_BLOWUP = ('[run]\nmode = "dynamics"', '[run]\nmode = "dynamics"\nintegrator = "rk4"\ndt = 0.05')


def diverging_sim():
    """The reach arm with fixed-step RK4 at the control period: unstable
    on its stiff shear modes, so the first step blows up."""
    text = open(se.REACH_SCENE).read().replace(*RK4_BLOWUP)
    return softrod.Simulation.from_toml(text, name="reach_rk4.toml")


def test_core_package_imports_neither_gymnasium_nor_ray():
    code = (
        "import sys, softrod, softrod.distributed\n"
        "bad = [m for m in ('gymnasium', 'ray') if m in sys.modules]\n"
        "assert not bad, bad\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


ENV_IDS = ["softrod/Reach-v0", "softrod/Track-v0", "softrod/ReachAround-v0", "softrod/Push-v0"]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_registered_envs_pass_gymnasiums_checker(env_id):
    from gymnasium.utils.env_checker import check_env

    env = gymnasium.make(env_id)
    with warnings.catch_warnings():
        # The checker's advice (normalized actions, finite observation
        # bounds) is a recommendation; the spaces are documented as they are.
        warnings.simplefilter("ignore")
        check_env(env.unwrapped)
    obs, info = env.reset(seed=1)
    assert env.observation_space.contains(obs)
    for _ in range(3):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs)
        assert np.isfinite(reward) and not terminated
    env.close()


def test_stable_baselines3_checker_where_installed():
    sb3 = pytest.importorskip("stable_baselines3.common.env_checker")
    for make in (se.reach_env, se.track_env, se.reach_around_env, se.push_env):
        sb3.check_env(make(), warn=False)


def test_the_shipped_scenes_load_without_warnings():
    for path in (se.REACH_SCENE, se.TRACK_SCENE, se.REACH_AROUND_SCENE, se.PUSH_SCENE):
        sim = softrod.Simulation.from_file(path)
        assert sim.warnings == [] and sim.n_cables in (2, 4)


def test_spaces_bounds_and_observation_layout():
    env = se.reach_env(max_tension=[2.0, 4.0])
    assert env.action_space.low.tolist() == [0.0, 0.0]
    assert env.action_space.high.tolist() == [2.0, 4.0]
    n = env.n_dof
    assert env.observation_slices == {
        "strains": slice(0, n),
        "strain_rates": slice(n, 2 * n),
        "tip_position": slice(2 * n, 2 * n + 3),
        "target": slice(2 * n + 3, 2 * n + 6),
    }
    obs, _ = env.reset(seed=0)
    q0, _ = env.sim.initial_state()
    np.testing.assert_array_equal(obs[env.observation_slices["strains"]], q0)
    tip = env.sim.tip_pose(0, q0)[:3, 3]
    np.testing.assert_array_equal(obs[env.observation_slices["tip_position"]], tip)
    assert se.reach_env().action_space.high.tolist() == [se.DEFAULT_MAX_TENSION] * 2


def test_max_tension_from_the_scene_file_where_it_names_one(tmp_path):
    """The scene's [[cable]] max_tension bounds a cable the env's argument
    leaves open (read from the file; the key is the scene contract's)."""
    from softrod.envs._core import _bounds, _scene_max_tensions

    path = tmp_path / "arm.toml"
    text = open(se.REACH_SCENE).read()
    path.write_text(text.replace("tension = 0.0", "tension = 0.0\nmax_tension = 1.5", 1))
    found = _scene_max_tensions(path)
    assert found == [1.5, None]
    assert _bounds(2, None, found).tolist() == [1.5, se.DEFAULT_MAX_TENSION]
    assert _bounds(2, 4.0, found).tolist() == [4.0, 4.0]
    assert _scene_max_tensions(se.REACH_SCENE) is None
    with pytest.raises(softrod.InputError, match="positive"):
        _bounds(2, [1.0, -2.0], None)


def test_actions_clip_or_reject_and_nan_raises():
    env = se.reach_env()
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([-1.0, 99.0]))
    assert info["action_clipped"]
    np.testing.assert_array_equal(env.u, [0.0, se.DEFAULT_MAX_TENSION])
    with pytest.raises(softrod.InputError, match="finite"):
        env.step(np.array([np.nan, 1.0]))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.array([1.0, 1.0, 1.0]))
    strict = se.reach_env(action_policy="reject")
    strict.reset(seed=0)
    with pytest.raises(softrod.InputError, match="outside"):
        strict.step(np.array([0.5, 3.5]))


def test_a_scene_without_cables_is_refused():
    sim = softrod.Simulation.from_toml(open(se.REACH_SCENE).read().split("[[cable]]")[0])
    with pytest.raises(softrod.InputError, match="cables"):
        se.RodEnv(sim, se.ReachTask())


def test_diverging_step_terminates_with_a_reason_and_finite_observation():
    env = se.RodEnv(diverging_sim(), se.ReachTask())
    obs0, _ = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(np.array([3.0, 0.0]))
    assert terminated and not truncated
    assert info["termination"].startswith("diverged: ")
    assert np.all(np.isfinite(obs)) and np.isfinite(reward)
    # The last valid state is the one observed.
    np.testing.assert_array_equal(obs, obs0)


def test_seeded_resets_repeat_and_differ():
    a, b = se.track_env(), se.track_env()
    oa, _ = a.reset(seed=7)
    ob, _ = b.reset(seed=7)
    np.testing.assert_array_equal(oa, ob)
    oc, _ = b.reset(seed=8)
    assert not np.array_equal(oa, oc)


def test_reach_target_is_an_equilibrium_of_the_dynamics_under_its_tensions():
    """The target drawn at reset is the statics tip under the drawn tensions
    (Newton on the static residual): started from that equilibrium at rest
    and holding those tensions, the integrated dynamics must stay there."""
    env = se.reach_env()
    env.reset(seed=3)
    u = env.task.target_tensions
    st = env.sim.statics(tensions=u)
    env.q, env.qdot = st.q.copy(), np.zeros(env.n_dof)
    for _ in range(20):  # 1 s
        _, _, terminated, _, info = env.step(u)
        assert not terminated
        assert info["distance"] < 1e-6 * env.length
    # And a different action moves the tip away from it.
    _, _, _, _, info = env.step(env.max_tension - u)
    assert info["distance"] > 1e-4 * env.length


def test_track_target_moves_on_its_circle():
    env = se.track_env()
    env.reset(seed=2)
    task = env.task
    b, a, e1, e2 = task._frame
    L, th = env.length, task.theta
    for t in (0.0, 0.7, 3.1):
        p, v = task.target(t)
        d = p - b
        np.testing.assert_allclose(d @ a, L * np.sin(th) / th, rtol=1e-12)
        np.testing.assert_allclose(np.hypot(d @ e1, d @ e2), L * (1 - np.cos(th)) / th, rtol=1e-12)
        h = 1e-6  # central difference of the position
        fd = (task.target(t + h)[0] - task.target(t - h)[0]) / (2 * h)
        np.testing.assert_allclose(v, fd, rtol=1e-6, atol=1e-12)


def test_batch_stepper_equals_single_steps_bit_for_bit():
    sims = [softrod.Simulation.from_file(se.REACH_SCENE) for _ in range(5)]
    sims.append(diverging_sim())
    rng = np.random.default_rng(11)
    n = sims[0].n_dof
    q0, qd0 = sims[0].initial_state()
    q = q0 + 0.2 * rng.standard_normal((6, n))
    qd = 0.1 * rng.standard_normal((6, n))
    u = rng.uniform(0.0, 3.0, (6, 2))
    t = np.linspace(0.0, 1.0, 6)
    batch = softrod.BatchStepper(sims, threads=2)
    q1, qd1, errors = batch.step(t, q, qd, u, 0.05)
    for i, sim in enumerate(sims):
        try:
            s = sim.step(softrod.State(t[i], q[i], qd[i]), 0.05, u[i])
        except softrod.SimulationError as e:
            assert errors[i] == str(e)
            np.testing.assert_array_equal(q1[i], q[i])
            continue
        assert errors[i] is None
        np.testing.assert_array_equal(q1[i], s.q)
        np.testing.assert_array_equal(qd1[i], s.qdot)
    # Inactive copies are passed through untouched.
    q2, _, errors2 = batch.step(t, q, qd, u, 0.05, [False] * 6)
    np.testing.assert_array_equal(q2, q)
    assert errors2 == [None] * 6
    with pytest.raises(softrod.InputError, match=r"u\[2\]"):
        bad = u.copy()
        bad[2, 1] = -1.0
        batch.step(t, q, qd, bad, 0.05)
    with pytest.raises(softrod.InputError, match="shape"):
        batch.step(t, q[:3], qd, u, 0.05)


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_batched_vector_env_equals_sync_vector_env(mode):
    from gymnasium.vector import SyncVectorEnv

    # Episodes of different lengths and one copy that diverges, so resets
    # happen at different steps in different copies.
    fns = [lambda k=k: se.reach_env(episode_steps=k) for k in (3, 5, 4)]
    fns.append(lambda: se.RodEnv(diverging_sim(), se.ReachTask(), episode_steps=6))
    sync = SyncVectorEnv(fns, autoreset_mode=mode)
    batched = se.BatchedVectorEnv(fns, threads=2, autoreset_mode=mode)
    o1, _ = sync.reset(seed=5)
    o2, _ = batched.reset(seed=5)
    np.testing.assert_array_equal(o1, o2)
    rng = np.random.default_rng(0)
    ends = 0
    for _ in range(12):
        a = rng.uniform(-0.5, 3.5, (4, 2))  # some outside the box: clipped
        r1, r2 = sync.step(a), batched.step(a)
        for x, y in zip(r1[:4], r2[:4]):
            np.testing.assert_array_equal(x, y)
        i1, i2 = r1[4], r2[4]
        assert sorted(i1) == sorted(i2)
        for key in ("distance", "_distance", "action_clipped", "termination"):
            if key in i1:
                np.testing.assert_array_equal(i1[key], i2[key])
        if mode == "SameStep" and "final_obs" in i1:
            for f1, f2 in zip(i1["final_obs"], i2["final_obs"]):
                np.testing.assert_array_equal(f1, f2)
        ends += int(np.sum(r1[2] | r1[3]))
    assert ends >= 6
    # A partial reset (Gymnasium's reset_mask) resets the same copies.
    mask = np.array([True, False, True, False])
    o1, _ = sync.reset(seed=9, options={"reset_mask": mask.copy()})
    o2, _ = batched.reset(seed=9, options={"reset_mask": mask.copy()})
    np.testing.assert_array_equal(o1, o2)
    a = rng.uniform(0.0, 3.0, (4, 2))
    for x, y in zip(sync.step(a)[:4], batched.step(a)[:4]):
        np.testing.assert_array_equal(x, y)


def test_make_vec_gives_the_batched_env():
    env = gymnasium.make_vec("softrod/Track-v0", num_envs=3, vectorization_mode="vector_entry_point")
    assert isinstance(env, se.BatchedVectorEnv)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (3,) + env.single_observation_space.shape
    obs, rew, term, trunc, _ = env.step(env.action_space.sample())
    assert np.all(np.isfinite(obs)) and rew.shape == (3,)


def test_task_tolerance_keeps_the_tip_near_a_tight_run():
    """The registered tasks integrate at TASK_RTOL (1e-2): over 40 periods
    of random tensions the tip stays within 0.2 mm (3 % of Reach's success
    radius) of the same episode at rtol 1e-9 (docs/envs.md measures ~0.1 mm
    over 1000 periods)."""
    fast, tight = se.reach_env(), se.reach_env(rtol=1e-9)
    assert fast.sim.settings.rtol == se.TASK_RTOL and tight.sim.settings.rtol == 1e-9
    fast.reset(seed=2)
    tight.reset(seed=2)
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(40):
        a = rng.uniform(0.0, 3.0, 2)
        fast.step(a)
        tight.step(a)
        worst = max(worst, float(np.linalg.norm(fast._tip - tight._tip)))
    assert worst < 2e-4, worst
    # rtol=None keeps the scene's own settings.
    scene = softrod.Simulation.from_file(se.REACH_SCENE).settings
    assert se.RodEnv(se.REACH_SCENE, rtol=None).sim.settings.rtol == scene.rtol


def test_substeps_fixed_steps_converge_and_batch_equals_single():
    """``substeps=k``: k fixed steps of the settings' integrator per call.
    Radau IIA's fixed steps approach the tight adaptive step as k grows,
    and a batch with substeps equals the single steps bit for bit."""
    sim = softrod.Simulation.from_file(se.REACH_SCENE)
    sim.settings = softrod.Settings(integrator="radau5", rtol=1e-3)
    tight = softrod.Simulation.from_file(se.REACH_SCENE)
    tight.settings = softrod.Settings(rtol=1e-10, atol=1e-13)
    q0, qd0 = sim.initial_state()
    st = softrod.State(0.0, q0, qd0)
    u = np.array([2.5, 0.0])
    ref = tight.step(st, 0.05, u).q
    errs = [np.max(np.abs(sim.step(st, 0.05, u, substeps=k).q - ref)) for k in (1, 4, 16)]
    assert errs[2] < errs[1] < errs[0], errs
    batch = softrod.BatchStepper([sim, sim.copy()], threads=2)
    qb, qdb, errors = batch.step(0.0, np.array([q0, q0]), np.array([qd0, qd0]),
                                 np.array([u, u[::-1]]), 0.05, substeps=4)
    assert errors == [None, None]
    for i, ui in enumerate((u, u[::-1])):
        s = sim.step(st, 0.05, ui, substeps=4)
        np.testing.assert_array_equal(qb[i], s.q)
        np.testing.assert_array_equal(qdb[i], s.qdot)
    for bad in (0, -1):
        with pytest.raises((softrod.InputError, OverflowError), match="substeps|negative"):
            sim.step(st, 0.05, u, substeps=bad)
    with pytest.raises(softrod.InputError, match="substeps"):
        se.reach_env(substeps=0)
    env = se.reach_env(substeps=2)
    env.reset(seed=0)
    obs, *_ = env.step(np.array([1.0, 0.0]))
    assert np.all(np.isfinite(obs))


def test_reach_around_targets_are_equilibria_in_contact():
    """ReachAround's targets are statics tips with the post in place: a
    target drawn on the post's side presses the arm on it (the statics
    solver's contacts), and started there at rest, holding the target's
    tensions, the integrated dynamics (the same penalty contact) stay at
    the target."""
    env = se.reach_around_env()
    for seed in range(40):
        env.reset(seed=seed)
        u = env.task.target_tensions
        st = env.sim.statics(tensions=u)
        if env.sim.contacts(st.q):
            break
    else:
        pytest.fail("no target in contact with the post in 40 draws")
    assert u[0] > 0  # the cable that bends the arm towards the post (+x)
    free = se.reach_env()  # the same arm and tensions without the post
    tip_free = free.sim.statics(tensions=u).tips["arm"][:3, 3]
    assert np.linalg.norm(tip_free - env.task.target(0.0)[0]) > 1e-3  # the post moved the target
    env.q, env.qdot = st.q.copy(), np.zeros(env.n_dof)
    for _ in range(20):  # 1 s
        obs, _, terminated, _, info = env.step(u)
        assert not terminated and np.all(np.isfinite(obs))
        assert info["in_contact"]
        assert info["distance"] < 1e-4 * env.length, info["distance"]


def test_push_moves_the_box_towards_its_goal():
    env = se.push_env()
    obs, info = env.reset(seed=1)
    sl = env.observation_slices
    box0, goal = obs[sl["body_positions"]].copy(), obs[sl["target"]].copy()
    assert goal[0] - box0[0] >= 0.01 and np.allclose(goal[1:], box0[1:])
    contact = False
    for _ in range(40):  # 2 s pulling the cable on the box's side
        obs, reward, terminated, truncated, info = env.step(np.array([4.0, 0.0]))
        assert np.all(np.isfinite(obs)) and not terminated
        contact |= info["in_contact"]
        box = obs[sl["body_positions"]]
        # info and reward from the same state the observation shows
        assert info["distance"] == pytest.approx(np.linalg.norm(box - goal), rel=1e-12)
        tip = obs[sl["tip_position"]]
        expected = (-info["distance"] / env.length - 0.1 * np.linalg.norm(tip - box) / env.length
                    - 0.01 * np.mean((np.array([4.0, 0.0]) / env.max_tension) ** 2))
        assert reward == pytest.approx(expected, rel=1e-12)
    assert contact
    # The box moved along +x only (its joint), by the joint coordinate.
    assert box[0] - box0[0] > 0.02 and np.allclose(box[1:], box0[1:])
    assert box[0] - box0[0] == pytest.approx(obs[sl["strains"]][-1], rel=1e-9)


def test_contact_tasks_refuse_scenes_without_their_objects():
    with pytest.raises(softrod.InputError, match="body"):
        se.RodEnv(se.REACH_SCENE, se.PushTask())
    with pytest.raises(softrod.InputError, match="obstacle"):
        se.RodEnv(se.REACH_SCENE, se.ReachAroundTask())


def test_env_from_a_config_mapping():
    """The factory RLlib and Ray Tune call with their env_config dict."""
    env = se.make_env_from_config({"task": "push", "episode_steps": 7})
    assert isinstance(env.task, se.PushTask) and env.episode_steps == 7
    assert isinstance(se.make_env_from_config({}).task, se.ReachTask)
    with pytest.raises(softrod.InputError, match="task"):
        se.make_env_from_config({"task": "juggle"})


@pytest.mark.parametrize("which", ["reach_around", "push"])
def test_contact_tasks_terminate_a_diverging_step_without_nan(which):
    """The contact scenes with fixed-step RK4 at the control period (unstable
    on the stiff modes): the first step diverges, the episode ends with the
    reason, the observation and reward stay those of the last valid state."""
    path = se.REACH_AROUND_SCENE if which == "reach_around" else se.PUSH_SCENE
    text = open(path).read().replace(*RK4_BLOWUP)
    assert "rk4" in text
    sim = softrod.Simulation.from_toml(text, name=f"{which}_rk4.toml")
    task = se.ReachAroundTask() if which == "reach_around" else se.PushTask()
    env = se.RodEnv(sim, task)
    obs0, _ = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.high)
    assert terminated and not truncated
    assert info["termination"].startswith("diverged: ")
    assert np.all(np.isfinite(obs)) and np.isfinite(reward)
    np.testing.assert_array_equal(obs, obs0)


# -- joint actuators (issue 29: actions are tensions and/or joint forces) ----

G, LINK_MASS, LINK_COM, LINK_K = 9.81, 0.2, 0.1, 0.2


def link_scene(actuator="{ max_force = 0.5 }", cable=False):
    """A short flexible rod clamped to the world with a link body on an
    actuated revolute joint about y at its tip (spring LINK_K), gravity
    along -z; with ``cable``, one cable along the rod."""
    text = (
        f"[world]\ngravity = [0.0, 0.0, -{G}]\n"
        '[[rod]]\nname = "base"\nlength = 0.2\npieces = 2\nstrains = ["kx", "ky", "kz"]\n'
        'section = { shape = "circle", radius = 0.01 }\n'
        "material = { density = 1000.0, young = 1.0e7, poisson = 0.5, viscosity = 2.0e5 }\n"
        '[[body]]\nname = "link"\nparent = "base"\n'
        f'joint = {{ type = "revolute", axis = [0, 1, 0], stiffness = {LINK_K}, damping = 0.05, '
        f"actuator = {actuator} }}\n"
        f"mass = {LINK_MASS}\ninertia = [1e-4, 1e-4, 1e-4]\n"
        f"center_of_mass = [{LINK_COM}, 0, 0]\n"
    )
    if cable:
        text += (
            '[[cable]]\nrod = "base"\noffset = [0.0, 0.008]\ntension = 0.0\nmax_tension = 2.0\n'
        )
    return softrod.Simulation.from_toml(text, name="link.toml")


def passive_torque(sim, q):
    """The spring's -k theta plus gravity's moment about the joint axis,
    a . (R c x m g), from the link's pose: what a held joint torque must
    balance at rest (the link is the only thing beyond the joint)."""
    pose = sim.body_poses(q)[0]
    r = pose[:3, :3] @ np.array([LINK_COM, 0.0, 0.0])
    a = pose[:3, :3] @ np.array([0.0, 1.0, 0.0])
    return -LINK_K * q[-1] + a @ np.cross(r, np.array([0.0, 0.0, -LINK_MASS * G]))


def test_joint_actuator_action_space_from_the_scene_and_refusals():
    env = se.RodEnv(link_scene(cable=True), se.ReachTask(), observe=["strains", "joint_forces"])
    assert env.n_cables == 1 and env.n_joint_inputs == 1
    np.testing.assert_array_equal(env.action_space.low, [0.0, -0.5])
    np.testing.assert_array_equal(env.action_space.high, [se.DEFAULT_MAX_TENSION, 0.5])
    sl = env.observation_slices["joint_forces"]
    np.testing.assert_array_equal(env.observation_space.low[sl], [-0.5])
    np.testing.assert_array_equal(env.observation_space.high[sl], [0.5])
    # The env's max_force overrides the scene's.
    env2 = se.RodEnv(link_scene(), se.ReachTask(), max_force=0.25)
    np.testing.assert_array_equal(env2.action_space.low, [-0.25])
    # An actuated coordinate without a bound is refused, naming the key.
    with pytest.raises(softrod.InputError, match="max_force"):
        se.RodEnv(link_scene("{ force = 0.0 }"), se.ReachTask())
    # Out of the box: clipped (info says so) or rejected; NaN always raises.
    env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([-1.0, -7.0]))
    assert info["action_clipped"]
    np.testing.assert_array_equal(env.u, [0.0])
    np.testing.assert_array_equal(env.f, [-0.5])
    obs = env._observation()
    np.testing.assert_array_equal(obs[sl], [-0.5])
    with pytest.raises(softrod.InputError, match="joint forces must be finite"):
        env.step(np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match="shape"):
        env.step(np.array([1.0]))
    strict = se.RodEnv(link_scene(), se.ReachTask(), action_policy="reject")
    strict.reset(seed=0)
    with pytest.raises(softrod.InputError, match="outside"):
        strict.step(np.array([0.6]))
    # Simulation.step and BatchStepper check the joint forces too.
    sim = link_scene()
    st = softrod.State(0.0, *sim.initial_state())
    with pytest.raises(softrod.InputError, match="joint_forces"):
        sim.step(st, 0.05, [], joint_forces=[np.inf])
    with pytest.raises(softrod.InputError, match="joint_forces"):
        sim.step(st, 0.05, [], joint_forces=[1.0, 2.0])


def test_held_joint_torque_reaches_the_moment_balance_and_the_statics():
    """A constant torque held over many periods settles where it balances
    the spring and gravity's moment about the joint (checked from the
    link's pose), and where Simulation.statics puts it (Newton on the
    static residual, an independent path)."""
    tau = 0.3
    # A tight tolerance: at rest the step's Newton tolerance is what is left.
    env = se.RodEnv(
        link_scene(), se.ReachTask(), episode_steps=400, control_period=0.05, rtol=1e-8
    )
    env.reset(seed=0)
    for _ in range(300):  # 15 s, ~35 decay times of the slowest mode
        _, _, term, _, _ = env.step(np.array([tau]))
        assert not term
    assert np.max(np.abs(env.qdot)) < 1e-10
    theta = env.q[-1]
    assert abs(theta) > 0.5  # the link swung down (1.32 rad)
    # Residual of the moment balance, relative to the gravity moment m g d.
    assert abs(tau + passive_torque(env.sim, env.q)) < 1e-10 * LINK_MASS * G * LINK_COM
    st = env.sim.statics(joint_forces=[tau])
    np.testing.assert_allclose(env.q, st.q, rtol=0, atol=1e-9)
    # Without the input the statics differ by the torque: the input is used.
    st0 = env.sim.statics(joint_forces=[0.0])
    assert abs(st0.q[-1] - theta) > 0.1


def test_joint_force_batch_equals_single_steps_bit_for_bit():
    sims = [link_scene(cable=True) for _ in range(4)]
    rng = np.random.default_rng(3)
    n = sims[0].n_dof
    q0, _ = sims[0].initial_state()
    q = q0 + 0.05 * rng.standard_normal((4, n))
    qd = 0.1 * rng.standard_normal((4, n))
    u = rng.uniform(0.0, 2.0, (4, 1))
    f = rng.uniform(-0.5, 0.5, (4, 1))
    batch = softrod.BatchStepper(sims, threads=2)
    assert batch.n_joint_inputs == 1
    q1, qd1, errors = batch.step(0.0, q, qd, u, 0.05, joint_forces=f)
    for i, sim in enumerate(sims):
        s = sim.step(softrod.State(0.0, q[i], qd[i]), 0.05, u[i], joint_forces=f[i])
        assert errors[i] is None
        np.testing.assert_array_equal(q1[i], s.q)
        np.testing.assert_array_equal(qd1[i], s.qdot)
    # The force is an input: a different one moves the link differently.
    q2, _, _ = batch.step(0.0, q, qd, u, 0.05, joint_forces=-f)
    assert np.all(q2[:, -1] != q1[:, -1])
    with pytest.raises(softrod.InputError, match=r"joint_forces\[1\]"):
        bad = f.copy()
        bad[1, 0] = np.nan
        batch.step(0.0, q, qd, u, 0.05, joint_forces=bad)
    with pytest.raises(softrod.InputError, match="shape"):
        batch.step(0.0, q, qd, u, 0.05, joint_forces=f[:2])


@pytest.mark.parametrize("mode", ["NextStep", "SameStep"])
def test_joint_force_batched_vector_env_equals_sync_vector_env(mode):
    from gymnasium.vector import SyncVectorEnv

    fns = [
        lambda k=k: se.RodEnv(link_scene(cable=True), se.ReachTask(), episode_steps=k)
        for k in (3, 5, 4)
    ]
    sync = SyncVectorEnv(fns, autoreset_mode=mode)
    batched = se.BatchedVectorEnv(fns, threads=2, autoreset_mode=mode)
    o1, _ = sync.reset(seed=5)
    o2, _ = batched.reset(seed=5)
    np.testing.assert_array_equal(o1, o2)
    rng = np.random.default_rng(0)
    for _ in range(10):
        a = np.column_stack([rng.uniform(-0.5, 3.5, 3), rng.uniform(-0.7, 0.7, 3)])
        r1, r2 = sync.step(a), batched.step(a)
        for x, y in zip(r1[:4], r2[:4]):
            np.testing.assert_array_equal(x, y)


def test_joint_actuator_env_passes_gymnasiums_checker():
    from gymnasium.utils.env_checker import check_env

    for sim in (link_scene(), link_scene(cable=True)):
        env = se.RodEnv(sim, se.ReachTask(), episode_steps=5)
        with warnings.catch_warnings():
            # Its advice (normalized actions) is a recommendation, as above.
            warnings.simplefilter("ignore")
            check_env(env)
        obs, _ = env.reset(seed=1)
        for _ in range(3):
            obs, reward, terminated, _, _ = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs)
            assert np.isfinite(reward) and not terminated
