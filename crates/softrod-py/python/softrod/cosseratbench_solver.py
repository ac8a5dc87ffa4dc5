"""A cosseratbench solver adapter for softrod.

`cosseratbench <https://pypi.org/project/cosseratbench/>`_ (0.3) finds it
through the entry point ``softrod`` of the group ``cosseratbench.solvers``
that this package declares, so after installing softrod::

    cosseratbench run cantilever -s softrod -s pyelastica

compares softrod with the PyElastica and MuJoCo adapters it ships.

What softrod models of a scenario: rods clamped at their start and free at
their end, starting straight and unstretched, under gravity and constant
point loads in the world frame, with stretch and shear (all six strains).
What it does not: contact of any kind, pinned or driven ends, bent or
pre-stretched initial shapes. Experiments that need contact are reported
"unsupported" by cosseratbench from :attr:`SoftrodSolver.capabilities`;
the others that fall outside the model raise ``NotImplementedError`` with
the reason, which cosseratbench reports as "unsupported" too.

Numerics: the stiff, error-controlled Rosenbrock-W integrator (softrod's
default) at ``rtol = 1e-5 * time_step_scale**3`` (its step scales as the
cube root of the tolerance, so ``time_step_scale`` scales the steps it
takes), one PCS piece per element. Material damping is added only where the
scenario asks for quasi-static settling: a Kelvin-Voigt viscosity that
damps the slowest bending mode critically (``mu = 2 E / (3 omega_1)``,
since the bending damping of softrod's material is ``3 mu J``, the
stiffness ``E J``), with ``omega_1`` from ``Scenario.slowest_frequency``.
"""

from __future__ import annotations

import numpy as np

import softrod

try:  # only needed when cosseratbench loads the adapter
    from cosseratbench.scenario import End, EndCondition, Scenario
    from cosseratbench.solver import Capability, Diverged
    from cosseratbench.trajectory import Trajectory
except ImportError as error:  # pragma: no cover - exercised without cosseratbench
    raise ImportError(
        "softrod.cosseratbench_solver needs cosseratbench: pip install cosseratbench"
    ) from error

#: Relative tolerance at time_step_scale = 1: the tip of the benchmark's
#: cantilever is then converged to < 1e-4 of its deflection.
RTOL = 1e-5
#: Absolute tolerance on strains and strain rates.
ATOL = 1e-8
#: Straightness of a centerline: distance of every point from the line
#: through its ends, relative to the length.
STRAIGHT_TOL = 1e-9


def _unsupported(what: str) -> NotImplementedError:
    return NotImplementedError(f"softrod: {what}")


def _base_and_length(rod) -> tuple[np.ndarray, float]:
    """The clamped base pose (4x4) of a straight scenario rod: local x along
    the rod, local z along the scenario's ``normal`` projected across it (the
    material direction d1 the benchmark tracks), y = z x x."""
    points = np.asarray(rod.centerline, dtype=float)
    axis = points[-1] - points[0]
    length = float(np.linalg.norm(axis))
    t = axis / length
    off = points - points[0]
    across = off - np.outer(off @ t, t)
    if np.abs(np.linalg.norm(across, axis=1)).max() > STRAIGHT_TOL * length:
        raise _unsupported("rods start from their straight stress-free shape; this one is bent")
    if rod.rest_arc_length is not None and abs(rod.length - length) > STRAIGHT_TOL * length:
        raise _unsupported("rods start unstretched; this one starts stretched")
    d1 = np.asarray(rod.normal, dtype=float)
    d1 = d1 - (d1 @ t) * t
    d1 /= np.linalg.norm(d1)
    g = np.eye(4)
    g[:3, 0], g[:3, 1], g[:3, 2], g[:3, 3] = t, np.cross(d1, t), d1, points[0]
    return g, length


class SoftrodSolver:
    """softrod's PCS Cosserat rods in cosseratbench."""

    name = "softrod"
    backend_version = softrod.__version__
    # All six strains; no contact of any kind.
    capabilities = frozenset({Capability.STRETCH, Capability.SHEAR})

    def __init__(self, time_step_scale: float = 1.0) -> None:
        if not time_step_scale > 0:
            raise ValueError(f"time_step_scale must be positive, got {time_step_scale}")
        self.rtol = RTOL * time_step_scale**3

    def _viscosity(self, scenario: Scenario, rod) -> float:
        if not scenario.quasi_static:
            return 0.0
        return 2.0 * rod.material.youngs_modulus / (3.0 * scenario.slowest_frequency())

    def settings(self, scenario: Scenario, *, n_elements: int, n_frames: int) -> dict:
        """The numerical choices made for a run."""
        return {
            "integrator": "Rosenbrock-W ROS34PW2 (stiff, error-controlled)",
            "rtol": self.rtol,
            "atol": ATOL,
            "pieces_per_rod": n_elements,
            "strains": "all",
            "kelvin_voigt_viscosity": [self._viscosity(scenario, r) for r in scenario.rods],
        }

    def _simulation(self, scenario: Scenario, n_elements: int) -> softrod.Simulation:
        if scenario.obstacles:
            raise _unsupported("no contact with obstacles")
        if scenario.self_contact:
            raise _unsupported("no self-contact, and this scenario lets a rod reach itself")
        rods = []
        for i, spec in enumerate(scenario.rods):
            if spec.start is not EndCondition.CLAMPED or spec.end is not EndCondition.FREE:
                raise _unsupported(
                    f"rods are clamped at the start and free at the end; rod {i} is "
                    f"{spec.start.value} at the start and {spec.end.value} at the end"
                )
            if spec.start_motion is not None or spec.end_motion is not None:
                raise _unsupported("clamped ends hold still; this scenario drives one")
            base, length = _base_and_length(spec)
            loads = [
                softrod.PointLoad(s=length, force=list(load.force), frame="world")
                for load in spec.loads
                if load.at is End.END  # a load on the clamp is taken by the clamp
            ]
            m = spec.material
            material = softrod.Material(
                density=m.density,
                young=m.youngs_modulus,
                shear_modulus=m.shear_modulus,
                viscosity=self._viscosity(scenario, spec),
            )
            rods.append(
                softrod.Rod(
                    length=length,
                    pieces=n_elements,
                    strains="all",
                    section=softrod.Circle(spec.radius),
                    material=material,
                    base=base,
                    loads=loads,
                    name=f"rod{i}",
                )
            )
        return softrod.Simulation(rods=rods, gravity=list(scenario.gravity))

    def run(self, scenario: Scenario, *, n_elements: int, n_frames: int) -> Trajectory:
        sim = self._simulation(scenario, n_elements)
        duration = scenario.duration
        try:
            traj = sim.simulate(
                duration,
                integrator="rosenbrock",
                rtol=self.rtol,
                atol=ATOL,
                output_every=duration / (n_frames - 1),
            )
        except softrod.SimulationError as error:
            raise Diverged(str(error), time=error.time) from error
        if len(traj) != n_frames:
            raise RuntimeError(f"softrod returned {len(traj)} frames, expected {n_frames}")
        positions, directors = [], []
        for r in range(len(scenario.rods)):
            ends = np.linspace(0.0, scenario.rods[r].length, n_elements + 1)
            mids = 0.5 * (ends[1:] + ends[:-1])
            p = np.empty((n_frames, n_elements + 1, 3))
            d = np.empty((n_frames, n_elements, 3))
            for k in range(n_frames):
                p[k] = traj.shape(k, rod=r)
                # d1 is the section's local z axis (see _base_and_length).
                d[k] = sim.pose(r, mids, traj.q[k])[:, :3, 2]
            positions.append(p)
            directors.append(d)
        return Trajectory(np.linspace(0.0, duration, n_frames), tuple(positions), tuple(directors))
