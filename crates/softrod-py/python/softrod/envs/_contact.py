"""Tasks with contact (obstacles, pushed bodies): softrod/ReachAround-v0
and softrod/Push-v0. Conventions as in ``_core`` (SI units, world frame,
actions are cable tensions)."""

from __future__ import annotations

from typing import Any

import numpy as np

from softrod._errors import InputError

from ._core import TASK_RTOL, ReachTask, RodEnv, Task, _scene

#: The scene of softrod/ReachAround-v0 (the reach arm and a post, 18 DoF).
REACH_AROUND_SCENE = _scene("reach_around_arm.toml")
#: The scene of softrod/Push-v0 (the reach arm and a box on a table, 19 DoF).
PUSH_SCENE = _scene("push_box.toml")


class ReachAroundTask(ReachTask):
    """Reach a random static target in a scene with obstacles.

    The target is drawn as in :class:`ReachTask` — the tip of the static
    equilibrium under one random cable's tension — with the obstacles in
    place, so the equilibrium presses on them where the arm meets them
    (the statics solver includes contact): targets on the obstacle's side
    lie where the arm, wrapped around the obstacle, can reach, and every
    target is reachable by a constant action. Reward per step, with ``d``
    the tip–target distance [m], ``L`` the rod's length, ``ū = u /
    max_tension`` and ``p`` the largest penetration of any contact [m]
    (``Simulation.max_penetration``; the contact model allows a little):

        r = −d / L − effort_weight · mean(ū²) − penetration_weight · p / L

    (penetration_weight = 0 by default: touching the obstacle is how the
    arm gets around it). ``info``: ``distance``, ``is_success`` (``d ≤
    success_radius · L``), ``in_contact`` (whether any contact is active),
    ``max_penetration`` [m]. Episodes end by truncation (100 steps, 5 s)
    or when a step diverges.
    """

    def __init__(
        self,
        *,
        effort_weight: float = 0.01,
        success_radius: float = 0.02,
        penetration_weight: float = 0.0,
    ):
        super().__init__(effort_weight=effort_weight, success_radius=success_radius)
        self.penetration_weight = float(penetration_weight)

    def bind(self, env: RodEnv) -> None:
        super().bind(env)
        if not env.sim.obstacle_names:
            raise InputError(
                "ReachAroundTask needs a scene with obstacles ([[obstacle]]); this one has none"
            )

    def reward(self, t: float, tip: np.ndarray, u: np.ndarray) -> tuple[float, dict[str, Any]]:
        reward, info = super().reward(t, tip, u)
        env = self.env
        p = float(env.sim.max_penetration(env.q, t=t))
        info["max_penetration"] = p
        info["in_contact"] = bool(env.sim.contacts(env.q, env.qdot, t=t))
        return reward - self.penetration_weight * p / env.length, info


class PushTask(Task):
    """Push a body to a goal.

    The scene has a rigid body carrying an obstacle (its surface) that the
    arm can push: in softrod/Push-v0 a box on a prismatic joint along world
    x (a table with viscous friction). At reset the goal is the body's
    initial position moved along ``direction`` (a unit vector, default
    world +x) by a distance drawn uniformly from ``distance`` [m] (default
    1–5 cm; 4 N on the pushing cable moves the box ~7 cm in 3 s). The
    observation's ``target`` is the goal. Reward per step, with ``b`` the
    body's position, ``g`` the goal, ``tip`` the arm's tip, ``L`` the rod's
    length and ``ū = u / max_tension``:

        r = −|b − g| / L − reach_weight · |tip − b| / L − effort_weight · mean(ū²)

    (the second term, default weight 0.1, leads the tip to the body).
    ``info``: ``distance`` (|b − g|, m), ``is_success`` (``|b − g| ≤
    success_radius · L``, default 1 % of L = 3 mm), ``tip_distance``
    (|tip − b|), ``in_contact``. Episodes end by truncation (100 steps, 5
    s) or when a step diverges; a box pushed past its goal cannot be pulled
    back (the arm only pushes).
    """

    default_observation = (
        "strains",
        "strain_rates",
        "tip_position",
        "body_positions",
        "target",
    )

    def __init__(
        self,
        *,
        body: int | str = 0,
        direction: tuple[float, float, float] = (1.0, 0.0, 0.0),
        distance: tuple[float, float] = (0.01, 0.05),
        effort_weight: float = 0.01,
        reach_weight: float = 0.1,
        success_radius: float = 0.01,
    ):
        d = np.asarray(direction, dtype=np.float64)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
            raise InputError(f"direction must be a nonzero finite 3-vector, got {direction}")
        self.direction = d / np.linalg.norm(d)
        self.distance = (float(distance[0]), float(distance[1]))
        if not 0.0 <= self.distance[0] <= self.distance[1]:
            raise InputError(f"distance must be 0 <= lo <= hi, got {distance}")
        self.body = body
        self.effort_weight = float(effort_weight)
        self.reach_weight = float(reach_weight)
        self.success_radius = float(success_radius)
        self._goal = np.zeros(3)

    def bind(self, env: RodEnv) -> None:
        super().bind(env)
        names = env.sim.body_names
        if not names:
            raise InputError("PushTask needs a scene with a rigid body ([[body]]); this one has none")
        if isinstance(self.body, str):
            if self.body not in names:
                raise InputError(f"PushTask: no body {self.body!r} (bodies: {names})")
            self.body_index = names.index(self.body)
        else:
            if not -len(names) <= int(self.body) < len(names):
                raise InputError(f"PushTask: body index {self.body} out of range for {len(names)} bodies")
            self.body_index = int(self.body) % len(names)
        self._start = self.body_position(env.q0, 0.0)

    def body_position(self, q: np.ndarray, t: float) -> np.ndarray:
        """The pushed body's position [m] (its frame's origin, world frame)."""
        return np.array(self.env.sim.body_poses(q, t=t)[self.body_index][:3, 3])

    def reset(self, rng: np.random.Generator) -> None:
        self._goal = self._start + self.direction * rng.uniform(*self.distance)

    def target(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        return self._goal, np.zeros(3)

    def reward(self, t: float, tip: np.ndarray, u: np.ndarray) -> tuple[float, dict[str, Any]]:
        env = self.env
        b = self.body_position(env.q, t)
        distance = float(np.linalg.norm(b - self._goal))
        tip_distance = float(np.linalg.norm(tip - b))
        effort = float(np.mean((u / env.action_scale) ** 2))
        reward = (
            -distance / env.length
            - self.reach_weight * tip_distance / env.length
            - self.effort_weight * effort
        )
        return reward, {
            "distance": distance,
            "tip_distance": tip_distance,
            "is_success": distance <= self.success_radius * env.length,
            "in_contact": bool(env.sim.contacts(env.q, env.qdot, t=t)),
        }


def reach_around_env(scene=None, *, task: ReachAroundTask | None = None, **kwargs) -> RodEnv:
    """softrod/ReachAround-v0: the two-cable arm with a post in its way
    (``REACH_AROUND_SCENE``) reaching a random static target, 20 Hz, 100
    steps (5 s); keywords as :class:`RodEnv` and :class:`ReachAroundTask`."""
    names = ("effort_weight", "success_radius", "penetration_weight")
    task_kw = {k: kwargs.pop(k) for k in names if k in kwargs}
    kwargs.setdefault("episode_steps", 100)
    kwargs.setdefault("rtol", TASK_RTOL)
    return RodEnv(scene or REACH_AROUND_SCENE, task or ReachAroundTask(**task_kw), **kwargs)


def push_env(scene=None, *, task: PushTask | None = None, **kwargs) -> RodEnv:
    """softrod/Push-v0: the two-cable arm pushing a box along a table to a
    goal (``PUSH_SCENE``), 20 Hz, 100 steps (5 s); keywords as
    :class:`RodEnv` and :class:`PushTask`."""
    names = ("body", "direction", "distance", "effort_weight", "reach_weight", "success_radius")
    task_kw = {k: kwargs.pop(k) for k in names if k in kwargs}
    kwargs.setdefault("episode_steps", 100)
    kwargs.setdefault("rtol", TASK_RTOL)
    return RodEnv(scene or PUSH_SCENE, task or PushTask(**task_kw), **kwargs)


__all__ = [
    "PUSH_SCENE",
    "REACH_AROUND_SCENE",
    "PushTask",
    "ReachAroundTask",
    "push_env",
    "reach_around_env",
]
