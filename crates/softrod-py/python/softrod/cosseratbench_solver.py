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

Contact (docs/theory-contact.md, :func:`_contact_tables`): a ``Plane`` is
a plane obstacle, a ``Cylinder`` a capsule of its length (the same surface
within the length; rounded past its ends where the scenario's is cut flat),
rods touch each other and, where the scenario says ``self_contact``,
themselves, with the Coulomb coefficients of the scenario's rule (the larger
of the two that touch; rods of different coefficients are refused). The
penalty stiffness and the anchored friction are softrod's own: the adapter
chooses no contact number. Rods whose starts are close (:func:`_groups`)
are simulated together so that they can touch; rods far apart run as
separate simulations. A start fitted by PCS pieces may cut into an obstacle
where the scenario's curve changes curvature within a piece; the fit's
targets are then lifted off the obstacles (``START_CLEARANCE``, reported as
``start_lift`` in ``settings``).

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
- **Quasi-static** (the equilibrium is the result): an L-stable,
  error-controlled implicit method at ``rtol = RTOL_QUASI_STATIC *
  time_step_scale**4`` (the steps of both methods below scale as the
  fourth root of the tolerance) and ``atol = ATOL_QUASI_STATIC``: the
  tolerances bound only the path to the equilibrium: ESDIRK4(3),
  softrod's default (Newton on the exact Jacobian: the O(n) structured
  solve on open chains, the dense constrained one on loop closures), its
  steps ending on the output frames (``steps_to_outputs``,
  docs/theory-derivatives.md CD10: before, its quintic Hermite between
  steps of up to 1.4 s left the catenary's sag wandering by +-40 um), and
  on models with loop closures (a pinned, clamped or driven far end) the
  state projected onto the closures after every step
  (``project_closures``, docs/theory.md D121; :func:`_closed`): held by
  the constraint stabilization alone, the crossing's loops came apart at
  t = 0.1 s and the twist's at self contact (t = 15.4 s), which kept
  models with both loop closures and contact on Radau IIA, hours on the
  crossing
  (docs/performance.md, "Closed chains: projection onto the closures").
  Damping: linear drag proportional to mass (force
  ``-c_t v``, moment ``-c_r w`` per unit length, ``c_t = 2 omega_1 rho
  A``, ``c_r = 2 omega_1 rho I``), critical for the slowest mode
  ``omega_1 = Scenario.slowest_frequency()``: the rule of the PyElastica,
  MuJoCo and dismech adapters, so every solver settles through the same
  damping.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, fields, replace

import numpy as np

import softrod

try:  # only needed when cosseratbench loads the adapter
    from cosseratbench.metrics import segment_distance
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
#: Order of the step in the tolerance: ESDIRK4(3)'s error estimate (its
#: embedded order-3 solution) is O(h^4), so its step scales as rtol^(1/4).
#: Radau IIA(5)'s, the rule on loop closures with contact, is O(h^4) too.
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
#: A start fitted by PCS pieces cuts into an obstacle where the scenario's
#: curve changes curvature within a piece (the capstan's rope where it
#: leaves the cylinder: 1e-5 m at 100 pieces, 7e-5 m at 20, against the
#: 1e-5 m = 1 % of its radius softrod lets a start sink in). The fit's
#: targets are then lifted off the obstacles by the depth found, until the
#: start sinks in by at most this fraction of the thinnest rod's radius, in
#: at most START_LIFT_ROUNDS fits; START_SAMPLES points per piece measure it.
START_CLEARANCE = 0.005
START_LIFT_ROUNDS = 4
START_SAMPLES = 16
#: Rods whose starting surfaces come within this fraction of the shorter
#: one's length of each other are simulated together, so that they touch
#: (see _groups); the crossing's ropes start 1 cm apart on a 1 m length, the
#: twist's rods 0.23 m.
GROUP_REACH = 0.1


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
        # qx is the stretch's deviation from 1 (unstretched: 0).
        strains[i] = (local[1], local[2], along / h - 1.0)
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


def _friction(scenario: Scenario) -> float:
    """The rods' Coulomb coefficient (``Rod.friction``). softrod has one
    coefficient between rods (``[contact] friction``) and one per obstacle
    against every rod, which is the scenario's rule (the larger of the two
    coefficients that touch) exactly when every rod has the same one: rods
    of different coefficients are refused."""
    values = sorted({float(r.friction) for r in scenario.rods})
    if len(values) > 1:
        raise _unsupported(
            "rods with different friction coefficients "
            f"({', '.join(map(str, values))}): softrod has one coefficient between rods "
            "and one per obstacle against every rod"
        )
    return values[0]


def _contact_tables(scenario: Scenario) -> str:
    """The scene's contact (docs/scene-format.md, "Contact").

    - each ``Plane`` an ``[[obstacle]] shape = "plane"`` (``position =
      point``, ``normal``): the same half-space;
    - each ``Cylinder`` an ``[[obstacle]] shape = "capsule"`` of the
      cylinder's ``length`` (``position = center``, ``axis``, ``radius``):
      the same surface wherever a rod touches it within its length, which
      is where the scenarios' rods touch (the capstan's rope lies across
      its middle); past its ends the capsule is rounded where the
      scenario's cylinder is cut flat (softrod's ``cylinder`` is infinite,
      further from the scenario there);
    - each obstacle's ``friction`` the larger of its own and the rods'
      (the scenario's rule; :func:`_friction` refuses rods of different
      coefficients);
    - ``[contact] rods = true`` with more than one rod (rods always collide
      with each other), ``self = scenario.self_contact``, ``friction`` the
      rods' coefficient;
    - ``restitution = 0`` everywhere (the scenarios state none; softrod's 0
      is a critically damped contact, no bounce).

    The penalty stiffness and the penetration it allows are softrod's own
    (docs/theory-contact.md CT3): no contact number is chosen here.
    """
    friction = _friction(scenario)
    out = ""
    for k, obstacle in enumerate(scenario.obstacles):
        mu = max(float(obstacle.friction), friction)
        if obstacle.kind == "plane":
            table = {"name": f"plane{k}", "shape": "plane",
                     "position": np.asarray(obstacle.point, float),
                     "normal": np.asarray(obstacle.unit_normal, float)}
        elif obstacle.kind == "cylinder":
            table = {"name": f"cylinder{k}", "shape": "capsule",
                     "position": np.asarray(obstacle.center, float),
                     "axis": np.asarray(obstacle.unit_axis, float),
                     "length": float(obstacle.length), "radius": float(obstacle.radius)}
        else:  # pragma: no cover - cosseratbench 0.3 has no other obstacle
            raise _unsupported(f"an obstacle of kind {obstacle.kind!r}")
        out += _table("[obstacle]", table | {"friction": mu, "restitution": 0.0})
    rods, self_contact = len(scenario.rods) > 1, bool(scenario.self_contact)
    if rods or self_contact:
        out += _table("contact", {"rods": rods, "self": self_contact, "friction": friction,
                                  "restitution": 0.0})
    return out


def _touching(scenario: Scenario) -> bool:
    """Whether rods of the scenario may touch each other or themselves."""
    return len(scenario.rods) > 1 or bool(scenario.self_contact)


def _obstacle_distance(scenario: Scenario, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distance of each point to the nearest obstacle surface (negative
    inside) and the outward normal there, for the obstacles as
    :func:`_contact_tables` models them (planes, capsules); +inf without
    obstacles."""
    best = np.full(len(points), np.inf)
    normal = np.zeros_like(points)
    for o in scenario.obstacles:
        if o.kind == "plane":
            n = np.broadcast_to(o.unit_normal, points.shape)
            d = (points - np.asarray(o.point, float)) @ o.unit_normal
        else:
            axis, half = o.unit_axis, o.length / 2.0
            off = points - np.asarray(o.center, float)
            across = off - np.outer(np.clip(off @ axis, -half, half), axis)
            length = np.linalg.norm(across, axis=1)
            n = across / np.where(length > 0.0, length, 1.0)[:, None]
            d = length - o.radius
        closer = d < best
        best, normal = np.where(closer, d, best), np.where(closer[:, None], n, normal)
    return best, normal


def _lifted(scenario: Scenario, radius: float, rows: np.ndarray, lift: float) -> np.ndarray:
    """Centerline rows ``[s, x, y, z]`` with every point closer than ``radius
    + lift`` to an obstacle moved out along its normal to that distance (the
    targets of a start fitted clear of the obstacles)."""
    if lift == 0.0 or not scenario.obstacles:
        return rows
    rows = np.array(rows, dtype=float)
    d, n = _obstacle_distance(scenario, rows[:, 1:])
    rows[:, 1:] += n * np.maximum(radius + lift - d, 0.0)[:, None]
    return rows


def _start_depth(scenario: Scenario, sim: softrod.Simulation, rod: int, n_elements: int,
                 q: np.ndarray) -> float:
    """How deep rod ``rod`` of ``sim`` at ``q`` sinks into the obstacles [m],
    sampled at START_SAMPLES points per piece."""
    if not scenario.obstacles:
        return 0.0
    spec = scenario.rods[rod]
    s = np.linspace(0.0, spec.length * (1.0 - 1e-14), START_SAMPLES * n_elements + 1)
    d, _ = _obstacle_distance(scenario, sim.pose(rod, s, q)[:, :3, 3])
    return float(max(spec.radius - d.min(), 0.0))


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
    #: How far the fit's targets were lifted off the obstacles [m] (see
    #: START_CLEARANCE).
    start_lift: float


def _start_gap(a, b) -> float:
    """The smallest distance between two rods' starting surfaces [m]: their
    centerline polylines' closest segments less both radii."""
    p, q = np.asarray(a.centerline, float), np.asarray(b.centerline, float)
    i, j = np.meshgrid(np.arange(len(p) - 1), np.arange(len(q) - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    distance = segment_distance(p[i], p[i + 1], q[j], q[j + 1]).min()
    return float(distance) - a.radius - b.radius


def _groups(scenario: Scenario) -> list[tuple[int, ...]]:
    """The rods that are simulated together: those linked by a chain of rods
    that start within ``GROUP_REACH`` of the shorter one's length of each
    other (rod surfaces, :func:`_start_gap`). softrod's rod–rod contact acts
    only within a simulation, so rods apart can pass through each other;
    cosseratbench's ``max_rod_overlap``, reported on every run, would show
    it."""
    rods = scenario.rods
    group = list(range(len(rods)))

    def root(i: int) -> int:
        while group[i] != i:
            i = group[i]
        return i

    for i in range(len(rods)):
        for j in range(i + 1, len(rods)):
            reach = GROUP_REACH * min(rods[i].length, rods[j].length)
            if root(i) != root(j) and _start_gap(rods[i], rods[j]) < reach:
                group[root(j)] = root(i)
    out: dict[int, list[int]] = {}
    for i in range(len(rods)):
        out.setdefault(root(i), []).append(i)
    return [tuple(g) for g in out.values()]


def _parts(scenario: Scenario, n_elements: int, damping_rate: float) -> list[_Part]:
    """The scenario as independent simulations, one per group of rods that
    may touch (:func:`_groups`). Rods that nothing couples (no body or
    closure joins two rods, and contact only acts between rods of a group)
    move exactly as they would together, and apart they cost the sum of
    their runs rather than a run of all their coordinates at once (a closed
    model's Newton matrices are dense)."""
    groups = _groups(scenario)
    if len(groups) == 1:
        return [_Part(groups[0], *_build(scenario, n_elements, damping_rate))]
    return [
        _Part(g, *_build(replace(scenario, rods=tuple(scenario.rods[i] for i in g)), n_elements,
                         damping_rate))
        for g in groups
    ]


def _closed(scenario: Scenario) -> bool:
    """Whether the scenario's model has loop closures (a rod whose far end
    is pinned, clamped or driven, see :func:`_build`)."""
    return any(r.end is not EndCondition.FREE for r in scenario.rods)


def _build_key(scenario: Scenario, n_elements: int) -> tuple:
    """What the built simulations depend on: every field of the scenario but
    its ``duration`` (the build reads the rods, ends, motions, loads,
    obstacles, gravity and contact flags, and :meth:`SoftrodSolver.run`
    alone reads the duration), and the resolution. cosseratbench's warm-up
    run is the scenario at a thousandth of its duration: keyed on the whole
    scenario, the timed run would rebuild (fit the start, find the
    closures' anchors) inside its timing."""
    return (
        tuple((f.name, getattr(scenario, f.name)) for f in fields(scenario)
              if f.name != "duration"),
        n_elements,
    )


class SoftrodSolver:
    """softrod's PCS Cosserat rods in cosseratbench."""

    name = "softrod"
    backend_version = softrod.__version__
    # All six strains; contact with planes and cylinders (capsules of their
    # length), between rods and of a rod with itself, with Coulomb friction
    # (see _contact_tables).
    capabilities = frozenset({
        Capability.STRETCH, Capability.SHEAR, Capability.PLANE_CONTACT,
        Capability.CYLINDER_CONTACT, Capability.ROD_CONTACT, Capability.ROD_FRICTION,
    })

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
                "integrator": "esdirk",
                "rtol": RTOL_QUASI_STATIC * self.time_step_scale**STEP_ORDER,
                "atol": ATOL_QUASI_STATIC,
                # A settle's ESDIRK steps outgrow the decay of the damped
                # modes, and its quintic Hermite dense output across them
                # does not follow that decay (docs/theory-derivatives.md
                # CD10): the frames are step ends instead.
                "steps_to_outputs": True,
                # Loops held exactly at every step end (docs/theory.md D121).
                "project_closures": _closed(scenario),
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
        """The numerical choices made for a run, and what building it measured
        (only the numerics, and why, for a scenario softrod cannot express:
        :meth:`run` then raises what the runner reports as unsupported)."""
        try:
            parts = self._parts(scenario, n_elements)
        except NotImplementedError as error:
            return {**self.numerics(scenario), "unsupported": str(error)}
        rate = self._damping_rate(scenario)
        rods = scenario.rods
        fit = np.zeros(len(rods))
        for part in parts:
            fit[list(part.rods)] = part.fit_error
        return {
            **self.numerics(scenario),
            **({"integrator_rule": "quasi-static: ESDIRK4(3), steps ending on the output "
                "frames, loop closures projected after every step (the adapter's docstring "
                "says why)"}
               if scenario.quasi_static else {}),
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
            **({"start_lift": max(p.start_lift for p in parts)} if scenario.obstacles else {}),
            **self._contact_settings(scenario, parts),
        }

    @staticmethod
    def _contact_settings(scenario: Scenario, parts: list[_Part]) -> dict:
        """What the contact is, where there is any (see _contact_tables)."""
        out = {}
        if scenario.obstacles:
            out["obstacles"] = [
                ("capsule of the cylinder's length" if o.kind == "cylinder" else o.kind)
                for o in scenario.obstacles
            ]
        if scenario.obstacles or _touching(scenario):
            out |= {
                "contact": "penalty, stiffness per contact point from its weight and a "
                "1 m/s impact (docs/theory-contact.md CT3); Coulomb friction by "
                "anchored springs, committed after accepted steps (CT5, CT10)",
                "self_contact": bool(scenario.self_contact) and (
                    all("self = true" in p.scene for p in parts)
                    or "not modelled: this softrod refuses contact on models with loop "
                    "closures (pinned or clamped far ends)"),
                "rod_friction": _friction(scenario),
            }
        if len(scenario.rods) > 1:
            out["rod_groups"] = [list(p.rods) for p in parts]
        return out

    def _parts(self, scenario: Scenario, n_elements: int) -> list[_Part]:
        key = _build_key(scenario, n_elements)
        if key not in self._cache:
            # One model at a time: settings, the runner's warm-up (a
            # thousandth of the duration) and the timed run share it.
            self._cache.clear()
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
) -> tuple[softrod.Simulation, str, list[float], float, float]:
    """The scenario as a softrod simulation, in three scenes: one that fits
    the rods' starting shapes with FIT_STRAINS, the open model (no end
    bodies, no closures) at the fitted coordinates, where the ends are read,
    and the whole model with the closures anchored at those ends (a closure
    must hold at the start) and the coordinates carried over by name."""
    contact = _contact_tables(scenario)
    rods, bodies, shapes, shaped, guesses = [], [], [], [], {}
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
            shaped.append(i)
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

    def text(strains, extra_bodies=(), closures=(), initial=None, touch=False) -> str:
        """A scene; with contact only when ``touch`` (the fit and the draft
        models only place the rods)."""
        out = _table("world", {"gravity": np.asarray(scenario.gravity, float)})
        out += "".join(_table("[rod]", rod | {"strains": strains}) for rod in rods)
        out += "".join(body.toml() for body in [*bodies, *extra_bodies])
        out += "".join(_table("[closure]", closure) for closure in closures)
        out += "".join(_table("[load]", load) for load in loads)
        return out + (_table("initial", initial) if initial else "") + (contact if touch else "")

    def carried(sim: softrod.Simulation, values: dict) -> np.ndarray:
        return np.array([values.get(n, 0.0) for n in sim.q_names])

    fitted, lift = {}, 0.0
    if shapes:
        draft = _scene(text(list(FIT_STRAINS)))
        guess = carried(draft, guesses)
        for _ in range(START_LIFT_ROUNDS):
            lifted = [
                shape | {"centerline": _lifted(scenario, scenario.rods[i].radius,
                                               shape["centerline"], lift)}
                for i, shape in zip(shaped, shapes)
            ]
            fit = _scene(text(list(FIT_STRAINS), initial={"shape": lifted, "q": guess}))
            q_fit = fit.initial_state()[0]
            depth = max((_start_depth(scenario, fit, i, n_elements, q_fit)
                         for i in range(len(scenario.rods))), default=0.0)
            radius = min(r.radius for r in scenario.rods)
            if depth <= START_CLEARANCE * radius:
                break
            lift += depth
        else:
            raise _unsupported(
                f"the fitted start sinks {depth:.3e} m into an obstacle after lifting its "
                f"targets by {lift:.3e} m: more pieces are needed there"
            )
        fitted = dict(zip(fit.q_names, q_fit))
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
        scene = text("all", initial={"q": q_open}, touch=True)
        return _scene(scene), scene, fit_error, offset, lift
    draft = _scene(text("all", extra))
    initial = {"q": carried(draft, values)}
    scene = text("all", extra, closures, initial, touch=True)
    sim = _scene(scene)
    if closures and contact and not _accepts_contact(sim):
        # This softrod's dynamics has no contact on models with loop
        # closures (it says so at the first evaluation).
        if scenario.obstacles or len(scenario.rods) > 1:
            raise _unsupported(
                "contact on a model with loop closures (a rod's far end pinned, clamped or "
                "driven): softrod has none yet"
            )
        # Self contact alone is left out, and settings say so.
        scene = text("all", extra, closures, initial)
        sim = _scene(scene)
    return sim, scene, fit_error, offset, lift


def _accepts_contact(sim: softrod.Simulation) -> bool:
    """Whether softrod's dynamics runs ``sim`` (a model with loop closures
    and contact): asked of softrod by one evaluation at the start, so the
    adapter expresses such scenarios (pinned ropes by closures, rod–rod
    contact with friction) as soon as the dynamics accepts them."""
    q, qd = sim.initial_state()
    try:
        sim.forward_dynamics(0.0, q, qd)
    except softrod.NotSupportedError:
        return False
    return True


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
