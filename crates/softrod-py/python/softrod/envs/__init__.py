"""Gymnasium environments over softrod scenes (needs ``pip install
softrod[rl]``, i.e. gymnasium >= 1.0; ``import softrod`` alone does not
import gymnasium).

>>> import gymnasium, softrod.envs
>>> env = gymnasium.make("softrod/Reach-v0")
>>> obs, info = env.reset(seed=0)
>>> obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

Importing this module registers:

- ``softrod/Reach-v0``: a two-cable planar arm reaching a random static
  target (:func:`reach_env`, :class:`ReachTask`);
- ``softrod/Track-v0``: a four-cable arm tracking a target moving on a
  circle in 3-D (:func:`track_env`, :class:`TrackTask`);
- ``softrod/ReachAround-v0``: the two-cable arm reaching a random target
  with a post in its way, in contact (:func:`reach_around_env`,
  :class:`ReachAroundTask`);
- ``softrod/Push-v0``: the two-cable arm pushing a box along a table to a
  random goal, in contact (:func:`push_env`, :class:`PushTask`);
- ``softrod/SwingReach-v0``: the two-cable arm on a prescribed revolute
  base whose angle target is part of the action (:func:`swing_reach_env`,
  :class:`ReachTask`).

Both accept the keywords of :class:`RodEnv` through ``gymnasium.make``
(``scene=``, ``control_period=``, ``max_tension=``, ``observe=``, …), and
``gymnasium.make_vec(id, num_envs=n, vectorization_mode="vector_entry_point")``
gives a :class:`BatchedVectorEnv` whose copies step in Rust threads. Any
other scene with cables: ``RodEnv("my_scene.toml", ReachTask())``.
Documentation: docs/envs.md of the repository.
"""

from __future__ import annotations

import gymnasium

from softrod._errors import InputError

from ._core import (
    DEFAULT_MAX_TENSION,
    DEFAULT_Q_LIMIT,
    OBSERVATION_KEYS,
    REACH_SCENE,
    SWING_REACH_SCENE,
    TASK_RTOL,
    TRACK_SCENE,
    ReachTask,
    RodEnv,
    Task,
    TrackTask,
    reach_env,
    swing_reach_env,
    track_env,
)
from ._contact import (
    PUSH_SCENE,
    REACH_AROUND_SCENE,
    PushTask,
    ReachAroundTask,
    push_env,
    reach_around_env,
)
from ._vector import BatchedVectorEnv


def reach_vector_env(num_envs: int, *, threads: int | None = None, autoreset_mode=None, **kwargs):
    """A :class:`BatchedVectorEnv` of ``num_envs`` softrod/Reach-v0 copies
    (keywords of :func:`reach_env`)."""
    return _vector(reach_env, num_envs, threads, autoreset_mode, kwargs)


def track_vector_env(num_envs: int, *, threads: int | None = None, autoreset_mode=None, **kwargs):
    """A :class:`BatchedVectorEnv` of ``num_envs`` softrod/Track-v0 copies
    (keywords of :func:`track_env`)."""
    return _vector(track_env, num_envs, threads, autoreset_mode, kwargs)


def reach_around_vector_env(
    num_envs: int, *, threads: int | None = None, autoreset_mode=None, **kwargs
):
    """A :class:`BatchedVectorEnv` of ``num_envs`` softrod/ReachAround-v0
    copies (keywords of :func:`reach_around_env`)."""
    return _vector(reach_around_env, num_envs, threads, autoreset_mode, kwargs)


def swing_reach_vector_env(
    num_envs: int, *, threads: int | None = None, autoreset_mode=None, **kwargs
):
    """A :class:`BatchedVectorEnv` of ``num_envs`` softrod/SwingReach-v0
    copies (keywords of :func:`swing_reach_env`)."""
    return _vector(swing_reach_env, num_envs, threads, autoreset_mode, kwargs)


def push_vector_env(num_envs: int, *, threads: int | None = None, autoreset_mode=None, **kwargs):
    """A :class:`BatchedVectorEnv` of ``num_envs`` softrod/Push-v0 copies
    (keywords of :func:`push_env`)."""
    return _vector(push_env, num_envs, threads, autoreset_mode, kwargs)


#: The task names of :func:`make_env_from_config`.
TASKS = {
    "reach": reach_env,
    "track": track_env,
    "reach_around": reach_around_env,
    "push": push_env,
    "swing_reach": swing_reach_env,
}


def make_env_from_config(config) -> RodEnv:
    """An env from a config mapping, the form RLlib and Ray Tune hand to an
    env factory (``ray.tune.registry.register_env(name, lambda c:
    softrod.envs.make_env_from_config(c))``): ``config["task"]`` names the
    task (``"reach"`` — the default —, ``"track"``, ``"reach_around"``,
    ``"push"``, ``"swing_reach"``); the other entries are the keywords of its env function
    (:func:`reach_env`, …). An unknown task raises ``softrod.InputError``."""
    kwargs = dict(config or {})
    task = kwargs.pop("task", "reach")
    if task not in TASKS:
        raise InputError(f"config['task'] = {task!r}: one of {sorted(TASKS)}")
    return TASKS[task](**kwargs)


def _vector(make, num_envs, threads, autoreset_mode, kwargs):
    kw = {} if autoreset_mode is None else {"autoreset_mode": autoreset_mode}
    # gymnasium.make_vec passes render_mode; these envs do not render.
    kwargs.pop("render_mode", None)
    return BatchedVectorEnv([lambda: make(**kwargs)] * num_envs, threads=threads, **kw)


def _register() -> None:
    for env_id, entry, vector in (
        ("softrod/Reach-v0", "softrod.envs:reach_env", "softrod.envs:reach_vector_env"),
        ("softrod/Track-v0", "softrod.envs:track_env", "softrod.envs:track_vector_env"),
        (
            "softrod/ReachAround-v0",
            "softrod.envs:reach_around_env",
            "softrod.envs:reach_around_vector_env",
        ),
        ("softrod/Push-v0", "softrod.envs:push_env", "softrod.envs:push_vector_env"),
        (
            "softrod/SwingReach-v0",
            "softrod.envs:swing_reach_env",
            "softrod.envs:swing_reach_vector_env",
        ),
    ):
        if env_id not in gymnasium.registry:
            # No max_episode_steps: the env truncates by itself (episode_steps),
            # the same way in single and batched envs.
            gymnasium.register(id=env_id, entry_point=entry, vector_entry_point=vector)


_register()

__all__ = [
    "DEFAULT_MAX_TENSION",
    "DEFAULT_Q_LIMIT",
    "OBSERVATION_KEYS",
    "PUSH_SCENE",
    "REACH_AROUND_SCENE",
    "REACH_SCENE",
    "SWING_REACH_SCENE",
    "TASK_RTOL",
    "TRACK_SCENE",
    "TASKS",
    "BatchedVectorEnv",
    "PushTask",
    "ReachAroundTask",
    "ReachTask",
    "RodEnv",
    "Task",
    "TrackTask",
    "make_env_from_config",
    "push_env",
    "push_vector_env",
    "reach_around_env",
    "reach_around_vector_env",
    "reach_env",
    "reach_vector_env",
    "swing_reach_env",
    "swing_reach_vector_env",
    "track_env",
    "track_vector_env",
]
