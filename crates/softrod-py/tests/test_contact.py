"""Contact from Python (issue 24; docs/theory-contact.md; scene-format.md,
"Contact"): obstacles and contact settings in Simulation(...), the contacts
at a state, a run's contacts, against independent references (the weight a
table carries, linear beam theory, the CLI's statics as a second path) and
bad input raising with the key path."""

from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

import softrod

G = 9.81
RHO, E, R = 1000.0, 1.0e6, 0.01


def material():
    return softrod.Material(density=RHO, young=E, poisson=0.5)


def table_rod(length=0.3, pieces=4):
    """A rod along x whose centreline is a radius above the table z = 0,
    free to move up and down only (a prismatic joint along z) and to bend."""
    return softrod.Rod(length, pieces, ["ky"], name="rod", section=softrod.Circle(R),
                       material=material(), base={"position": [0, 0, R]},
                       joint=softrod.Joint("prismatic", axis=[0, 0, 1]))


def on_table(length=0.3, **obstacle):
    table = softrod.Obstacle("table", "plane", normal=[0, 0, 1], **obstacle)
    return softrod.Simulation([table_rod(length)], [0, 0, -G], obstacles=[table])


def total_force(contacts):
    return np.sum([c.force for c in contacts], axis=0)


def test_a_rod_lying_on_a_table_carries_its_weight_in_statics():
    length = 0.3
    sim = on_table(length)
    st = sim.statics()
    contacts = sim.contacts(st.q)
    # The statics result lists the same (as statics --json does).
    assert [repr(c) for c in st.contacts] == [repr(c) for c in contacts]
    assert st.max_penetration == sim.max_penetration(st.q)
    weight = RHO * np.pi * R**2 * G * length
    f = total_force(contacts)
    # The vertical force balance of the joint coordinate: exact to the
    # statics residual.
    assert f[2] == pytest.approx(weight, rel=1e-9)
    assert abs(f[0]) < 1e-15 and abs(f[1]) < 1e-15
    assert all(c.other == "table" and c.other_kind == "obstacle" and c.other_s is None
               for c in contacts)
    assert all(np.allclose(c.normal, [0, 0, 1]) for c in contacts)
    # The whole rod touches, base to tip.
    s = sorted(c.s for c in contacts)
    assert s[0] == 0.0 and s[-1] == pytest.approx(length, abs=1e-15)
    # Penetration within the stated 1 % of the radius at rest.
    deepest = max(-c.gap for c in contacts)
    assert sim.max_penetration(st.q) == deepest
    assert 0 < deepest < 0.01 * R
    # The contact point lies on the rod's surface: the centreline point
    # less the radius along the normal.
    c = contacts[len(contacts) // 2]
    centre = sim.pose("rod", c.s, st.q)[:3, 3]
    assert np.allclose(c.point, centre - R * c.normal, atol=1e-15)
    assert sim.obstacle_names == ["table"]


def test_a_rod_resting_on_a_table_carries_its_weight_in_a_run():
    """From the equilibrium, a run stays there: its recorded contacts carry
    the weight at every output time; max_penetration and max_contacts are
    those of the recorded contacts."""
    length = 0.3
    sim = on_table(length, friction=0.5)
    q = sim.statics().q
    traj = sim.simulate(0.05, q0=q, output_every=0.01, rtol=1e-8, atol=1e-10)
    weight = RHO * np.pi * R**2 * G * length
    assert len(traj.contacts) == len(traj.t) == 6
    for contacts in traj.contacts:
        assert total_force(contacts)[2] == pytest.approx(weight, rel=1e-6)
    deepest = max(-c.gap for cs in traj.contacts for c in cs)
    assert traj.max_penetration == deepest
    assert traj.max_contacts == max(len(cs) for cs in traj.contacts)
    assert {c.state for cs in traj.contacts for c in cs} <= {"stick", "slip"}


PROPPED = """
[world]
gravity = [0, 0, -9.81]

[[rod]]
name = "arm"
length = 0.5
pieces = 20
strains = ["ky"]
base = { rotation = ROTATION }
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e9, poisson = 0.5 }

[[obstacle]]
name = "table"
shape = "plane"
position = [0, 0, TABLE]
normal = [0, 0, 1]
"""


def test_a_propped_cantilever_matches_beam_theory_and_the_cli(tmp_path, softrod_bin):
    """A stiff cantilever tilted down by theta droops under its weight onto
    a frictionless table half its free tip deflection below the straight
    rod's tip, and only the tip touches (the slope keeps the rest of the
    rod clear). Linear beam theory across the beam, load q cos(theta) and
    prop R cos(theta) (R vertical), tip deflection delta / cos(theta) for
    the vertical drop delta: R = 3 q L / 8 - 3 E I delta / (L^3 cos^2
    theta). The CLI's statics of the same file and the same scene built in
    Python agree with it."""
    length, young, theta = 0.5, 1.0e9, 0.05
    c, s = np.cos(theta), np.sin(theta)
    rotation = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    q_load = RHO * np.pi * R**2 * G
    ei = young * np.pi * R**4 / 4
    free = q_load * length**4 / (8 * ei)  # 3 mm: small deflection
    table = -length * s - R - 0.5 * free
    scene = tmp_path / "propped.toml"
    scene.write_text(PROPPED.replace("TABLE", repr(float(table)))
                     .replace("ROTATION", json.dumps(rotation)))
    sim = softrod.Simulation.from_file(scene)
    st = sim.statics()
    q, contacts = st.q, st.contacts
    assert len(contacts) == 1 and contacts[0].s == pytest.approx(length, abs=1e-12)
    force = total_force(contacts)
    delta = -sim.tip_pose("arm", q)[2, 3] - length * s
    expected = 3 * q_load * length / 8 - 3 * ei * delta / (length**3 * c * c)
    # PCS with 20 pieces under a distributed load: 2e-3 from the beam.
    assert force[2] == pytest.approx(expected, rel=5e-3)
    assert abs(force[0]) < 1e-15 and abs(force[1]) < 1e-15
    assert 0.3 * free < delta < 0.7 * free
    # The penalty is calibrated on a rod's own weight (1 % of r at rest,
    # docs/theory-contact.md CT3); the prop carries far more than the tip's
    # weight, and sinks 2 % of r: below the 50 % at which a run stops.
    assert sim.max_penetration(q) == -contacts[0].gap
    assert 0 < -contacts[0].gap < 0.05 * R

    # Second path: the command line's statics of the same file.
    out = subprocess.run([str(softrod_bin), "statics", str(scene), "--json"], check=True,
                         capture_output=True, text=True).stdout
    cli = json.loads(out)
    np.testing.assert_allclose(q, cli["q"], rtol=1e-12, atol=1e-15)
    assert len(cli["contacts"]) == len(contacts)
    for c, j in zip(contacts, cli["contacts"]):
        assert (c.rod, c.s, c.other, c.other_s) == (j["a"], j["s"], j["b"], j["b_s"])
        assert c.gap == pytest.approx(j["gap"], rel=1e-9, abs=1e-15)
        np.testing.assert_allclose(c.force, j["force"], rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(c.point, j["point"], rtol=1e-12, atol=1e-15)
    assert sim.max_penetration(q) == pytest.approx(cli["max_penetration"], rel=1e-9)

    # Third: the same scene built in Python.
    rod = softrod.Rod(length, 20, ["ky"], name="arm", section=softrod.Circle(R),
                      material=softrod.Material(density=RHO, young=young, poisson=0.5),
                      base={"rotation": rotation})
    py = softrod.Simulation(
        [rod], [0, 0, -G],
        obstacles=[softrod.Obstacle("table", "plane", position=[0, 0, table],
                                    normal=[0, 0, 1])])
    np.testing.assert_allclose(py.statics().q, q, rtol=1e-12, atol=1e-15)


def test_a_simulation_without_contact_has_none():
    sim = softrod.Simulation([table_rod()], [0, 0, -G])
    q = np.zeros(sim.n_dof)
    assert sim.contacts(q) == [] and sim.max_penetration(q) == 0.0
    traj = sim.simulate(0.01, output_every=0.005)
    assert traj.contacts == [[], [], []]
    assert traj.max_penetration == 0.0 and traj.max_contacts == 0
    assert sim.obstacle_names == []


def test_contact_radius_sets_the_surface():
    """A rectangle's contact surface is half its diagonal unless the rod
    sets contact_radius: resting on a table its centreline sits that high."""
    section = softrod.Rectangle(0.02, 0.01)
    for radius in (None, 0.004):
        expected = radius if radius is not None else 0.5 * np.hypot(0.02, 0.01)
        rod = softrod.Rod(0.2, 2, ["ky"], name="bar", section=section, material=material(),
                          contact_radius=radius, base={"position": [0, 0, expected]},
                          joint=softrod.Joint("prismatic", axis=[0, 0, 1]))
        sim = softrod.Simulation([rod], [0, 0, -G],
                                 obstacles=[softrod.Obstacle("table", "plane",
                                                             normal=[0, 0, 1])])
        q = sim.statics().q
        z = sim.pose("bar", 0.1, q)[2, 3]
        assert expected - 0.01 * expected < z <= expected
        assert all(c.gap <= 0 for c in sim.contacts(q))


def test_an_obstacle_carried_by_a_body_moves_with_it():
    """A ball carried by a body that a prismatic joint holds 3 cm below a
    rod: pushing the body up presses the ball into the rod."""
    rod = softrod.Rod(0.3, 3, ["ky"], name="rod", section=softrod.Circle(R), material=material())
    holder = softrod.Body("holder", "world", mass=0.1, inertia=[1e-5] * 3,
                          base={"position": [0.15, 0, -0.05]},
                          joint=softrod.Joint("prismatic", axis=[0, 0, 1]))
    ball = softrod.Obstacle("knob", "sphere", radius=0.03, parent="holder")
    sim = softrod.Simulation([rod], bodies=[holder], obstacles=[ball])
    q = np.zeros(sim.n_dof)
    assert sim.contacts(q) == []
    q[-1] = 0.01 + 1e-4  # the holder's joint: 0.1 mm into the rod
    contacts = sim.contacts(q)
    assert contacts and all(c.other == "knob" for c in contacts)
    assert sim.max_penetration(q) == pytest.approx(1e-4, rel=1e-6)


@pytest.mark.parametrize("obstacle, path", [
    (dict(shape="sphere", radius=-0.03), "obstacle[0].radius"),
    (dict(shape="sphere", radius=float("nan")), "obstacle[0].radius"),
    (dict(shape="plane", normal=[0, 0, 0]), "obstacle[0].normal"),
    (dict(shape="cylinder", radius=0.1), "obstacle[0].axis"),
    (dict(shape="box", rotation=[[1, 0, 0], [0, 1, 0], [0, 0, 2]], half_extents=[1, 1, 1]),
     "obstacle[0].rotation"),
    (dict(shape="box", rotation=np.eye(3), half_extents=[1, 0, 1]), "obstacle[0].half_extents"),
    (dict(shape="plane", normal=[0, 0, 1], friction=-0.5), "obstacle[0].friction"),
    (dict(shape="plane", normal=[0, 0, 1], parent="bal"), "obstacle[0].parent"),
    (dict(shape="cone", radius=0.1), "obstacle[0].shape"),
    (dict(shape="sphere", radius=0.1, normal=[0, 0, 1]), "obstacle[0].normal"),
])
def test_bad_obstacles_raise_naming_the_key(obstacle, path):
    rod = softrod.Rod(0.3, 3, ["ky"], section=softrod.Circle(R), material=material())
    with pytest.raises(softrod.SceneError, match=r"^Simulation: " + path.replace("[", r"\[")):
        softrod.Simulation([rod], obstacles=[softrod.Obstacle("o", **obstacle)])


def test_bad_contact_settings_and_values_raise():
    rod = softrod.Rod(0.3, 3, ["ky"], section=softrod.Circle(R), material=material())
    with pytest.raises(softrod.SceneError, match=r"contact\.friction"):
        softrod.Simulation([rod], contact=softrod.ContactSettings(rods=True, friction=-1))
    with pytest.raises(softrod.SceneError, match=r"contact\.restitution"):
        softrod.Simulation([rod], contact={"restitution": 2.0})
    with pytest.raises(softrod.SceneError, match=r"contact\.selfish: unknown key"):
        softrod.Simulation([rod], contact={"selfish": True})
    with pytest.raises(softrod.InputError, match=r"obstacle\[0\]\.position: a object"):
        softrod.Simulation([rod], obstacles=[{"name": "o", "shape": "plane",
                                              "position": object(), "normal": [0, 0, 1]}])
    with pytest.raises(softrod.InputError, match="contact: give a dict"):
        softrod.Simulation([rod], contact=[True])
    with pytest.raises(softrod.InputError, match=r"contact_radius"):
        softrod.Rod(0.3, 3, section=softrod.Circle(R), material=material(), contact_radius=-1.0)
    # A rod that starts inside an obstacle, deeper than 1 % of its radius.
    with pytest.raises(softrod.SoftrodError, match="table"):
        softrod.Simulation([rod], obstacles=[softrod.Obstacle("table", "plane",
                                                              position=[0, 0, 0.005],
                                                              normal=[0, 0, 1])]).simulate(0.01)
    # The state given must have the model's size.
    sim = on_table()
    with pytest.raises(softrod.InputError, match="q"):
        sim.contacts(np.zeros(sim.n_dof + 1))
    with pytest.raises(softrod.InputError, match="t must be finite"):
        sim.contacts(np.zeros(sim.n_dof), t=float("nan"))


def test_penetration_stays_within_the_bound_or_stops_the_run():
    """As `softrod run` (crates/softrod-cli/tests/contact.rs): the contact
    stiffness follows the force carried (docs/theory-contact.md CT15), so a
    2 N load on the tip of the dropped rod of
    examples/rod_dropped_on_table.toml (130 times the tip point's weight; it
    sank 43 % of the radius with the stiffness of the points' own weight)
    stays within the 10 % bound, landing included, and the trajectory says
    nothing, like the drop without it; a load no stiffness can follow
    within a step (2 kN, suddenly) stops the run with a SimulationError
    naming the rod, s, the obstacle, the time and the depth."""
    from pathlib import Path

    text = (Path(__file__).parents[3] / "examples" / "rod_dropped_on_table.toml").read_text()
    text = text[: text.index("[run]")]
    run = dict(duration=0.2, output_every=5e-3, rtol=1e-5, atol=1e-8)

    def load(force):
        return f'[[load]]\nrod = "rod"\ns = 0.2\nforce = [0.0, 0.0, {force}]\n'

    for extra in ["", load(-2.0)]:
        tr = softrod.Simulation.from_toml(text + extra).simulate(**run)
        assert 0.0 < tr.max_penetration < 0.1 * 0.01
        assert not [w for w in tr.warnings if w.startswith("contact:")]
    with pytest.raises(softrod.SimulationError) as err:
        softrod.Simulation.from_toml(text + load(-2000.0)).simulate(**run)
    message = str(err.value)
    assert "rod 0 ('rod') penetrates obstacle 'table' at s = 0.200000 m, t = " in message
    assert "> bound 1.500e-3 m" in message
