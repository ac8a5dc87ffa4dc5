"""Simulation.solve_actuation (inverse statics, docs/theory-control.md) against the
constant-curvature law of a cable at constant offset, a forward statics solve, the CLI,
and its errors."""

from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest

import softrod
from conftest import EXAMPLES

# A planar arm bending about y only, one cable 8 mm off the centreline along local z.
PLANAR = """
[[rod]]
name = "arm"
length = 0.5
pieces = 10
strains = ["ky"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }
[[cable]]
rod = "arm"
offset = [0.0, 0.008]
tension = 0.0
"""
EI = 1.0e6 * math.pi * 0.01**4 / 4


def arc_tip(kappa: float) -> list[float]:
    return [math.sin(kappa * 0.5) / kappa, 0.0, -(1 - math.cos(kappa * 0.5)) / kappa]


def test_constant_curvature_tension():
    # kappa = -T d / EI for the moment T d, uniform along the rod.
    sim = softrod.Simulation.from_toml(PLANAR)
    kappa = -2.0
    r = sim.solve_actuation([{"rod": "arm", "position": arc_tip(kappa)}], effort_weight=0.0)
    want = -kappa * EI / 0.008
    assert r["converged"] and r["reached"], r["message"]
    assert abs(r["tensions"][0] - want) < 1e-9 * want
    assert np.allclose(r["q"], kappa, rtol=1e-9, atol=0)
    assert r["bounds"] == ["free"]


def test_recovers_the_tensions_of_a_forward_solve_and_warm_starts():
    sim = softrod.Simulation.from_file(EXAMPLES / "cable_arm_inverse.toml")
    truth = np.array([12.0, 3.0, 7.0])
    st = sim.statics(tensions=truth)
    tip = st.tip[:3, 3]
    r = sim.solve_actuation([{"rod": 0, "position": tip}], max_tension=30.0, effort_weight=0.0)
    assert r["reached"], r["message"]
    assert np.allclose(r["tensions"], truth, rtol=0, atol=1e-6)
    moved = tip + [0.0, 0.001, 0.0]
    w = sim.solve_actuation([{"position": moved}], max_tension=30.0, warm_start=r)
    assert w["reached"] and w["iterations"] <= 4, w


def test_unreachable_and_bounds():
    sim = softrod.Simulation.from_toml(PLANAR)
    r = sim.solve_actuation([{"position": [0.0, 0.0, 0.4]}], max_tension=0.5)
    assert r["converged"] and not r["reached"]
    assert r["bounds"] == ["upper"] and r["tensions"][0] == 0.5
    assert "not reachable" in r["message"]


def test_matches_the_cli(softrod_bin):
    path = EXAMPLES / "cable_arm_inverse.toml"
    out = subprocess.run([softrod_bin, "inverse", str(path), "--json"], capture_output=True, text=True, check=True)
    cli = json.loads(out.stdout)
    sim = softrod.Simulation.from_file(path)
    r = sim.solve_actuation([{"rod": "arm", "s": 0.5, "position": [0.497, 0.02, -0.03]}], max_tension=30.0)
    assert np.allclose(r["tensions"], cli["tensions"], rtol=1e-12, atol=0)


# A three-cable arm under gravity, a gripper body 3 cm beyond its tip, the tip sliding
# on the world's x axis (a slider closure): a closed model with a body target.
GRIPPER_ON_SLIDER = """
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "arm"
length = 0.5
pieces = 10
strains = ["kx", "ky", "kz", "qx"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }
[[body]]
name = "gripper"
parent = "arm"
base = { position = [0.03, 0.0, 0.0] }
joint = { type = "revolute", axis = [0, 1, 0], stiffness = 0.05 }
mass = 0.02
inertia = [4e-6, 4e-6, 4e-6]
[[closure]]
type = "slider"
axis = [1, 0, 0]
a = { element = "arm" }
b = { element = "world" }
""" + "".join(
    f'[[cable]]\nrod = "arm"\noffset = [{0.008 * math.cos(math.radians(a))}, '
    f"{0.008 * math.sin(math.radians(a))}]\ntension = 0.0\n"
    for a in (90.0, 210.0, 330.0)
)


def test_body_target_on_a_closed_model_recovers_a_forward_solve():
    # docs/theory-control.md IS8-IS11: the gripper's position and the arm's midpoint at
    # known tensions (forward constrained statics) give the tensions back.
    sim = softrod.Simulation.from_toml(GRIPPER_ON_SLIDER)
    truth = np.array([0.4, 1.1, 0.7])
    st = sim.statics(tensions=truth)
    grip = st.bodies["gripper"][:3, 3]
    mid = sim.pose("arm", 0.25, st.q)[:3, 3]
    r = sim.solve_actuation(
        [{"body": "gripper", "position": grip}, {"rod": "arm", "s": 0.25, "position": mid}],
        effort_weight=0.0,
    )
    assert r["converged"] and r["reached"], r["message"]
    assert np.allclose(r["tensions"], truth, rtol=0, atol=1e-7)
    assert np.allclose(r["q"], st.q, rtol=0, atol=1e-8)
    assert np.allclose(r["targets"][0]["position"], grip, rtol=0, atol=1e-9)


@pytest.mark.parametrize(
    "target, words",
    [
        ({"body": "hand", "position": [0, 0, 0]}, "targets[0].body"),
        ({"body": 3, "position": [0, 0, 0]}, "targets[0].body"),
        ({"body": "gripper", "s": 0.1, "position": [0, 0, 0]}, "targets[0].s"),
        ({"body": "gripper", "rod": "arm", "position": [0, 0, 0]}, "targets[0].rod"),
    ],
)
def test_bad_body_targets_raise(target, words):
    sim = softrod.Simulation.from_toml(GRIPPER_ON_SLIDER)
    with pytest.raises(softrod.InputError, match=__import__("re").escape(words)):
        sim.solve_actuation([target])


@pytest.mark.parametrize(
    "targets, kwargs, words",
    [
        ([{"rod": "hand", "position": [0, 0, 0]}], {}, "targets[0].rod"),
        ([{"s": 0.7, "position": [0, 0, 0]}], {}, "targets[0].s"),
        ([{"position": [0, math.nan, 0]}], {}, "targets[0].position[1]"),
        ([{"position": [0, 0, 0], "weight": 0.0}], {}, "targets[0].weight"),
        ([{"position": [0, 0, 0]}], {"max_tension": -1.0}, "max_tension"),
        ([{"position": [0, 0, 0]}], {"max_tension": math.nan}, "max_tension"),
        ([{"spot": [0, 0, 0]}], {}, "unknown key"),
        ([], {}, "no targets"),
    ],
)
def test_bad_input_raises(targets, kwargs, words):
    sim = softrod.Simulation.from_toml(PLANAR)
    with pytest.raises(softrod.InputError, match=__import__("re").escape(words)):
        sim.solve_actuation(targets, **kwargs)


# A cantilever bending in x-z (no gravity, no cable).
CANTILEVER = """
[[rod]]
name = "arm"
length = 0.5
pieces = 10
strains = ["ky"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }
"""

# A link body on an actuated revolute joint (with a spring) at the tip of a short rod, gravity -z.
LINK = """
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "base"
length = 0.2
pieces = 2
strains = ["kx", "ky", "kz"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }
[[body]]
name = "link"
parent = "base"
joint = { type = "revolute", axis = [0, 1, 0], stiffness = 0.2, actuator = ACTUATOR }
mass = 0.2
inertia = [1e-4, 1e-4, 1e-4]
center_of_mass = [0.1, 0, 0]
"""


def test_unknown_load_of_a_forward_solve_is_recovered():
    # The tip force of a forward [[load]] solve, recovered from the tip position with the
    # scene's unknown load (default) and with unknown_loads= given in Python.
    force = -0.02
    given = softrod.Simulation.from_toml(
        CANTILEVER + f'[[load]]\nrod = "arm"\ns = 0.5\nforce = [0.0, 0.0, {force}]\n'
    )
    tip = given.statics().tip[:3, 3]
    # Bounds [0, 0, 1]: the force is vertical (f_x, f_y held at 0), one unknown.
    scene = softrod.Simulation.from_toml(
        CANTILEVER
        + '[[load]]\nrod = "arm"\ns = 0.5\nunknown = true\nmax_force = [0.0, 0.0, 1.0]\n'
    )
    r = scene.solve_actuation([{"position": tip}])
    assert r["reached"], r["message"]
    assert r["forces"].shape == (1, 3)
    assert abs(r["forces"][0, 2] - force) < 1e-7 * abs(force)
    assert r["forces"][0, 0] == 0.0 and r["forces"][0, 1] == 0.0
    assert r["force_bounds"] == [["lower", "lower", "free"]]
    assert len(r["tensions"]) == 0 and len(r["joint_forces"]) == 0
    # All three components free: f_x moves the bent tip through its small arm only, so the
    # default effort term (IS2) would bias the fit at ~1e-4; without it the fit is exact.
    plain = softrod.Simulation.from_toml(CANTILEVER)
    p = plain.solve_actuation(
        [{"position": tip}],
        unknown_loads=[{"rod": "arm", "s": 0.5, "max_force": [1, 1, 1]}],
        effort_weight=0.0,
    )
    assert abs(p["forces"][0, 2] - force) < 1e-7 * abs(force)
    assert abs(p["forces"][0, 0]) < 1e-8
    # A bound below the force: held at it, out of reach.
    b = plain.solve_actuation([{"position": tip}], unknown_loads=[{"max_force": 0.01}])
    assert b["converged"] and not b["reached"]
    assert b["forces"][0, 2] == -0.01 and b["force_bounds"][0][2] == "lower"
    with pytest.raises(softrod.InputError, match=r"unknown_loads\[0\]\.max_force\[1\]"):
        plain.solve_actuation([{"position": tip}], unknown_loads=[{"max_force": [1, -1, 1]}])
    with pytest.raises(softrod.SceneError, match=r"load\[0\]\.max_force"):
        softrod.Simulation.from_toml(
            CANTILEVER + '[[load]]\nrod = "arm"\ns = 0.5\nunknown = true\nmax_force = -1.0\n'
        )


def test_joint_torque_of_a_forward_solve_is_recovered():
    tau = -0.1
    truth = softrod.Simulation.from_toml(LINK.replace("ACTUATOR", f"{{ force = {tau} }}"))
    st = truth.statics()
    position = truth.body_poses(st.q)[0][:3, 3]
    sim = softrod.Simulation.from_toml(LINK.replace("ACTUATOR", "{ max_force = 1.0 }"))
    r = sim.solve_actuation([{"body": "link", "position": position}])
    assert r["reached"], r["message"]
    assert abs(r["joint_forces"][0] - tau) < 1e-8
    assert r["joint_force_bounds"] == ["free"]
    assert np.allclose(r["q"], st.q, rtol=0, atol=1e-8)
    # Warm-started from it, the same target costs no step.
    w = sim.solve_actuation([{"body": "link", "position": position}], warm_start=r)
    assert w["iterations"] <= 2 and abs(w["joint_forces"][0] - tau) < 1e-8
    with pytest.raises(softrod.SceneError, match=r"body\[0\]\.joint\.actuator\.max_force"):
        softrod.Simulation.from_toml(LINK.replace("ACTUATOR", "{ max_force = -1.0 }"))


def test_actuated_joint_from_the_builders_matches_the_scene_text():
    # The builders' joint with an actuator is the scene's: the same equilibrium, bit for bit.
    from softrod.builders import Body, Joint

    text = softrod.Simulation.from_toml(LINK.replace("ACTUATOR", "{ force = -0.1 }"))
    scene = {
        "world": {"gravity": [0.0, 0.0, -9.81]},
        "rod": [
            {
                "name": "base", "length": 0.2, "pieces": 2, "strains": ["kx", "ky", "kz"],
                "section": {"shape": "circle", "radius": 0.01},
                "material": {"density": 1000.0, "young": 1.0e7, "poisson": 0.5},
            }
        ],
        "body": [
            Body("link", "base", mass=0.2, inertia=[1e-4, 1e-4, 1e-4],
                 center_of_mass=[0.1, 0, 0],
                 joint=Joint("revolute", axis=[0, 1, 0], stiffness=0.2,
                             actuator={"force": -0.1}))
        ],
    }
    built = softrod.Simulation.from_dict(scene)
    assert np.array_equal(built.statics().q, text.statics().q)
