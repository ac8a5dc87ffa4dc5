"""Python with the reach of a scene (issue 27): bodies, joints, trees,
closures and prescribed joints built in Python read by the scene
loader, so that a Python-built robot is the same model as its TOML scene
(same coordinates, same run to round-off); a pendulum body on a revolute
joint against its small-oscillation period; the Python objects written as
their scene tables (the same model either way)."""

from __future__ import annotations

import tomllib

import re

import numpy as np
import pytest

import softrod
from conftest import EXAMPLES, smooth_state

ROBOT = """
[world]
gravity = [0, 0, -9.81]

[[rod]]
name = "arm"
parent = "base"
length = 0.2
pieces = 2
strains = ["ky", "kz", "qx"]
joint = { type = "revolute", axis = [0, 0, 1], stiffness = 0.5, damping = 0.01 }
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 100.0 }

[[rod]]
name = "finger"
parent = "hand"
length = 0.1
pieces = 2
strains = ["ky", "kz"]
base = { position = [0.01, 0, 0] }
joint = { type = "universal", axes = [[0, 1, 0], [0, 0, 1]], stiffness = [0.05, 0.05] }
section = { shape = "circle", radius = 0.005 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "base"
parent = "world"
joint = { type = "prismatic", axis = [1, 0, 0], prescribed = { times = [0, 0.05, 0.1], values = [0, 0.002, 0] } }
mass = 0.2
inertia = [1e-4, 1e-4, 1e-4]

[[body]]
name = "hand"
parent = "arm"
at = 0.2
mass = 0.02
inertia = [[2e-6, 0, 0], [0, 2e-6, 0], [0, 0, 2e-6]]
center_of_mass = [0.005, 0, 0]

[[closure]]
name = "pin"
type = "ball"
a = { element = "finger" }
b = { element = "world", base = { position = [0.31, 0, 0] } }
"""


def python_robot():
    """ROBOT built with the Python API."""
    mat = softrod.Material(density=1000.0, young=1.0e6, poisson=0.5)
    arm = softrod.Rod(0.2, 2, ["ky", "kz", "qx"], name="arm", section=softrod.Circle(0.01),
                      material=softrod.Material(density=1000.0, young=1.0e6, poisson=0.5,
                                                viscosity=100.0),
                      parent="base",
                      joint=softrod.Joint("revolute", axis=[0, 0, 1], stiffness=0.5,
                                          damping=0.01))
    finger = softrod.Rod(0.1, 2, ["ky", "kz"], name="finger", section=softrod.Circle(0.005),
                         material=mat, parent="hand", base={"position": [0.01, 0, 0]},
                         joint=softrod.Joint("universal", axes=[[0, 1, 0], [0, 0, 1]],
                                             stiffness=[0.05, 0.05]))
    base = softrod.Body("base", "world", mass=0.2, inertia=[1e-4] * 3,
                        joint=softrod.Joint("prismatic", axis=[1, 0, 0],
                                            prescribed=softrod.Prescribed([0, 0.05, 0.1],
                                                                          [0, 0.002, 0])))
    hand = softrod.Body("hand", "arm", at=0.2, mass=0.02, inertia=np.diag([2e-6] * 3),
                        center_of_mass=[0.005, 0, 0])
    pin = softrod.Closure("ball", softrod.Frame("finger"),
                          softrod.Frame("world", base=softrod.Base([0.31, 0, 0])), name="pin")
    return softrod.Simulation([arm, finger], [0, 0, -9.81], bodies=[base, hand],
                              closures=[pin])


def assert_same_model(a, b, t=0.03):
    assert a.q_names == b.q_names
    assert a.prescribed_names == b.prescribed_names
    assert a.body_names == b.body_names
    assert a.obstacle_names == b.obstacle_names
    q, qd = smooth_state(a.n_dof, scale=0.05)
    np.testing.assert_array_equal(a.mass_matrix(t, q), b.mass_matrix(t, q))
    np.testing.assert_array_equal(a.bias_force(t, q, qd), b.bias_force(t, q, qd))
    np.testing.assert_array_equal(a.stiffness_matrix(), b.stiffness_matrix())
    np.testing.assert_array_equal(a.damping_matrix(), b.damping_matrix())
    np.testing.assert_array_equal(a.body_poses(q, t=t), b.body_poses(q, t=t))
    assert a.closure_residuals(q, t=t) == b.closure_residuals(q, t=t)


def test_a_python_robot_is_its_toml_scene():
    py = python_robot()
    toml = softrod.Simulation.from_toml(ROBOT)
    assert py.q_names[:2] == ["arm.joint.theta", "arm.p0.ky"]
    assert py.prescribed_names == ["base.joint.d"]
    assert_same_model(py, toml)
    # The same run, number for number.
    kw = dict(output_every=0.01, rtol=1e-6, atol=1e-9)
    a, b = py.simulate(0.1, **kw), toml.simulate(0.1, **kw)
    assert a.columns == b.columns
    np.testing.assert_allclose(a.table, b.table, rtol=1e-13, atol=1e-15)
    assert a.prescribed_force.shape == (11, 1)


def test_from_dict_reads_the_scene_as_toml():
    as_dict = tomllib.loads(ROBOT)
    sim = softrod.Simulation.from_dict(as_dict)
    assert_same_model(sim, softrod.Simulation.from_toml(ROBOT))
    # Numpy values and Python objects stand for theirs.
    as_dict["rod"][0]["section"] = softrod.Circle(0.01)
    as_dict["rod"][0]["material"] = softrod.Material(density=1000.0, young=1.0e6,
                                                      poisson=0.5, viscosity=100.0)
    as_dict["body"][1]["inertia"] = np.diag([2e-6] * 3)
    as_dict["world"]["gravity"] = np.array([0, 0, -9.81])
    assert_same_model(softrod.Simulation.from_dict(as_dict), sim)


def _interleaved(text):
    """Whether a body table comes before a rod table: the file's q order
    may then interleave them, which a dict (rods and bodies under two keys)
    cannot state."""
    heads = re.findall(r"^\[\[(rod|body)\]\]", text, flags=re.M)
    return "body" in heads and "rod" in heads[heads.index("body"):]


@pytest.mark.parametrize("name", sorted(p.name for p in EXAMPLES.glob("*.toml")))
def test_every_example_reads_the_same_from_a_dict(name):
    path = EXAMPLES / name
    text = path.read_text()
    a = softrod.Simulation.from_file(path)
    b = softrod.Simulation.from_dict(tomllib.loads(text), name=name)
    if a.q_names != b.q_names:
        # Rods and bodies with coordinates interleaved in the file: the
        # dict's model has the same coordinates, rods first.
        assert _interleaved(text)
        assert sorted(a.q_names) == sorted(b.q_names)
        return
    assert_same_model(a, b, t=0.0)
    assert a.settings.integrator == b.settings.integrator
    assert a.settings.rtol == b.settings.rtol


def test_pendulum_period_on_a_revolute_joint():
    """A body on a revolute joint, centre of mass d below the axis:
    T = 2 pi sqrt(I / (m g d)), I = I_c + m d^2 about the axis, times
    (1 + theta0^2 / 16) for the amplitude theta0."""
    m, d, ic, g = 0.5, 0.2, 1e-3, 9.81
    bob = softrod.Body("bob", "world", mass=m, inertia=[ic, ic, ic], center_of_mass=[0, 0, -d],
                       joint=softrod.Joint("revolute", axis=[0, 1, 0]))
    # A model needs a rod: a short stiff one elsewhere, not coupled to the bob.
    post = softrod.Rod(0.05, 1, ["ky"], name="post", section=softrod.Circle(0.01),
                       material=softrod.Material(density=1000.0, young=1e9, poisson=0.5),
                       base={"position": [1.0, 0, 0]})
    sim = softrod.Simulation([post], [0, 0, -g], bodies=[bob])
    assert sim.q_names == ["post.p0.ky", "bob.joint.theta"]
    theta0 = 0.01
    q0 = sim.statics().q.copy()
    q0[1] = theta0
    traj = sim.simulate(2.0, q0=q0, output_every=1e-3, rtol=1e-10, atol=1e-12)
    theta = traj.q[:, 1]
    t = traj.t
    k = np.nonzero(np.sign(theta[:-1]) != np.sign(theta[1:]))[0]
    crossings = t[k] - theta[k] * (t[k + 1] - t[k]) / (theta[k + 1] - theta[k])
    period = 2 * np.mean(np.diff(crossings))
    expected = 2 * np.pi * np.sqrt((ic + m * d * d) / (m * g * d)) * (1 + theta0**2 / 16)
    assert len(crossings) >= 4
    assert period == pytest.approx(expected, rel=2e-5)


def test_python_rods_are_written_as_their_scene_tables():
    """A rod with everything a softrod.Rod takes is the same model whether
    built directly or read back as the scene tables it stands for."""
    rod = softrod.Rod(
        0.4, [0.1, 0.1, 0.2], ["kx", "ky", "kz", "qx"], name="arm",
        section=softrod.Tube(0.01, 0.004),
        material=softrod.Material(density=1100.0, young=2e6, shear_modulus=7e5, viscosity=50.0),
        base={"position": [0.0, 0.1, 0.2],
              "rotation": [[0, -1, 0], [1, 0, 0], [0, 0, 1]]},
        rest_strain=[0.0, 0.5, 0.0, 1.0, 0.0, 0.0], drag=(0.3, 0.001),
        cables=[softrod.Cable([0.0, 0.006], tension=([0, 0.5], [0, 2.0])),
                softrod.Cable(path=[[0, 0.005, 0], [0.4, 0.002, 0.001]], tension=1.0,
                              from_=0.05, to=0.35)],
        loads=[softrod.PointLoad(0.4, [0, 0, -0.1], moment=[0.001, 0, 0], frame="body")])
    tapered = softrod.Rod(0.2, 2, name="tip", section=softrod.TaperedCircle(0.01, 0.005),
                          material=softrod.Material(density=1000.0, young=1e6, poisson=0.45))
    direct = softrod.Simulation([rod, tapered], [0, 0, -9.81], quadrature=3)
    # An empty [contact] table: the scene's path, no contact.
    scene = softrod.Simulation([rod, tapered], [0, 0, -9.81], quadrature=3,
                               contact=softrod.ContactSettings())
    assert_same_model(direct, scene)
    q, _ = smooth_state(direct.n_dof, scale=0.05)
    np.testing.assert_allclose(direct.actuation_matrix(q), scene.actuation_matrix(q),
                               rtol=1e-14, atol=1e-15)
    kw = dict(output_every=0.01, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(direct.simulate(0.05, **kw).table,
                               scene.simulate(0.05, **kw).table, rtol=1e-12, atol=1e-15)


def test_bad_robots_raise_naming_the_key():
    mat = softrod.Material(density=1000.0, young=1e6, poisson=0.5)
    rod = softrod.Rod(0.2, 2, section=softrod.Circle(0.01), material=mat, name="arm")
    with pytest.raises(softrod.SceneError, match=r"^Simulation: body\[0\]\.mass"):
        softrod.Simulation([rod], bodies=[softrod.Body("b", "arm", mass=-1, inertia=[1, 1, 1])])
    with pytest.raises(softrod.SceneError, match=r"body\[0\]\.parent"):
        softrod.Simulation([rod], bodies=[softrod.Body("b", "arn", mass=1, inertia=[1, 1, 1])])
    with pytest.raises(softrod.SceneError, match=r"rod\[0\]\.joint\.type"):
        softrod.Simulation([softrod.Rod(0.2, 2, section=softrod.Circle(0.01), material=mat,
                                        joint=softrod.Joint("helical"))])
    with pytest.raises(softrod.SceneError, match=r"rod\[0\]\.joint\.axis: missing"):
        softrod.Simulation([softrod.Rod(0.2, 2, section=softrod.Circle(0.01), material=mat,
                                        joint=softrod.Joint("revolute"))])
    with pytest.raises(softrod.SceneError, match=r"closure\[0\]\.type"):
        softrod.Simulation([rod], closures=[softrod.Closure("glue", softrod.Frame("arm"),
                                                            softrod.Frame("world"))])
    with pytest.raises(softrod.SceneError, match=r"^<dict>: rod\[0\]\.length: missing"):
        softrod.Simulation.from_dict({"rod": [{"name": "a"}]})
    with pytest.raises(softrod.SceneError, match=r"^robot: run\.integrator"):
        softrod.Simulation.from_dict({**tomllib.loads(ROBOT), "run": {"integrator": "euler"}},
                                     name="robot")
    with pytest.raises(softrod.InputError, match=r"rod\[0\]: a softrod.Rod stands for"):
        softrod.Simulation.from_dict({"rod": [rod]})
    with pytest.raises(softrod.InputError, match=r"keys must be strings"):
        softrod.Simulation.from_dict({1: 2})
    with pytest.raises(softrod.InputError, match=r"rods\[0\]"):
        softrod.Simulation([3.0], bodies=[])
    with pytest.raises(softrod.InputError, match=r"Rod\(joint\)"):
        softrod.Rod(0.2, 2, section=softrod.Circle(0.01), material=mat, joint="revolute")


def test_a_body_on_a_free_joint_falls_freely_and_a_spherical_one_spins():
    """A free body under gravity: z = z0 - g t^2 / 2, its orientation kept;
    a body on a spherical joint with its centre of mass on the joint keeps
    its spin rate about a principal axis (no gravity torque)."""
    g = 9.81
    post = softrod.Rod(0.05, 1, ["ky"], name="post", section=softrod.Circle(0.01),
                       material=softrod.Material(density=1000.0, young=1e9, poisson=0.5))
    stone = softrod.Body("stone", "world", mass=0.3, inertia=[1e-4, 2e-4, 3e-4],
                         base=softrod.Base([1.0, 0, 2.0]), joint=softrod.Joint("free"))
    top = softrod.Body("top", "world", mass=0.1, inertia=[1e-4, 1e-4, 2e-4],
                       base=softrod.Base([2.0, 0, 0]), joint=softrod.Joint("spherical"))
    sim = softrod.Simulation([post], [0, 0, -g], bodies=[stone, top])
    assert sim.body_names == ["stone", "top"]
    assert len(sim.q_names) == 1 + 6 + 3
    q0 = np.zeros(sim.n_dof)
    qd0 = np.zeros(sim.n_dof)
    spin = 3.0
    qd0[sim.q_names.index("top.joint.rz")] = spin
    traj = sim.simulate(0.5, q0=q0, qdot0=qd0, output_every=0.05, rtol=1e-10, atol=1e-12)
    for t, q in zip(traj.t, traj.q):
        poses = sim.body_poses(q, t=t)
        assert poses[0][2, 3] == pytest.approx(2.0 - 0.5 * g * t * t, abs=1e-9)
        assert np.allclose(poses[0][:3, :3], np.eye(3), atol=1e-9)
        c, s = np.cos(spin * t), np.sin(spin * t)
        assert np.allclose(poses[1][:3, :3], [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-8)
