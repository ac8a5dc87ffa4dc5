"""A cosseratbench solver adapter for softrod.

`cosseratbench <https://pypi.org/project/cosseratbench/>`_ (0.3) finds it
through the entry point ``softrod`` of the group ``cosseratbench.solvers``
that this package declares, so after installing softrod::

    cosseratbench run cantilever -s softrod -s pyelastica

compares softrod with the PyElastica, MuJoCo and dismech adapters it ships.

How a scenario becomes a softrod scene (docs/scene-format.md), rod by rod,
one PCS piece per element, all six strains:

- the start: ``FREE`` a free joint, ``PINNED`` a spherical joint,
  ``CLAMPED`` the rod's fixed base; a driven start (``start_motion``) a
  prescribed free joint, and one that slides along an axis a prescribed
  body carrying a carriage on a free prismatic joint, the rod hanging from
  the carriage;
- the end: ``PINNED`` a ball closure to the world, ``CLAMPED`` a weld
  closure to the world; a driven end a weld to a body on a prescribed free
  joint, and one that slides a weld to a carriage on that body;
- the starting shape: a bent or stretched ``centerline`` is fitted by the
  rod's strains (``[initial] shape`` with ``[s, x, y, z]`` rows, ``s`` the
  unstretched arc length, so a pre-stretched start is a stretch strain),
  the base frame along the curve's tangent at ``s = 0`` with local z the
  scenario's ``normal`` (its director ``d1``); closures are anchored where
  the fitted ends are, so they hold at the start as softrod requires;
- loads: dead point loads at ``s = 0`` or ``s = L``; gravity.

A motion's samples are followed through the not-a-knot cubic spline of a
prescribed joint (C2) where cosseratbench interpolates them linearly: the
two agree at the samples, and on the experiments' motions (a cosine ramp
sampled 121 times, a straight descent) the spline is the sampled motion
itself.

What softrod does not model yet is contact: obstacles and rods touching rods
or themselves (issue 24). Experiments that need it are reported unsupported
by cosseratbench from :attr:`SoftrodSolver.capabilities`. A scenario with
obstacles is refused with the reason; one that only says a rod *could* reach
itself (``self_contact``) or has several rods runs without contact between
them, says so in its ``settings``, and cosseratbench's ``max_rod_overlap``
of every run shows whether anything passed through anything. When contact
lands, :func:`_contact_tables` emits it (its docstring says what) and the
contact capabilities are added.

Numerics, the same rules for every scenario, chosen from what the scenario
declares (``settings`` states them):

- **Dynamics** (``quasi_static`` false: the motion is the result): the
  generalized-alpha method (rho_inf = 0.9) at a fixed step of
  ``1 / STEPS_PER_PERIOD`` of the slowest period ``2 pi /
  Scenario.slowest_frequency()``, times ``time_step_scale``; no damping.
  An error-controlled method spends its steps resolving the stiff
  stretch and shear vibrations that any starting shape rings with; a fixed
  step that resolves the slow motion leaves them to the method's
  unconditional stability.
- **Quasi-static** (the equilibrium is the result): Radau IIA order 5
  (L-stable, error-controlled) at ``rtol = RTOL_QUASI_STATIC *
  time_step_scale**4`` (its steps scale as the fourth root of the
  tolerance) and ``atol = ATOL_QUASI_STATIC``: the tolerances bound only the
  path to the equilibrium. Damping: linear drag proportional to mass (force
  ``-c_t v``, moment ``-c_r w`` per unit length, ``c_t = 2 omega_1 rho A``,
  ``c_r = 2 omega_1 rho I``), critical for the slowest mode ``omega_1 =
  Scenario.slowest_frequency()``: the rule of the PyElastica, MuJoCo and
  dismech adapters, so every solver settles through the same damping.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace

import numpy as np

import softrod

try:  # only needed when cosseratbench loads the adapter
    from cosseratbench.scenario import End, EndCondition, Motion, Scenario
    from cosseratbench.solver import Capability, Diverged
    from cosseratbench.trajectory import Trajectory
except ImportError as error:  # pragma: no cover - exercised without cosseratbench
    raise ImportError(
        "softrod.cosseratbench_solver needs cosseratbench: pip install cosseratbench"
    ) from error

#: Steps per slowest period of a dynamic run (generalized-alpha, fixed step).
STEPS_PER_PERIOD = 1000
#: Relative tolerance of a quasi-static run at time_step_scale = 1.
RTOL_QUASI_STATIC = 1e-3
#: Absolute tolerance of a quasi-static run on strains [1/m], joint
#: coordinates [rad, m] and their rates: like the relative one it bounds the
#: path, not the equilibrium (the twist experiment's growth rates, measured
#: on the path from 1e-5 m sideways, agree to 5e-6 with atol 1e-8, while
#: the catenary's ringing stretch costs 18 times the steps there).
ATOL_QUASI_STATIC = 1e-5
#: Order of the step in the tolerance: Radau IIA(5)'s error estimate is
#: O(h^4), so its step scales as rtol^(1/4).
STEP_ORDER = 4
#: A centerline is straight when every point is within this many rod
#: lengths of the line through its ends.
STRAIGHT_TOL = 1e-9
#: The strains a bent or stretched start is fitted with: bending and
#: stretch. The scenarios' rods start untwisted (directors carried by
#: parallel transport, which for PCS pieces is zero torsion kx) and
#: unsheared, so those strains start at zero; fitted freely, shear takes up
#: the misfit of the positions and starts the rod ringing at its shear
#: frequencies.
FIT_STRAINS = ("ky", "kz", "qx")


def _unsupported(what: str) -> NotImplementedError:
    return NotImplementedError(f"softrod: {what}")


def _scene(text: str) -> softrod.Simulation:
    """A Simulation from scene text (the one place the adapter reads a scene)."""
    return softrod.Simulation.from_toml(text)


def _toml(value) -> str:
    """A TOML value: numbers as shortest round-trip decimals, strings,
    booleans, arrays and inline tables."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        x = float(value)
        if not np.isfinite(x):
            raise ValueError(f"softrod: a scenario value is not finite: {x}")
        return repr(x + 0.0)  # + 0.0: no "-0.0"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + " }"
    if isinstance(value, np.ndarray):
        value = value.tolist()
    return "[" + ", ".join(_toml(v) for v in value) + "]"


def _table(header: str, entries: dict) -> str:
    """``[header]`` (or ``[[header]]`` for ``header = "[name]"``) and its keys."""
    return f"[{header}]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in entries.items()) + "\n"


def _pose(rotation: np.ndarray, position: np.ndarray) -> dict:
    """A scene `base` (rotation rows map the local frame to the parent's)."""
    return {"position": np.asarray(position, float), "rotation": np.asarray(rotation, float)}


def _arc(spec) -> np.ndarray:
    """Unstretched arc length to each centerline point (the scenario's rule)."""
    if spec.rest_arc_length is not None:
        return np.asarray(spec.rest_arc_length, dtype=float)
    points = np.asarray(spec.centerline, dtype=float)
    return np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))))


def _fit_abscissae(spec) -> np.ndarray:
    """The arc lengths of the centerline points, the last pulled in by 1e-14
    of the length: softrod checks them against the sum of its piece lengths,
    which rounds below the rod's length by a few ulps (1.0 / 10 * 10 < 1.0)."""
    return np.minimum(_arc(spec), spec.length * (1.0 - 1e-14))


def _is_straight_and_unstretched(spec) -> bool:
    points = np.asarray(spec.centerline, dtype=float)
    axis = points[-1] - points[0]
    length = float(np.linalg.norm(axis))
    off = points - points[0]
    across = off - np.outer(off @ axis / length**2, axis)
    straight = np.linalg.norm(across, axis=1).max() <= STRAIGHT_TOL * length
    return bool(straight and abs(spec.length - length) <= STRAIGHT_TOL * length)


def _start_frame(spec) -> tuple[np.ndarray, np.ndarray]:
    """The rod's frame at s = 0 as (rotation, position): local x along the
    centerline's tangent there, local z the scenario's ``normal`` projected
    across it (the director d1 cosseratbench tracks), y = z x x.

    The tangent of a bent start is that of the circle through its first
    three points (exact on a circular arc, O(h^2) of the centerline's spacing
    on any smooth curve), not the first chord, which is off by half its
    turning angle.
    """
    points = np.asarray(spec.centerline, dtype=float)
    t = points[-1] - points[0]
    if len(points) >= 3 and not _is_straight_and_unstretched(spec):
        a, m, b = points[:3]
        chord = b - a
        normal = np.cross(m - a, b - m)
        t = chord
        if np.linalg.norm(normal) > 1e-15 * np.linalg.norm(chord) ** 2:
            # The chord a-b turns the circle's tangent at a by half the arc's
            # turn, the angle at m's opposite: the inscribed angle theorem.
            cos_m = -((m - a) @ (b - m)) / (np.linalg.norm(m - a) * np.linalg.norm(b - m))
            half_turn = np.pi - np.arccos(np.clip(cos_m, -1.0, 1.0))
            t = _rotation(normal / np.linalg.norm(normal), -half_turn) @ chord
    t = t / np.linalg.norm(t)
    d1 = np.asarray(spec.normal, dtype=float)
    d1 = d1 - (d1 @ t) * t
    if np.linalg.norm(d1) < 1e-12:
        raise ValueError("softrod: the rod's normal is along its tangent at the start")
    d1 /= np.linalg.norm(d1)
    rotation = np.column_stack([t, np.cross(d1, t), d1])
    return rotation, points[0]


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` about the unit ``axis`` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def _arc_strains(spec, n_elements: int, frame: np.ndarray) -> np.ndarray:
    """A starting guess of the strains (ky, kz, qx) per piece: each piece the
    circular arc through the centerline at its two ends and its middle
    (curvature, bending plane and stretched length), the frame turned by it
    about an axis across the tangent, so without twist. Exact for a circular
    arc; the fit refines the rest."""
    arc = _arc(spec)
    points = np.asarray(spec.centerline, dtype=float)
    s = np.linspace(0.0, spec.length, 2 * n_elements + 1)
    at = np.column_stack([np.interp(s, arc, points[:, k]) for k in range(3)])
    h = spec.length / n_elements
    strains = np.zeros((n_elements, 3))
    for i in range(n_elements):
        a, m, b = at[2 * i], at[2 * i + 1], at[2 * i + 2]
        chord = float(np.linalg.norm(b - a))
        normal = np.cross(m - a, b - m)
        sine = float(np.linalg.norm(normal))
        curvature = 2.0 * sine / (np.linalg.norm(m - a) * np.linalg.norm(b - m) * chord)
        turn = 2.0 * np.arcsin(min(curvature * chord / 2.0, 1.0))
        along = turn / curvature if turn > 1e-12 else chord
        axis = np.zeros(3)
        if turn > 1e-12:
            tangent = frame[:, 0]
            axis = normal - (normal @ tangent) * tangent
            axis /= np.linalg.norm(axis)
        local = frame.T @ axis * (turn / h)
        strains[i] = (local[1], local[2], along / h)
        if turn > 1e-12:
            frame = _rotation(axis, turn) @ frame
    return strains


def _prescribed(motion: Motion, frame: np.ndarray) -> dict:
    """A free joint's prescribed curve for ``motion`` of a frame whose
    rotation (world) is ``frame``: the joint's coordinates are (rotation
    vector, translation) in that frame (docs/theory.md D50), so the motion's
    world rotation vector r and displacement d become (frame^T r, frame^T d)."""
    r = np.asarray(motion.rotation, dtype=float) @ frame
    d = np.asarray(motion.displacement, dtype=float) @ frame
    return {"times": np.asarray(motion.times, float), "values": np.hstack([r, d])}


@dataclass
class _Body:
    name: str
    parent: str
    base: dict
    joint: dict
    mass: float
    inertia: float

    def toml(self) -> str:
        return _table(
            "[body]",
            {
                "name": self.name,
                "parent": self.parent,
                "base": self.base,
                "joint": self.joint,
                "mass": self.mass,
                "inertia": [self.inertia] * 3,
            },
        )


def _contact_tables(scenario: Scenario) -> str:
    """The scene's contact, once softrod has it (issue 24); until then a refusal.

    What it will emit (docs/scene-format.md, "Contact"):

    - each ``Cylinder`` as ``[[obstacle]] shape = "cylinder"`` (``position =
      center``, ``axis``, ``radius``): softrod's cylinder is infinite, which
      is the scenario's wherever rods stay within its ``length`` (they do on
      the capstan; otherwise a ``"capsule"`` of that length is the nearest
      shape, with round ends);
    - each ``Plane`` as ``[[obstacle]] shape = "plane"`` (``position = point``,
      ``normal``);
    - each obstacle's ``friction`` the larger of its own and the rods' (the
      scenario's rule; exact with one rod, or rods of one coefficient);
    - ``[contact] rods = true`` with more than one rod (rods always collide
      with each other), ``self = scenario.self_contact``, ``friction`` the
      rods' coefficient (the larger where they differ);
    - ``restitution = 0`` everywhere (the scenarios state none).

    The capabilities ``ROD_CONTACT``, ``ROD_FRICTION``, ``CYLINDER_CONTACT``
    and ``PLANE_CONTACT`` are then added, and ``settings`` states the
    contact's own numbers (penetration allowed, stiffness or barrier width).
    """
    if scenario.obstacles:
        kinds = sorted({o.kind for o in scenario.obstacles})
        raise _unsupported(f"no contact with obstacles yet ({', '.join(kinds)}; issue 24)")
    return ""


@dataclass
class _Part:
    """Rods simulated together, as one softrod simulation, and what building
    it measured."""

    #: The scenario's indices of the rods, in the simulation's rod order.
    rods: tuple[int, ...]
    sim: softrod.Simulation
    scene: str
    #: Per rod: the largest distance of the fitted start from the scenario's
    #: centerline points [m] (round-off for a straight start).
    fit_error: list[float]
    #: The largest distance between a closure's anchor and the scenario's
    #: end point it stands for [m] (the fitted end, where softrod anchors it).
    anchor_offset: float


def _parts(scenario: Scenario, n_elements: int, damping_rate: float) -> list[_Part]:
    """The scenario as independent simulations. Rods that nothing couples
    (no body, closure or contact joins two rods; contact between rods is not
    modelled yet) move exactly as they would together, and apart they cost
    the sum of their runs rather than a run of all their coordinates at once
    (a closed model's Newton matrices are dense)."""
    rods = scenario.rods
    if len(rods) == 1:
        return [_Part((0,), *_build(scenario, n_elements, damping_rate))]
    return [
        _Part((i,), *_build(replace(scenario, rods=(spec,)), n_elements, damping_rate))
        for i, spec in enumerate(rods)
    ]


class SoftrodSolver:
    """softrod's PCS Cosserat rods in cosseratbench."""

    name = "softrod"
    backend_version = softrod.__version__
    # All six strains; contact arrives with issue 24 (see _contact_tables).
    capabilities = frozenset({Capability.STRETCH, Capability.SHEAR})

    def __init__(self, time_step_scale: float = 1.0) -> None:
        if not time_step_scale > 0:
            raise ValueError(f"time_step_scale must be positive, got {time_step_scale}")
        self.time_step_scale = time_step_scale
        self._cache: dict = {}

    def numerics(self, scenario: Scenario) -> dict:
        """The integrator and its settings for ``scenario`` (keywords of
        ``softrod.Simulation.simulate``)."""
        if scenario.quasi_static:
            return {
                "integrator": "radau5",
                "rtol": RTOL_QUASI_STATIC * self.time_step_scale**STEP_ORDER,
                "atol": ATOL_QUASI_STATIC,
            }
        period = 2.0 * np.pi / scenario.slowest_frequency()
        return {
            "integrator": "generalized-alpha",
            "dt": period / STEPS_PER_PERIOD * self.time_step_scale,
        }

    # -- numerics ---------------------------------------------------------

    @staticmethod
    def _damping_rate(scenario: Scenario) -> float:
        """Mass-proportional damping rate [1/s]: 2 omega_1 when quasi-static."""
        return 2.0 * scenario.slowest_frequency() if scenario.quasi_static else 0.0

    def settings(self, scenario: Scenario, *, n_elements: int, n_frames: int) -> dict:
        """The numerical choices made for a run, and what building it measured."""
        parts = self._parts(scenario, n_elements)
        rate = self._damping_rate(scenario)
        rods = scenario.rods
        fit = np.zeros(len(rods))
        for part in parts:
            fit[list(part.rods)] = part.fit_error
        touching = len(rods) > 1 or scenario.self_contact
        return {
            **self.numerics(scenario),
            "pieces_per_rod": n_elements,
            "strains": "all",
            "simulations": len(parts),
            "damping": "mass-proportional drag" if rate else "none",
            "damping_rate": rate,
            "drag_translational": [rate * r.material.density * r.area for r in rods],
            "drag_rotational": [
                rate * r.material.density * r.second_moment_of_area for r in rods
            ],
            "start_fit_error": fit.tolist(),
            "closure_anchor_offset": max(p.anchor_offset for p in parts),
            **({"rod_contact": "not modelled (issue 24)"} if touching else {}),
        }

    def _parts(self, scenario: Scenario, n_elements: int) -> list[_Part]:
        key = (scenario, n_elements)
        if key not in self._cache:
            self._cache.clear()  # one scenario at a time: the runner's warm-up, then the run
            self._cache[key] = _parts(scenario, n_elements, self._damping_rate(scenario))
        return self._cache[key]

    def run(self, scenario: Scenario, *, n_elements: int, n_frames: int) -> Trajectory:
        duration = scenario.duration
        positions = [None] * len(scenario.rods)
        directors = [None] * len(scenario.rods)
        for part in self._parts(scenario, n_elements):
            sim = part.sim
            try:
                traj = sim.simulate(
                    duration, output_every=duration / (n_frames - 1), **self.numerics(scenario)
                )
            except softrod.SimulationError as error:
                raise Diverged(str(error), time=error.time) from error
            if len(traj) != n_frames:
                raise RuntimeError(f"softrod returned {len(traj)} frames, expected {n_frames}")
            for r, index in enumerate(part.rods):
                ends = np.linspace(0.0, scenario.rods[index].length, n_elements + 1)
                mids = 0.5 * (ends[1:] + ends[:-1])
                p = np.empty((n_frames, n_elements + 1, 3))
                d = np.empty((n_frames, n_elements, 3))
                for k in range(n_frames):
                    p[k] = traj.shape(k, rod=r)
                    # d1 is the section's local z axis (see _start_frame); the
                    # poses of driven models depend on the time of their drives.
                    d[k] = sim.pose(r, mids, traj.q[k], t=float(traj.t[k]))[:, :3, 2]
                positions[index], directors[index] = p, d
        times = np.linspace(0.0, duration, n_frames)
        return Trajectory(times, tuple(positions), tuple(directors))


def _build(
    scenario: Scenario, n_elements: int, damping_rate: float
) -> tuple[softrod.Simulation, str, list[float], float]:
    """The scenario as a softrod simulation, in three scenes: one that fits
    the rods' starting shapes with FIT_STRAINS, the open model (no end
    bodies, no closures) at the fitted coordinates, where the ends are read,
    and the whole model with the closures anchored at those ends (a closure
    must hold at the start) and the coordinates carried over by name."""
    contact = _contact_tables(scenario)
    rods, bodies, shapes, guesses = [], [], [], {}
    for i, spec in enumerate(scenario.rods):
        name = f"rod{i}"
        rotation, position = _start_frame(spec)
        m = spec.material
        rod = {
            "name": name,
            "length": spec.length,
            "pieces": n_elements,
            "strains": "all",
            "section": {"shape": "circle", "radius": spec.radius},
            "material": {
                "density": m.density,
                "young": m.youngs_modulus,
                "shear_modulus": m.shear_modulus,
            },
            "base": _pose(rotation, position),
        }
        motion = spec.start_motion
        if spec.start is EndCondition.FREE:
            rod["joint"] = {"type": "free"}
        elif spec.start is EndCondition.PINNED:
            rod["joint"] = {"type": "spherical"}
        elif motion is not None and motion.slides_along is None:
            rod["joint"] = {"type": "free", "prescribed": _prescribed(motion, rotation)}
        elif motion is not None:
            drive, carriage = _sliding_clamp(f"{name}_start", motion, rotation, position, spec,
                                             n_elements)
            bodies += [drive, carriage]
            rod["parent"] = carriage.name
            rod["base"] = _pose(np.eye(3), np.zeros(3))
        if damping_rate:
            rod["drag"] = {
                "translational": damping_rate * m.density * spec.area,
                "rotational": damping_rate * m.density * spec.second_moment_of_area,
            }
        rods.append(rod)
        if not _is_straight_and_unstretched(spec):
            rows = np.column_stack([_fit_abscissae(spec), np.asarray(spec.centerline, float)])
            shapes.append({"rod": name, "centerline": rows})
            for k, values in enumerate(_arc_strains(spec, n_elements, rotation)):
                guesses |= {f"{name}.p{k}.{c}": v for c, v in zip(FIT_STRAINS, values)}
    loads = [
        {
            "rod": f"rod{i}",
            "s": 0.0 if load.at is End.START else spec.length,
            "force": np.asarray(load.force, float),
            "frame": "world",
        }
        for i, spec in enumerate(scenario.rods)
        for load in spec.loads
    ]

    def text(strains, extra_bodies=(), closures=(), initial=None) -> str:
        out = _table("world", {"gravity": np.asarray(scenario.gravity, float)})
        out += "".join(_table("[rod]", rod | {"strains": strains}) for rod in rods)
        out += "".join(body.toml() for body in [*bodies, *extra_bodies])
        out += "".join(_table("[closure]", closure) for closure in closures)
        out += "".join(_table("[load]", load) for load in loads)
        return out + (_table("initial", initial) if initial else "") + contact

    def carried(sim: softrod.Simulation, values: dict) -> np.ndarray:
        return np.array([values.get(n, 0.0) for n in sim.q_names])

    fitted = {}
    if shapes:
        draft = _scene(text(list(FIT_STRAINS)))
        guess = carried(draft, guesses)
        fit = _scene(text(list(FIT_STRAINS), initial={"shape": shapes, "q": guess}))
        fitted = dict(zip(fit.q_names, fit.initial_state()[0]))
    open_model = _scene(text("all"))
    q_open = carried(open_model, fitted)
    fit_error = []
    for i, spec in enumerate(scenario.rods):
        points = np.asarray(spec.centerline, dtype=float)
        at = open_model.pose(i, _fit_abscissae(spec), q_open)[:, :3, 3]
        fit_error.append(float(np.linalg.norm(at - points, axis=1).max()))

    extra, closures, offset = [], [], 0.0
    for i, spec in enumerate(scenario.rods):
        name, motion = f"rod{i}", spec.end_motion
        tip = open_model.tip_pose(i, q_open)
        rotation, position = tip[:3, :3], tip[:3, 3]
        weld = {"name": f"{name} end", "type": "weld", "a": {"element": name}}
        if spec.end is EndCondition.FREE:
            continue
        offset = max(offset, float(np.linalg.norm(position - spec.centerline[-1])))
        if spec.end is EndCondition.PINNED:
            closures.append(
                {"name": f"{name} end", "type": "ball", "a": {"element": name},
                 "b": {"element": "world", "base": {"position": position}}}
            )
        elif motion is None:
            closures.append(weld | {"b": {"element": "world", "base": _pose(rotation, position)}})
        elif motion.slides_along is None:
            drive = _drive(f"{name}_end", motion, rotation, position, spec, n_elements)
            extra.append(drive)
            closures.append(weld | {"b": {"element": drive.name}})
        else:
            drive, carriage = _sliding_clamp(f"{name}_end", motion, rotation, position, spec,
                                             n_elements)
            extra += [drive, carriage]
            closures.append(weld | {"b": {"element": carriage.name}})
    values = dict(zip(open_model.q_names, q_open))
    if not extra and not closures:
        scene = text("all", initial={"q": q_open})
        return (_scene(scene) if shapes else open_model), scene, fit_error, offset
    draft = _scene(text("all", extra))
    scene = text("all", extra, closures, {"q": carried(draft, values)})
    return _scene(scene), scene, fit_error, offset


def _drive(name: str, motion: Motion, rotation: np.ndarray, position: np.ndarray, spec,
           n_elements: int) -> _Body:
    """A body at the pose (``rotation``, ``position``) that follows
    ``motion`` (a prescribed free joint). Its mass, a piece of the rod's,
    moves only the drive's force, which the adapter does not report."""
    mass = spec.material.density * spec.area * spec.length / n_elements
    return _Body(f"{name}_drive", "world", _pose(rotation, position),
                 {"type": "free", "prescribed": _prescribed(motion, rotation)},
                 mass, mass * spec.radius**2)


def _sliding_clamp(name: str, motion: Motion, rotation: np.ndarray, position: np.ndarray,
                   spec, n_elements: int) -> tuple[_Body, _Body]:
    """A driven clamp that leaves its end free along an axis: a drive body
    (:func:`_drive`) carrying a carriage on a prismatic joint along the axis.
    The scenario's slider is massless, a softrod body is not: the carriage
    weighs one piece of the rod (as the MuJoCo adapter's), and its inertia
    rides along the slide with the end."""
    drive = _drive(name, motion, rotation, position, spec, n_elements)
    axis = rotation.T @ motion.axis
    carriage = _Body(f"{name}_carriage", drive.name, _pose(np.eye(3), np.zeros(3)),
                     {"type": "prismatic", "axis": axis}, drive.mass, drive.inertia)
    return drive, carriage
