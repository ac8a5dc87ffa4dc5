"""The surface: construction, shapes and dtypes in and out, settings, and
errors as Python exceptions with the Rust message."""

from __future__ import annotations

import numpy as np
import pytest

import softrod
from conftest import EXAMPLES, rod, scene_text, smooth_state


def test_rods_built_in_python_match_the_scene():
    """A Python-built rod and the scene with the same keys give the same
    model: same coordinates, same mass matrix and dynamics, bit for bit."""
    py = softrod.Simulation(rods=[rod(strains=["ky", "qx", "qz"], name="arm")],
                            gravity=[0, 0, -9.81])
    toml = softrod.Simulation.from_toml(
        scene_text('strains = ["qz", "ky", "qx"]', "[world]\ngravity = [0.0, 0.0, -9.81]\n"))
    assert py.n_dof == toml.n_dof == 30
    assert py.rod_names == toml.rod_names == ["arm"]
    q, qd = smooth_state(30)
    np.testing.assert_array_equal(py.mass_matrix(0.0, q), toml.mass_matrix(0.0, q))
    np.testing.assert_array_equal(py.forward_dynamics(0.0, q, qd),
                                  toml.forward_dynamics(0.0, q, qd))
    assert py.terms == toml.terms == ["inertia", "elasticity", "gravity"]


def test_from_file_reads_paths_and_from_toml_text():
    path = EXAMPLES / "cantilever_gravity.toml"
    a = softrod.Simulation.from_file(path)
    b = softrod.Simulation.from_file(str(path))
    c = softrod.Simulation.from_toml(path.read_text())
    assert a.n_dof == b.n_dof == c.n_dof > 0
    # The scene's [run] settings come along.
    assert a.settings.integrator == c.settings.integrator
    # A path given as text is not guessed at: the error says what to call.
    for wrong in (path, str(path)):
        with pytest.raises(softrod.InputError, match=r"Simulation\.from_file"):
            softrod.Simulation.from_toml(wrong)


def test_shapes_and_dtypes_of_every_output():
    sim = softrod.Simulation(rods=[rod(pieces=4)], gravity=[0, 0, -9.81])
    n = sim.n_dof
    q, qd = smooth_state(n)
    for out, shape in [
        (sim.forward_dynamics(0.0, q, qd), (n,)),
        (sim.inverse_dynamics(0.0, q, qd, qd), (n,)),
        (sim.mass_matrix(0.0, q), (n, n)),
        (sim.bias_force(0.0, q, qd), (n,)),
        (sim.coriolis_matrix(q, qd), (n, n)),
        (sim.coriolis_force(q, qd), (n,)),
        (sim.gravity_force(0.0, q), (n,)),
        (sim.stiffness_matrix(), (n, n)),
        (sim.damping_matrix(), (n, n)),
        (sim.actuation_matrix(q), (n, 0)),
        (sim.pose(0, 0.3, q), (4, 4)),
        (sim.pose("rod0", np.linspace(0, 0.5, 7), q), (7, 4, 4)),
        (sim.tip_pose(0, q), (4, 4)),
        (sim.jacobian(0, 0.3, q), (6, n)),
        (sim.jacobian(0, [0.1, 0.2], q, frame="world"), (2, 6, n)),
        (sim.gravity, (3,)),
    ]:
        assert out.shape == shape
        assert out.dtype == np.float64
        assert out.flags["C_CONTIGUOUS"]
    traj = sim.simulate(0.02, output_every=0.01)
    m = len(traj)
    assert m == 3
    for name, shape in [("t", (m,)), ("q", (m, n)), ("qdot", (m, n)),
                        ("tip_position", (m, 3)), ("tip_rotation", (m, 3, 3)),
                        ("tip_positions", (m, 1, 3)), ("tip_rotations", (m, 1, 3, 3)),
                        ("kinetic", (m,)), ("elastic", (m,)), ("gravitational", (m,)),
                        ("energy", (m,))]:
        a = getattr(traj, name)
        assert a.shape == shape, name
        assert a.dtype == np.float64
    assert traj.shape().shape == (5, 3)
    assert traj.shape(0, s=[0.0, 0.5]).shape == (2, 3)
    # Trajectory arrays are read-only: the record cannot be edited in place.
    with pytest.raises(ValueError):
        traj.q[0, 0] = 1.0


def test_inputs_of_any_array_like_are_accepted():
    """Lists, integer arrays and strided views convert; a float64
    C-contiguous array is read in place."""
    sim = softrod.Simulation(rods=[rod(pieces=2, strains=["ky"])])
    ref = sim.mass_matrix(0.0, np.array([0.5, 1.0]))
    np.testing.assert_array_equal(sim.mass_matrix(0.0, [0.5, 1]), ref)
    np.testing.assert_array_equal(sim.mass_matrix(0.0, np.array([0.5, 1.0, 7.0])[:2]), ref)
    np.testing.assert_array_equal(sim.mass_matrix(0.0, np.array([[0.5, 9], [1.0, 9]])[:, 0]), ref)
    np.testing.assert_array_equal(sim.mass_matrix(0.0, np.array([1, 2]) / np.array([2, 2])), ref)


@pytest.mark.parametrize("call, message", [
    (lambda s, q: s.mass_matrix(0.0, q[:3]), "q must have shape (60,), got (3,)"),
    (lambda s, q: s.forward_dynamics(0.0, q, q[:-1]), "qdot must have shape (60,), got (59,)"),
    (lambda s, q: s.forward_dynamics(0.0, q, q, np.zeros((60, 1))),
     "tau must have shape (60,), got (60, 1)"),
    (lambda s, q: s.inverse_dynamics(0.0, q, q, q[:5]), "qddot must have shape (60,), got (5,)"),
    (lambda s, q: s.energies(0.0, q, np.zeros(61)), "qdot must have shape (60,), got (61,)"),
    (lambda s, q: s.set_initial_state(q, q[:2]), "qdot must have shape (60,), got (2,)"),
    (lambda s, q: s.forward_dynamics(0.0, q, q, u=[1.0]), "u must have shape (0,)"),
    (lambda s, q: s.mass_matrix(0.0, "abc"), "q: not an array of numbers"),
    (lambda s, q: s.pose(0, 0.6, q), "s = 0.6"),
    (lambda s, q: s.pose("nope", 0.1, q), 'no rod "nope"'),
    (lambda s, q: s.pose(3, 0.1, q), "rod index 3 out of range"),
    (lambda s, q: s.jacobian(0, 0.1, q, frame="local"), 'frame must be "body" or "world"'),
])
def test_wrong_input_is_a_value_error_naming_the_argument(call, message):
    sim = softrod.Simulation(rods=[rod()])
    q, _ = smooth_state(sim.n_dof)
    with pytest.raises(softrod.InputError) as e:
        call(sim, q)
    assert isinstance(e.value, ValueError)
    assert message in str(e.value)


def test_invalid_rods_and_materials_are_refused_where_they_are_built():
    with pytest.raises(ValueError, match="poisson or shear_modulus"):
        softrod.Material(density=1000, young=1e6)
    with pytest.raises(ValueError, match="Young"):
        softrod.Material(density=1000, young=-1.0, poisson=0.3)
    with pytest.raises(ValueError, match="Poisson"):
        softrod.Material(density=1000, young=1e6, poisson=0.7)
    with pytest.raises(ValueError, match="Circle"):
        softrod.Circle(-0.01)
    with pytest.raises(ValueError, match='unknown strain "kw"'):
        rod(strains=["ky", "kw"])
    with pytest.raises(ValueError, match="sum to"):
        rod(pieces=[0.1, 0.2])
    with pytest.raises(ValueError, match="orthonormal"):
        rod(base=np.diag([1.0, 1.0, 2.0, 1.0]))
    with pytest.raises(ValueError, match=r"cables\[0\]"):
        rod(cables=[softrod.Cable(offset=(0, 0.005), tension=1.0, to=0.9)])
    with pytest.raises(ValueError, match="tension"):
        softrod.Cable(offset=(0, 0.005), tension=-1.0)
    with pytest.raises(ValueError, match=r"loads\[0\]"):
        rod(loads=[softrod.PointLoad(s=0.7, force=[0, 0, -1])])
    with pytest.raises(ValueError, match="two rods"):
        softrod.Simulation(rods=[rod(name="a"), rod(name="a")])


def test_scene_errors_name_the_key_path():
    text = scene_text().replace("young = 1.0e7", "young = -1.0e7")
    with pytest.raises(softrod.SceneError) as e:
        softrod.Simulation.from_toml(text)
    assert isinstance(e.value, ValueError)
    assert "rod[0].material.young" in str(e.value)
    with pytest.raises(softrod.InputError, match="run.integrator"):
        softrod.Simulation.from_toml(scene_text(extra='[run]\nintegrator = "radau"\n'))
    with pytest.raises(softrod.SceneError):
        softrod.Simulation.from_file(EXAMPLES / "no_such_scene.toml")


def test_settings_are_validated_and_apply():
    s = softrod.Settings(integrator="rk4", dt=1e-4, output_every=0.01)
    assert (s.integrator, s.dt, s.output_every) == ("rk4", 1e-4, 0.01)
    with pytest.raises(softrod.InputError, match="unknown integrator"):
        softrod.Settings(integrator="euler")
    with pytest.raises(softrod.InputError, match="run.rtol"):
        softrod.Settings(rtol=float("nan"))
    assert softrod.Settings(integrator="radau5").integrator == "radau5"
    # rtol alone lowers a larger atol to it (the error then tracks rtol).
    assert (softrod.Settings(rtol=1e-8).atol, softrod.Settings(rtol=1e-2).atol) == (1e-8, 1e-6)
    assert softrod.Settings(rtol=1e-8, atol=1e-5).atol == 1e-5
    sim = softrod.Simulation(rods=[rod(pieces=2)])
    sim.settings = s
    assert sim.settings.integrator == "rk4"
    with pytest.raises(softrod.InputError, match="run.duration"):
        sim.simulate(-1.0)


def test_settings_replace_keeps_what_it_does_not_name():
    """Settings.replace changes only the keywords named, by the rules of
    Settings(...); the scene's [run] duration, which Settings(...) cannot
    state, stays (the envs' rtol= used to reset it)."""
    sim = softrod.Simulation.from_toml(scene_text(
        extra='[run]\nduration = 0.02\nintegrator = "radau5"\nrtol = 1e-3\natol = 1e-5\n'))
    s = sim.settings.replace(rtol=1e-7)
    assert (s.integrator, s.rtol, s.atol) == ("radau5", 1e-7, 1e-7)
    assert sim.settings.replace(rtol=1e-4).atol == 1e-5
    assert sim.settings.replace(atol=1e-9).rtol == 1e-3
    sim.settings = s
    assert sim.simulate().t[-1] == pytest.approx(0.02, abs=1e-15)
    with pytest.raises(softrod.InputError, match="run.rtol"):
        s.replace(rtol=-1.0)


def test_steps_to_outputs_is_a_setting_that_survives_replace_and_pickle():
    """steps_to_outputs (docs/theory-derivatives.md CD10): off by default,
    kept by replace() and by a pickle, and in the repr."""
    import pickle
    assert not softrod.Settings().steps_to_outputs
    s = softrod.Settings(steps_to_outputs=True)
    assert s.steps_to_outputs and "steps_to_outputs=True" in repr(s)
    assert s.replace(rtol=1e-4).steps_to_outputs
    sim = softrod.Simulation(rods=[rod(pieces=2)])
    sim.settings = s
    assert pickle.loads(pickle.dumps(sim)).settings.steps_to_outputs


@pytest.mark.parametrize("kw", [
    dict(integrator="rosenbrock", rtol=1e-5, atol=1e-8),
    dict(integrator="esdirk", rtol=1e-5, atol=1e-8),
    dict(integrator="esdirk", rtol=1e-5, atol=1e-8, steps_to_outputs=True),
    dict(integrator="radau5", rtol=1e-5, atol=1e-8),
    dict(integrator="dopri5", rtol=1e-5, atol=1e-8),
    dict(integrator="rk4", dt=2e-5),
    dict(integrator="generalized-alpha", dt=1e-4),
    dict(integrator="generalized-alpha", dt=1e-4, error_control=True, rtol=1e-4),
    dict(integrator="generalized-alpha", dt=1e-4, linearly_implicit=True),
])
def test_every_integrator_and_option_runs_and_agrees(kw):
    """Each integrator reaches the same tip (a tight dopri5 run) within its
    accuracy on a 2-piece planar release."""
    # The second-order fixed-step schemes at dt = 1e-4 over 0.05 s: tip
    # error ~1e-5 m; the tolerance-controlled ones are tighter.
    tip_tol = 5e-5
    sim = softrod.Simulation(rods=[rod(pieces=2, strains=["ky", "qx", "qz"])],
                             gravity=[0, 0, -9.81])
    ref = sim.simulate(0.05, integrator="dopri5", rtol=1e-10, atol=1e-12, output_every=0.05)
    traj = sim.simulate(0.05, output_every=0.05, **kw)
    assert traj.status == "completed"
    assert np.abs(traj.tip_position[-1] - ref.tip_position[-1]).max() < tip_tol
    # Overrides are for one call only.
    assert sim.settings.integrator == "esdirk"


def test_initial_state_and_overrides():
    sim = softrod.Simulation(rods=[rod(pieces=2, strains=["ky"])])
    q0 = np.array([0.5, 0.5])
    sim.set_initial_state(q0, np.zeros(2))
    q, qd = sim.initial_state()
    np.testing.assert_array_equal(q, q0)
    traj = sim.simulate(0.01, output_every=0.01)
    np.testing.assert_array_equal(traj.q[0], q0)
    traj = sim.simulate(0.01, output_every=0.01, q0=np.zeros(2), qdot0=[1.0, 0.0])
    np.testing.assert_array_equal(traj.qdot[0], [1.0, 0.0])
    # The override did not stick.
    np.testing.assert_array_equal(sim.initial_state()[0], q0)
    st = sim.initial()
    assert st.t == 0.0
    np.testing.assert_array_equal(st.q, q0)


def test_help_is_useful():
    doc = softrod.Simulation.simulate.__doc__
    assert "controller" in doc and "zero-order hold" in doc and "output_every" in doc
    for obj in [softrod.Simulation, softrod.Rod, softrod.Material, softrod.Cable,
                softrod.Trajectory, softrod.simulate_many, softrod.Simulation.forward_dynamics,
                softrod.Simulation.step, softrod.Simulation.from_toml,
                softrod.Simulation.from_file]:
        assert obj.__doc__ and len(obj.__doc__) > 60, obj


def test_duration_defaults_to_the_scenes():
    sim = softrod.Simulation.from_toml(scene_text(extra="[run]\nduration = 0.02\noutput_every = 0.01\n"))
    assert sim.duration == 0.02
    assert sim.rod_lengths == pytest.approx([0.5], rel=1e-15)
    assert sim.simulate().t[-1] == 0.02
    built = softrod.Simulation(rods=[rod(pieces=2)])
    assert built.duration is None
    with pytest.raises(softrod.InputError, match="needs a duration"):
        built.simulate()
    # Python-built simulations sample every thousandth of the run.
    assert len(built.simulate(0.01)) == 1001
    # simulate_many follows the same rule, run by run.
    assert softrod.simulate_many([sim, sim.copy()])[1].t[-1] == 0.02
    with pytest.raises(softrod.InputError, match=r"needs a duration \(sims\[1\]"):
        softrod.simulate_many([sim, built])
    assert softrod.simulate_many([sim, built], 0.01)[1].t[-1] == 0.01


def test_robot_time_names_and_unsupported_methods():
    """Prescribed joints stand where the call's `t` puts them (the keyword
    `t`, default 0, of the kinematic queries), whatever ran before; bodies
    are named in body_poses' order; what a robot is not covered by raises
    NotSupportedError (a NotImplementedError)."""
    sim = softrod.Simulation.from_file(EXAMPLES / "oscillating_base.toml")
    q = np.zeros(sim.n_dof)
    tip0 = sim.tip_pose(0, q)
    sim.forward_dynamics(0.125, q, q)
    sim.simulate(0.02)
    np.testing.assert_array_equal(sim.tip_pose(0, q), tip0)
    np.testing.assert_array_equal(sim.tip_pose(0, q, t=0.0), tip0)
    # The base is at its crest, 0.01 m along x.
    assert sim.tip_pose(0, q, t=0.125)[0, 3] - tip0[0, 3] == pytest.approx(0.01, abs=1e-15)
    np.testing.assert_array_equal(sim.pose(0, sim.rod_lengths[0], q, t=0.125),
                                  sim.tip_pose(0, q, t=0.125))
    # Dynamics calls take the time first: at qdot = 0 the kinetic energy is
    # the drive's, largest at t = 0 (the base at full speed) and zero at
    # the crest, t = 1/8 s.
    assert sim.energies(0.0, q, q).kinetic > 0.0
    assert sim.energies(0.125, q, q).kinetic < 1e-12 * sim.energies(0.0, q, q).kinetic
    with pytest.raises(softrod.InputError):
        sim.tip_pose(0, q, t=float("nan"))
    arm = softrod.Simulation.from_file(EXAMPLES / "arm_with_payload.toml")
    assert arm.body_names == ["connector", "gripper"]
    assert arm.body_poses(np.zeros(arm.n_dof)).shape == (2, 4, 4)
    with pytest.raises(softrod.NotSupportedError, match="coriolis_matrix"):
        arm.coriolis_matrix(np.zeros(arm.n_dof), np.zeros(arm.n_dof))
    with pytest.raises(NotImplementedError):
        arm.coriolis_force(np.zeros(arm.n_dof), np.zeros(arm.n_dof))
