"""The single environment :class:`RodEnv` and the tasks that give it a
target and a reward.

Conventions (docs/envs.md of the repository): SI units, world frame; an
action is the vector of cable tensions ``u`` [N] in the model's cable order
(rod by rod, in the order the scene gives them) followed by the forces
``f`` [N or N·m] of the actuated joint coordinates (elements in model
order), held constant over one control period (zero-order hold,
``Simulation.step(state, dt, u, joint_forces=f)``).
"""

from __future__ import annotations

import copy
import math
import os
from collections.abc import Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

import softrod
from softrod._errors import InputError, SimulationError

#: The bound of every cable's tension [N] when neither the env's
#: ``max_tension`` nor the scene's ``[[cable]] max_tension`` gives one.
DEFAULT_MAX_TENSION = 3.0

#: A state with a generalized coordinate beyond this magnitude (a
#: curvature of 1000 1/m is a radius of 1 mm, a stretch of 1000 is a rod
#: 1000 times its length) ends the episode as diverged.
DEFAULT_Q_LIMIT = 1.0e3

#: The relative tolerance the registered tasks integrate at (the scene's
#: integrator, ESDIRK): on the reach arm the tip stays within 0.1 mm (1.6 %
#: of Reach's success radius) of an rtol 1e-9 run at every period end, for
#: 1.35 times the speed of rtol 1e-3 (docs/envs.md, "Integration").
TASK_RTOL = 1e-2

#: The observation keys and their sizes (n_dof and n_cables are the
#: model's): see :class:`RodEnv`.
OBSERVATION_KEYS = (
    "strains",
    "strain_rates",
    "tip_position",
    "tip_rotation",
    "target",
    "target_velocity",
    "tensions",
    "joint_forces",
    "body_positions",
    "prescribed",
)


def _scene_max_tensions(path: os.PathLike | str) -> list[float | None] | None:
    """Each ``[[cable]] max_tension`` of the scene file at ``path`` (None
    where a cable has none), or None when the scene names none (or no TOML
    reader is available: Python 3.10 without tomli)."""
    try:
        import tomllib  # Python >= 3.11
    except ModuleNotFoundError:  # pragma: no cover - Python 3.10
        try:
            import tomli as tomllib  # type: ignore[no-redef]
        except ModuleNotFoundError:
            return None
    with open(path, "rb") as f:
        scene = tomllib.load(f)
    cables = scene.get("cable", [])
    found = [c.get("max_tension") for c in cables]
    return found if any(v is not None for v in found) else None


def _bounds(
    n_cables: int,
    given: float | Sequence[float] | None,
    from_scene: list[float | None] | None,
) -> np.ndarray:
    """The tension bound of each cable [N]: the env's argument, else the
    scene's ``max_tension``, else :data:`DEFAULT_MAX_TENSION`."""
    if given is not None:
        b = np.broadcast_to(np.asarray(given, dtype=np.float64), (n_cables,)).copy()
        what = "max_tension"
    else:
        b = np.full(n_cables, DEFAULT_MAX_TENSION)
        for i, v in enumerate(from_scene or []):
            if v is not None and i < n_cables:
                b[i] = float(v)
        what = "cable[i].max_tension"
    bad = [i for i, v in enumerate(b) if not (math.isfinite(v) and v > 0.0)]
    if bad:
        raise InputError(
            f"{what}: every cable's bound must be positive and finite, got {b[bad[0]]} "
            f"for cable {bad[0]}"
        )
    return b


def _target_bounds(sim: softrod.Simulation) -> tuple[np.ndarray, np.ndarray]:
    """The target range ``[lo, hi]`` (rad or m) of each prescribed joint
    coordinate, from the scene's ``joint.prescribed.bounds``; a coordinate
    without one is refused (a target's action space needs a box)."""
    bounds = sim.prescribed_bounds
    names = sim.prescribed_names
    missing = [i for i, b in enumerate(bounds) if b is None]
    if missing:
        raise InputError(
            f"prescribed joint coordinate {names[missing[0]]!r} has no target bounds: give its "
            "joint `prescribed = { ..., bounds = [lo, hi] }` in the scene (joint.prescribed.bounds; "
            "the action space of a prescribed-joint target is [lo, hi])"
        )
    lo = np.array([b[0] for b in bounds], dtype=np.float64)
    hi = np.array([b[1] for b in bounds], dtype=np.float64)
    return lo, hi


def _force_bounds(
    n_inputs: int, given: float | Sequence[float] | None, from_scene: Sequence[float]
) -> np.ndarray:
    """The force bound of each actuated joint coordinate [N or N·m]: the
    env's ``max_force``, else the scene's ``actuator = { max_force }``;
    a coordinate with neither is refused (a joint torque has no natural
    scale to default to)."""
    if given is not None:
        b = np.broadcast_to(np.asarray(given, dtype=np.float64), (n_inputs,)).copy()
        what = "max_force"
    else:
        b = np.asarray(from_scene, dtype=np.float64).reshape(n_inputs).copy()
        missing = [i for i, v in enumerate(b) if math.isinf(v)]
        if missing:
            raise InputError(
                f"actuated joint coordinate {missing[0]} has no force bound: give the joint "
                "`actuator = { max_force = ... }` in the scene, or max_force= to the env "
                "(the action space of a joint force is [-max_force, max_force])"
            )
        what = "actuator.max_force"
    bad = [i for i, v in enumerate(b) if not (math.isfinite(v) and v > 0.0)]
    if bad:
        raise InputError(
            f"{what}: every actuated joint coordinate's bound must be positive and finite, "
            f"got {b[bad[0]]} for coordinate {bad[0]}"
        )
    return b


class Task:
    """What an episode asks of the arm: a target and a reward.

    A task is bound to one env (:meth:`bind`), draws its episode's
    parameters from the env's seeded generator at reset (:meth:`reset`),
    gives the target's position and velocity at any time (:meth:`target`)
    and scores a state (:meth:`reward`).
    """

    #: Weight of the effort term of the reward.
    effort_weight: float = 0.01
    #: Success radius as a fraction of the rod's length.
    success_radius: float = 0.05

    #: The observation keys a task's env shows by default.
    default_observation: tuple[str, ...] = (
        "strains",
        "strain_rates",
        "tip_position",
        "target",
    )

    def bind(self, env: RodEnv) -> None:
        """Called once by the env that owns the task."""
        if env.n_cables + env.n_joint_inputs + env.n_prescribed == 0:
            raise InputError(
                f"{type(self).__name__} needs a scene with actuators (the actions are cable "
                "tensions, actuated joints' forces and prescribed joints' targets); this scene "
                "has no cables, no joint actuators and no prescribed joints"
            )
        self.env = env

    def reset(self, rng: np.random.Generator) -> None:
        """Draws the episode's parameters."""
        raise NotImplementedError

    def target(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The target's position [m] and velocity [m/s] at time ``t`` [s]."""
        raise NotImplementedError

    def reward(self, t: float, tip: np.ndarray, u: np.ndarray) -> tuple[float, dict[str, Any]]:
        """The reward of the state reached at ``t`` with the tip at ``tip``
        under the action ``u`` (its effort part: tensions, then joint
        forces — a prescribed joint's target is a position, not an effort),
        and what ``info`` reports of it."""
        pos, _ = self.target(t)
        env = self.env
        distance = float(np.linalg.norm(tip - pos))
        effort = float(np.mean((u / env.action_scale) ** 2)) if u.size else 0.0
        reward = -distance / env.length - self.effort_weight * effort
        return reward, {
            "distance": distance,
            "is_success": distance <= self.success_radius * env.length,
        }


class ReachTask(Task):
    """Reach a random static target.

    At reset the target is the tip of the static equilibrium
    (``Simulation.statics(tensions=u*)``) under tensions ``u*`` where one
    cable, drawn uniformly, pulls with a tension drawn uniformly from
    ``[0, max_tension]`` and the others are slack: every target is
    reachable by a constant action (``target_tensions``), and on an
    antagonistic pair the targets spread evenly over both sides. With
    actuated joints the drawn input is one of all the action's entries, a
    joint force uniform in ``[-max_force, max_force]``
    (``target_joint_forces``). With prescribed joints (targets in the
    action) their targets are drawn too, uniformly in their bounds
    (``target_prescribed``), and the statics holds the joints there
    (``Simulation.hold_prescribed``). Reward
    per step, with ``d`` the tip–target distance [m], ``L`` the rod's
    length and ``ū`` the action over its bound (``u / max_tension``,
    ``f / max_force``):

        r = −d / L − effort_weight · mean(ū²)

    ``info["is_success"]``: ``d ≤ success_radius · L`` (default 2 % of L).
    Episodes end by truncation after ``episode_steps`` steps (no early
    termination on success).
    """

    def __init__(self, *, effort_weight: float = 0.01, success_radius: float = 0.02):
        self.effort_weight = float(effort_weight)
        self.success_radius = float(success_radius)
        self._target = np.zeros(3)

    def reset(self, rng: np.random.Generator) -> None:
        env = self.env
        last: Exception | None = None
        nc, nj = env.n_cables, env.n_joint_inputs
        for _ in range(10):
            u, f = np.zeros(nc), np.zeros(nj)
            k = int(rng.integers(nc + nj)) if nc + nj else -1
            if 0 <= k < nc:
                u[k] = rng.uniform(0.0, env.max_tension[k])
            elif k >= nc:
                f[k - nc] = rng.uniform(-env.max_force[k - nc], env.max_force[k - nc])
            p = None
            if env.n_prescribed:
                p = rng.uniform(env.target_low, env.target_high)
                env.sim.hold_prescribed(p)
            try:
                st = env.sim.statics(tensions=u, joint_forces=f if nj else None)
            except SimulationError as e:  # rare: draw again
                last = e
                continue
            finally:
                if p is not None:
                    env.sim.reset_prescribed()
            self._target = np.array(st.tips[env.rod_name][:3, 3], dtype=np.float64)
            self.target_tensions = u
            self.target_joint_forces = f
            self.target_prescribed = p
            return
        raise SimulationError(f"no reachable target found in 10 draws: {last}")

    def target(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        return self._target, np.zeros(3)


class TrackTask(Task):
    """Track a target that moves on a circle around the arm's rest axis.

    With ``b`` the rod's base, ``a`` the unit vector from the base to the
    rest tip, ``e1, e2`` unit vectors completing it to a right-handed frame
    and ``L`` the rod's length, the target is the tip of a constant-curvature
    arc of length ``L`` bent by ``θ`` and swung around the axis:

        p(t) = b + a · L sin θ / θ + ρ (cos φ(t) e1 + sin φ(t) e2),
        ρ = L (1 − cos θ) / θ,   φ(t) = φ0 + 2π s f t

    with ``θ`` uniform in ``arc_angle`` [rad], ``f`` uniform in
    ``frequency`` [Hz], ``φ0`` uniform in [0, 2π) and the sense ``s = ±1``
    drawn at reset. Reward and success as for :class:`ReachTask`, with the
    moving target.
    """

    default_observation = (
        "strains",
        "strain_rates",
        "tip_position",
        "tip_rotation",
        "target",
        "target_velocity",
    )

    def __init__(
        self,
        *,
        arc_angle: tuple[float, float] = (0.2, 0.5),
        frequency: tuple[float, float] = (0.1, 0.25),
        effort_weight: float = 0.01,
        success_radius: float = 0.05,
    ):
        self.arc_angle = (float(arc_angle[0]), float(arc_angle[1]))
        self.frequency = (float(frequency[0]), float(frequency[1]))
        if not 0.0 < self.arc_angle[0] <= self.arc_angle[1] < 2 * math.pi:
            raise InputError(f"arc_angle must be 0 < lo <= hi < 2 pi, got {arc_angle}")
        if not 0.0 <= self.frequency[0] <= self.frequency[1]:
            raise InputError(f"frequency must be 0 <= lo <= hi, got {frequency}")
        self.effort_weight = float(effort_weight)
        self.success_radius = float(success_radius)

    def bind(self, env: RodEnv) -> None:
        super().bind(env)
        q0 = env.q0
        base = env.sim.pose(env.rod, 0.0, q0)[:3, 3]
        tip = env.sim.tip_pose(env.rod, q0)[:3, 3]
        a = tip - base
        a = a / np.linalg.norm(a)
        # e1: the world axis least aligned with a, made orthogonal to it.
        k = int(np.argmin(np.abs(a)))
        e = np.zeros(3)
        e[k] = 1.0
        e1 = e - a * (a @ e)
        e1 /= np.linalg.norm(e1)
        self._frame = (base, a, e1, np.cross(a, e1))

    def reset(self, rng: np.random.Generator) -> None:
        self.theta = float(rng.uniform(*self.arc_angle))
        self.freq = float(rng.uniform(*self.frequency))
        self.phi0 = float(rng.uniform(0.0, 2 * math.pi))
        self.sense = 1.0 if rng.random() < 0.5 else -1.0

    def target(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        b, a, e1, e2 = self._frame
        L, th = self.env.length, self.theta
        rho = L * (1.0 - math.cos(th)) / th
        w = 2 * math.pi * self.sense * self.freq
        phi = self.phi0 + w * t
        c, s = math.cos(phi), math.sin(phi)
        p = b + a * (L * math.sin(th) / th) + rho * (c * e1 + s * e2)
        v = rho * w * (-s * e1 + c * e2)
        return p, v


class RodEnv(gymnasium.Env):
    """A Gymnasium environment over a softrod scene whose actions are cable
    tensions and actuated joints' forces.

    ``scene``: a scene file path (str or os.PathLike) or a
    ``softrod.Simulation`` (copied; its model, settings and initial state
    are used). ``task``: a :class:`Task` (default :class:`ReachTask`); the
    env keeps its own copy, so one task object can configure many envs.

    Action: ``u`` (n_cables,) [N], a ``Box(0, max_tension)``. The bound of
    each cable is ``max_tension`` (a number or one per cable), else the
    scene's ``[[cable]] max_tension`` where a scene file gives it, else
    :data:`DEFAULT_MAX_TENSION` = 3 N. With joint actuators
    (docs/theory-control.md IS14) the action is ``(u, f)``: the tensions,
    then one force ``f`` [N or N·m] per actuated joint coordinate (elements
    in model order, ``Simulation.n_joint_inputs``) in ``[-max_force,
    max_force]``, the bound from ``max_force`` (a number or one per
    coordinate), else the scene's ``actuator = { max_force }``; a
    coordinate with neither raises ``softrod.InputError``. With prescribed
    joints the action ends with one target ``p`` [rad or m] per prescribed
    coordinate (``Simulation.prescribed_names``) in the scene's
    ``joint.prescribed.bounds`` (required: a scene without them raises
    ``softrod.InputError`` naming the key); each period the joint follows
    the cubic from its position and rate to ``p``, reached at rest at the
    period's end (``Simulation.step(..., prescribed_targets=p)``,
    docs/envs.md). Targets are not efforts (the effort term weighs ``u``
    and ``f``).
    ``action_policy``: what an action
    outside the box does — ``"clip"`` (default) clips it to the box and
    sets ``info["action_clipped"]``, ``"reject"`` raises
    ``softrod.InputError``. An action that is not finite (NaN, ±inf) or
    has the wrong shape always raises ``softrod.InputError`` (a
    ``ValueError``).

    Step: the tensions are held for ``control_period`` seconds (default
    0.05 s, 20 Hz) and the scene's integrator advances the state
    (``Simulation.step``): adaptively at the scene's tolerances, or at
    relative tolerance ``rtol`` when given (and an absolute tolerance no
    looser than it; the registered tasks use 1e-2:
    the tip within ~0.1 mm of a tight-tolerance run, docs/envs.md,
    "Integration"), or in ``substeps`` fixed steps per period when given (a
    fixed cost; its accuracy is the caller's to check — measured on the
    reach arm it is worse than the adaptive default for the same cost).
    Episodes are truncated after
    ``episode_steps`` steps. A step that fails (the integrator gives up, a
    non-finite state, a coordinate beyond ``q_limit``) ends the episode:
    ``terminated=True``, ``info["termination"]`` says why (``"diverged:
    <message>"``), and the observation and reward are those of the last
    valid state — never NaN.

    Observation: a flat float64 ``Box`` concatenating, in the order of
    ``observe`` (default: the task's), any of
    ``"strains"`` (q, n_dof: strain coordinates [1/m, dimensionless],
    and joint coordinates on robots), ``"strain_rates"`` (q̇, n_dof),
    ``"tip_position"`` (3, m, world frame), ``"tip_rotation"`` (9, the tip
    frame's rotation matrix row by row), ``"target"`` (3, m),
    ``"target_velocity"`` (3, m/s), ``"tensions"`` (n_cables, N: the last
    applied tensions), ``"joint_forces"`` (n_joint_inputs, N or N·m: the
    last applied joint forces), ``"prescribed"`` (n_prescribed, rad or m:
    the prescribed joints' values now; added to the default observation
    when the scene has prescribed joints), ``"body_positions"`` (3 per rigid body of the scene,
    m, world frame: the origins of their frames, in the scene's order).
    ``observation_slices`` maps each key to its slice.

    Reset: the scene's initial state, plus Gaussian noise of standard
    deviation ``initial_noise`` on q and q̇ when positive, and the task's
    draw, all from the env's seeded generator (``reset(seed=...)``).
    ``rod``: the rod (name or index) whose tip is observed and rewarded.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        scene: softrod.Simulation | str | os.PathLike,
        task: Task | None = None,
        *,
        control_period: float = 0.05,
        episode_steps: int = 100,
        max_tension: float | Sequence[float] | None = None,
        max_force: float | Sequence[float] | None = None,
        observe: Sequence[str] | None = None,
        action_policy: str = "clip",
        initial_noise: float = 0.0,
        q_limit: float = DEFAULT_Q_LIMIT,
        rod: int | str = 0,
        rtol: float | None = None,
        substeps: int | None = None,
    ):
        super().__init__()
        scene_bounds = None
        if isinstance(scene, softrod.Simulation):
            self.sim = scene.copy()
        elif isinstance(scene, (str, os.PathLike)):
            self.sim = softrod.Simulation.from_file(scene)
            scene_bounds = _scene_max_tensions(scene)
        else:
            raise InputError(
                f"scene must be a scene file path or a softrod.Simulation, got {type(scene).__name__}"
            )
        if not (math.isfinite(control_period) and control_period > 0):
            raise InputError(f"control_period must be positive and finite, got {control_period}")
        if int(episode_steps) != episode_steps or episode_steps < 1:
            raise InputError(f"episode_steps must be a positive integer, got {episode_steps}")
        if action_policy not in ("clip", "reject"):
            raise InputError(f'action_policy must be "clip" or "reject", got {action_policy!r}')
        if not (math.isfinite(initial_noise) and initial_noise >= 0):
            raise InputError(f"initial_noise must be >= 0 and finite, got {initial_noise}")
        if rtol is not None:
            if not (math.isfinite(rtol) and rtol > 0):
                raise InputError(f"rtol must be positive and finite, got {rtol}")
            # replace, not Settings(...): the scene's duration and energy
            # tolerance stay; rtol alone lowers a larger atol to it.
            self.sim.settings = self.sim.settings.replace(rtol=float(rtol))
        if substeps is not None and (int(substeps) != substeps or substeps < 1):
            raise InputError(f"substeps must be a positive integer or None, got {substeps}")
        self.substeps = None if substeps is None else int(substeps)
        self.control_period = float(control_period)
        self.episode_steps = int(episode_steps)
        self.action_policy = action_policy
        self.initial_noise = float(initial_noise)
        self.q_limit = float(q_limit)
        names = self.sim.rod_names
        if isinstance(rod, str):
            if rod not in names:
                raise InputError(f"no rod {rod!r} (rods: {names})")
            self.rod = names.index(rod)
        else:
            r = int(rod)
            if not -len(names) <= r < len(names):
                raise InputError(f"rod index {rod} out of range for {len(names)} rods")
            self.rod = r % len(names)
        self.rod_name = names[self.rod]
        self.length = float(self.sim.rod_lengths[self.rod])
        self.n_dof = self.sim.n_dof
        self.n_cables = self.sim.n_cables
        self.q0, self.qdot0 = self.sim.initial_state()
        self.max_tension = _bounds(self.n_cables, max_tension, scene_bounds)
        self.n_joint_inputs = self.sim.n_joint_inputs
        self.max_force = _force_bounds(
            self.n_joint_inputs, max_force, self.sim.joint_max_forces
        )
        #: The action's bounds: tensions in [0, max_tension], joint forces
        #: in [-max_force, max_force]; ``action_scale`` normalizes effort.
        #: Prescribed joint coordinates whose targets end the action, with
        #: their ranges (the scene's ``joint.prescribed.bounds``, required).
        self.n_prescribed = self.sim.n_prescribed
        if self.n_prescribed:
            self.target_low, self.target_high = _target_bounds(self.sim)
        else:
            self.target_low = self.target_high = np.zeros(0)
        #: Entries of the action that are efforts (tensions, joint forces).
        self.n_effort = self.n_cables + self.n_joint_inputs
        self.action_low = np.concatenate(
            [np.zeros(self.n_cables), -self.max_force, self.target_low]
        )
        self.action_high = np.concatenate([self.max_tension, self.max_force, self.target_high])
        self.action_scale = self.action_high[: self.n_effort].copy()

        # A copy: a task holds its episode's draw, so envs must not share one.
        self.task = copy.deepcopy(task) if task is not None else ReachTask()
        self.task.bind(self)
        keys = tuple(observe) if observe is not None else self.task.default_observation
        if observe is None and self.n_prescribed and "prescribed" not in keys:
            keys = keys + ("prescribed",)
        unknown = [k for k in keys if k not in OBSERVATION_KEYS]
        if unknown or not keys:
            raise InputError(
                f"observe: unknown keys {unknown} (known: {list(OBSERVATION_KEYS)})"
                if unknown
                else "observe must name at least one key"
            )
        self.observe = keys
        sizes = {
            "strains": self.n_dof,
            "strain_rates": self.n_dof,
            "tip_position": 3,
            "tip_rotation": 9,
            "target": 3,
            "target_velocity": 3,
            "tensions": self.n_cables,
            "joint_forces": self.n_joint_inputs,
            "body_positions": 3 * len(self.sim.body_names),
            "prescribed": self.n_prescribed,
        }
        lo, hi, self.observation_slices, k = [], [], {}, 0
        for key in keys:
            n = sizes[key]
            self.observation_slices[key] = slice(k, k + n)
            k += n
            if key == "tip_rotation":
                lo.append(np.full(n, -1.0))
                hi.append(np.full(n, 1.0))
            elif key == "tensions":
                lo.append(np.zeros(n))
                hi.append(self.max_tension.copy())
            elif key == "joint_forces":
                lo.append(-self.max_force)
                hi.append(self.max_force.copy())
            else:
                lo.append(np.full(n, -np.inf))
                hi.append(np.full(n, np.inf))
        self.observation_space = spaces.Box(np.concatenate(lo), np.concatenate(hi), dtype=np.float64)
        self.action_space = spaces.Box(
            self.action_low.copy(), self.action_high.copy(), dtype=np.float64
        )
        self._steps = 0
        self.q, self.qdot = self.q0.copy(), self.qdot0.copy()
        self.u = np.zeros(self.n_cables)
        self.f = np.zeros(self.n_joint_inputs)
        self.p = self._prescribed_now()

    # -- state --------------------------------------------------------------

    @property
    def t(self) -> float:
        """The simulation time [s] of the current state (steps × period)."""
        return self._steps * self.control_period

    def _prescribed_now(self) -> np.ndarray:
        """The prescribed joints' values at the current time [rad or m]."""
        if not self.n_prescribed:
            return np.zeros(0)
        return np.asarray(self.sim.prescribed_state(self.t)[0], dtype=np.float64)

    def _observation(self) -> np.ndarray:
        t = self.t
        tip = self.sim.tip_pose(self.rod, self.q, t=t)
        target, target_v = self.task.target(t)
        parts = {
            "strains": self.q,
            "strain_rates": self.qdot,
            "tip_position": tip[:3, 3],
            # Clipped to the box: a rotation's entries are in [-1, 1] up to
            # round-off, which may exceed it by an ulp.
            "tip_rotation": np.clip(tip[:3, :3].reshape(9), -1.0, 1.0),
            "target": target,
            "target_velocity": target_v,
            "tensions": self.u,
            "joint_forces": self.f,
        }
        if "prescribed" in self.observe:
            parts["prescribed"] = self._prescribed_now()
        if "body_positions" in self.observe:
            poses = self.sim.body_poses(self.q, t=t)
            parts["body_positions"] = poses[:, :3, 3].reshape(-1)
        self._tip = tip[:3, 3].copy()
        return np.concatenate([np.asarray(parts[k], dtype=np.float64) for k in self.observe])

    # -- Gymnasium API -------------------------------------------------------

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        rng = self.np_random
        self._steps = 0
        self.q, self.qdot = self.q0.copy(), self.qdot0.copy()
        if self.initial_noise > 0:
            self.q = self.q + rng.normal(0.0, self.initial_noise, self.n_dof)
            self.qdot = self.qdot + rng.normal(0.0, self.initial_noise, self.n_dof)
        self.u = np.zeros(self.n_cables)
        self.f = np.zeros(self.n_joint_inputs)
        # The drive follows the scene's curve again until the first action.
        self.sim.reset_prescribed()
        self.p = self._prescribed_now()
        self.task.reset(rng)
        # An episode starts with no friction history (after the task's
        # statics, which commits its own contact state).
        self.sim.reset_contact()
        obs = self._observation()
        _, info = self.task.reward(self.t, self._tip, self._action())
        return obs, info

    def _action(self) -> np.ndarray:
        """The effort part of the last applied action: tensions, then joint
        forces (what a task's effort term weighs)."""
        return np.concatenate([self.u, self.f]) if self.n_joint_inputs else self.u

    def _prepare(self, action: Any) -> tuple[np.ndarray, bool]:
        """The action (tensions, then joint forces) of ``action`` by the
        action policy, and whether it was clipped. Raises InputError for a
        bad shape, a non-finite entry or (policy "reject") an action
        outside the box."""
        a = np.asarray(action, dtype=np.float64)
        nc, ne = self.n_cables, self.n_effort
        na = ne + self.n_prescribed
        if a.shape != (na,):
            what = "one tension per cable"
            if self.n_joint_inputs:
                what += ", then one force per actuated joint coordinate"
            if self.n_prescribed:
                what += ", then one target per prescribed joint coordinate"
            raise InputError(f"action must have shape ({na},) ({what}), got {a.shape}")
        if not np.all(np.isfinite(a)):
            i = int(np.flatnonzero(~np.isfinite(a))[0])
            what = (
                "cable tensions" if i < nc
                else "joint forces" if i < ne
                else f"prescribed-joint targets ({self.sim.prescribed_names[i - ne]})"
            )
            raise InputError(f"action[{i}] = {a[i]}: {what} must be finite")
        lo, hi = self.action_low, self.action_high
        inside = bool(np.all((a >= lo) & (a <= hi)))
        if inside:
            return a.copy(), False
        if self.action_policy == "reject":
            i = int(np.flatnonzero((a < lo) | (a > hi))[0])
            unit = (
                "N" if i < nc else "N or N·m" if i < ne
                else f"rad or m, the target of {self.sim.prescribed_names[i - ne]}"
            )
            raise InputError(
                f"action[{i}] = {a[i]} is outside [{lo[i]}, {hi[i]}] {unit} "
                '(action_policy="reject")'
            )
        return np.clip(a, lo, hi), True

    def _physics(self, a: np.ndarray) -> tuple[np.ndarray, np.ndarray, str | None]:
        """One control period under the action ``a``: the new (q, q̇), or
        the failure."""
        state = softrod.State(self.t, self.q, self.qdot)
        nc, ne = self.n_cables, self.n_effort
        f = a[nc:ne] if self.n_joint_inputs else None
        p = a[ne:] if self.n_prescribed else None
        try:
            s = self.sim.step(
                state, self.control_period, a[:nc], substeps=self.substeps, joint_forces=f,
                prescribed_targets=p,
            )
        except SimulationError as e:
            return self.q, self.qdot, str(e)
        return s.q, s.qdot, None

    def _finish(
        self, a: np.ndarray, clipped: bool, q: np.ndarray, qdot: np.ndarray, error: str | None
    ):
        """The step's result from the physics' outcome (shared with the
        batched vector env, so both give the same numbers)."""
        if error is None:
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qdot))):
                error = "the state is not finite"
            elif np.max(np.abs(q), initial=0.0) > self.q_limit:
                i = int(np.argmax(np.abs(q)))
                error = f"q[{i}] = {q[i]:.6g} is beyond q_limit = {self.q_limit:g}"
        info: dict[str, Any] = {"action_clipped": clipped}
        if error is not None:
            obs = self._observation()
            reward, more = self.task.reward(self.t, self._tip, self._action())
            info.update(more)
            info["termination"] = f"diverged: {error}"
            return obs, reward, True, False, info
        nc, ne = self.n_cables, self.n_effort
        self.q, self.qdot = np.array(q), np.array(qdot)
        self.u, self.f = a[:nc], a[nc:ne]
        self.p = a[ne:]
        self._steps += 1
        obs = self._observation()
        reward, more = self.task.reward(self.t, self._tip, a[:ne])
        info.update(more)
        truncated = self._steps >= self.episode_steps
        return obs, reward, False, truncated, info

    def step(self, action: Any):
        a, clipped = self._prepare(action)
        q, qdot, error = self._physics(a)
        return self._finish(a, clipped, q, qdot, error)


def _scene(name: str) -> str:
    return os.path.join(os.path.dirname(__file__), "scenes", name)


#: The scene file of softrod/Reach-v0 (two cables, planar, 18 DoF).
REACH_SCENE = _scene("reach_arm.toml")
#: The scene file of softrod/Track-v0 (four cables, 3-D, 15 DoF).
TRACK_SCENE = _scene("track_arm.toml")
#: The scene file of softrod/SwingReach-v0 (two cables and a prescribed
#: revolute base, 18 DoF + 1 prescribed coordinate).
SWING_REACH_SCENE = _scene("swing_reach_arm.toml")


def reach_env(scene=None, *, task: ReachTask | None = None, **kwargs) -> RodEnv:
    """softrod/Reach-v0: the two-cable planar arm (``REACH_SCENE``) reaching
    a random static target, 20 Hz, 100 steps (5 s); keywords as
    :class:`RodEnv` and :class:`ReachTask` (``effort_weight``,
    ``success_radius``)."""
    task_kw = {k: kwargs.pop(k) for k in ("effort_weight", "success_radius") if k in kwargs}
    kwargs.setdefault("episode_steps", 100)
    kwargs.setdefault("rtol", TASK_RTOL)
    return RodEnv(scene or REACH_SCENE, task or ReachTask(**task_kw), **kwargs)


def track_env(scene=None, *, task: TrackTask | None = None, **kwargs) -> RodEnv:
    """softrod/Track-v0: the four-cable arm (``TRACK_SCENE``) tracking a
    target on a circle in 3-D, 20 Hz, 200 steps (10 s); keywords as
    :class:`RodEnv` and :class:`TrackTask`."""
    names = ("arc_angle", "frequency", "effort_weight", "success_radius")
    task_kw = {k: kwargs.pop(k) for k in names if k in kwargs}
    kwargs.setdefault("episode_steps", 200)
    kwargs.setdefault("rtol", TASK_RTOL)
    return RodEnv(scene or TRACK_SCENE, task or TrackTask(**task_kw), **kwargs)


def swing_reach_env(scene=None, *, task: ReachTask | None = None, **kwargs) -> RodEnv:
    """softrod/SwingReach-v0: the Reach arm on a driven base
    (``SWING_REACH_SCENE``): the action is the two cables' tensions [N]
    and the target [rad] of the prescribed revolute joint at the clamp
    (bounds [-0.3, 0.3] rad, from the scene), which the joint reaches at
    rest at each period's end (docs/envs.md). Targets are drawn as Reach's
    with the base angle drawn too (reachable by a constant action); reward
    as Reach (the base angle is not an effort). 20 Hz, 100 steps;
    keywords as :func:`reach_env`."""
    return reach_env(scene or SWING_REACH_SCENE, task=task, **kwargs)
