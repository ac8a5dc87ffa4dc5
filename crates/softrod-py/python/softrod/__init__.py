"""softrod: soft manipulators (slender soft arms, tentacles, cable-driven
continuum robots) simulated with the Piecewise Constant Strain Cosserat-rod
model, from Python.

>>> import softrod
>>> rod = softrod.Rod(length=0.5, pieces=8, strains=["ky", "qx", "qz"],
...                   section=softrod.Circle(0.01),
...                   material=softrod.Material(density=1000, young=1e7, poisson=0.5))
>>> sim = softrod.Simulation(rods=[rod], gravity=[0, 0, -9.81])
>>> traj = sim.simulate(duration=0.1, output_every=1e-2)
>>> traj.tip_position.shape
(11, 3)

Or from a scene file: ``softrod.Simulation.from_file("examples/cantilever_gravity.toml")``
(``Simulation.from_toml(text)`` for scene text, ``Simulation.from_dict(scene)``
for a scene as dicts). Bodies, joints, closures, obstacles and contact
settings: ``softrod.Body``, ``Joint``, ``Closure``, ``Obstacle``,
``ContactSettings`` (the scene's tables, see ``softrod.builders``), given to
``Simulation(rods, ..., bodies=, closures=, obstacles=, contact=)``.

Learning and clusters (optional extras, not imported by ``import softrod``):
``softrod.envs`` (Gymnasium environments, ``pip install softrod[rl]``) and
``softrod.distributed`` (Ray, ``pip install softrod[ray]``); see docs/envs.md.

Units are SI. ``q`` are the generalized coordinates in the order of
``Simulation.q_names``: joint coordinates and strain coordinates (pieces
base to tip, the selected strains in the order kx, ky, kz, qx, qy, qz); arrays are
float64 numpy arrays; poses are 4x4 homogeneous transforms in the world
frame; twists and wrenches are 6-vectors, angular part first. Time is an
argument, never hidden state: the dynamics calls take it first,
``f(t, q, qdot)``, the kinematic queries as the keyword ``t`` (default 0;
only prescribed joints move with it). Durations default to the scene's
``[run] duration`` in ``simulate`` and ``simulate_many`` alike. The
equations are in docs/theory.md of the repository.
"""

from __future__ import annotations

from softrod._errors import (
    InputError,
    InternalError,
    NotSupportedError,
    SceneError,
    SimulationError,
    SoftrodError,
)
from softrod._softrod import (
    BatchStepper,
    Cable,
    Circle,
    Contact,
    Energies,
    Material,
    Modes,
    PointLoad,
    Rectangle,
    Rod,
    Section,
    Settings,
    Simulation,
    State,
    Statics,
    TaperedCircle,
    Trajectory,
    Tube,
    INTEGRATORS,
    __version__,
    simulate_many,
)
from softrod.builders import (
    Base,
    Body,
    Closure,
    ContactSettings,
    Frame,
    Joint,
    Obstacle,
    Prescribed,
)

#: The strain names of ``Rod(strains=...)``, in coordinate order: torsion,
#: two bendings, stretch, two shears (body frame, local x along the rod).
STRAINS = ("kx", "ky", "kz", "qx", "qy", "qz")

__all__ = [
    "INTEGRATORS",
    "STRAINS",
    "BatchStepper",
    "Base",
    "Body",
    "Cable",
    "Circle",
    "Closure",
    "Contact",
    "ContactSettings",
    "Frame",
    "Joint",
    "Obstacle",
    "Prescribed",
    "Energies",
    "InputError",
    "InternalError",
    "Material",
    "Modes",
    "NotSupportedError",
    "PointLoad",
    "Rectangle",
    "Rod",
    "SceneError",
    "Section",
    "Settings",
    "Simulation",
    "SimulationError",
    "SoftrodError",
    "State",
    "Statics",
    "TaperedCircle",
    "Trajectory",
    "Tube",
    "__version__",
    "simulate_many",
]
