"""A run or statics from the initial state starts from a fresh contact state
(docs/theory-contact.md CT15: base stiffness, no friction anchors), whatever
was called before it. The reference is a simulation built from the same
scene that has done nothing else: the results must agree bit for bit."""

from __future__ import annotations

import pickle

import numpy as np

import softrod

# A free rod lying across a 20° incline with mu = 0.5: it sticks, its
# weight held by the anchored springs of CT5 from the first step.
_A = np.radians(20.0)
_N = [float(np.sin(_A)), 0.0, float(np.cos(_A))]
INCLINE = f"""
[world]
gravity = [0.0, 0.0, -9.81]

[[rod]]
name = "rod"
length = 0.2
pieces = 4
strains = ["ky", "kz"]
joint = {{ type = "free" }}
base = {{ position = [{0.01 * _N[0]!r}, -0.1, {0.01 * _N[2]!r}], rotation = [[0, -1, 0], [1, 0, 0], [0, 0, 1]] }}
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}

[[obstacle]]
name = "slope"
shape = "plane"
position = [0.0, 0.0, 0.0]
normal = [{_N[0]!r}, 0.0, {_N[2]!r}]
friction = 0.5

[run]
duration = 0.1
integrator = "esdirk"
rtol = 1.0e-6
atol = 1.0e-8
output_every = 0.01
"""

# A rope clamped level on top of a cylinder with mu = 0.3, bent over it by
# a tip load far above its weight: statics raises the contacts' stiffness.
ROPE = """
[world]
gravity = [0.0, 0.0, -9.81]

[[rod]]
name = "rope"
length = 0.2
pieces = 16
strains = ["ky", "qx"]
base = { position = [-0.1, 0.0, 0.032] }
section = { shape = "circle", radius = 0.002 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[load]]
rod = "rope"
s = 0.2
force = [0.0, 0.0, -1.0]
frame = "world"

[[obstacle]]
name = "capstan"
shape = "cylinder"
position = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
radius = 0.03
friction = 0.3

[run]
duration = 0.01
integrator = "esdirk"
rtol = 1.0e-6
atol = 1.0e-8
output_every = 0.002
"""


def same(a, b):
    """Bit-for-bit equal trajectories (samples and recorded contact forces)."""
    assert np.array_equal(a.t, b.t)
    assert np.array_equal(a.q, b.q)
    assert np.array_equal(a.qdot, b.qdot)
    assert len(a.contacts) == len(b.contacts)
    for ca, cb in zip(a.contacts, b.contacts):
        assert [c.force.tobytes() for c in ca] == [c.force.tobytes() for c in cb]


def test_contact_a_second_run_repeats_the_first_bit_for_bit():
    want = softrod.Simulation.from_toml(INCLINE).simulate()
    sim = softrod.Simulation.from_toml(INCLINE)
    same(sim.simulate(), want)
    same(sim.simulate(), want)
    assert len(want.contacts[-1]) > 0


def test_contact_a_run_after_statics_is_the_run_alone():
    want = softrod.Simulation.from_toml(ROPE).simulate()
    sim = softrod.Simulation.from_toml(ROPE)
    sim.statics()
    same(sim.simulate(), want)


def test_contact_statics_after_a_run_is_statics_alone():
    fresh = softrod.Simulation.from_toml(ROPE)
    want = fresh.statics()
    sim = softrod.Simulation.from_toml(ROPE)
    sim.simulate()
    got = sim.statics()
    assert np.array_equal(got.q, want.q)
    assert len(want.contacts) > 0
    assert [c.force.tobytes() for c in got.contacts] == [
        c.force.tobytes() for c in want.contacts
    ]
    # contacts(q) reports what the last statics committed: the same as
    # the statics result lists.
    assert [c.force.tobytes() for c in sim.contacts(got.q)] == [
        c.force.tobytes() for c in got.contacts
    ]


def test_contact_a_controlled_run_repeats_and_a_pickle_runs_as_a_fresh_one():
    sim = softrod.Simulation.from_toml(INCLINE)

    def controller(t, q, qdot):
        return np.zeros(0)

    first = sim.simulate(controller=controller)
    same(sim.simulate(controller=controller), first)
    # A pickle carries the scene, not the contact state of past runs: its
    # run and the original's next run are the run of a fresh simulation.
    copy = pickle.loads(pickle.dumps(sim))
    want = softrod.Simulation.from_toml(INCLINE).simulate()
    same(copy.simulate(), want)
    same(sim.simulate(), want)
