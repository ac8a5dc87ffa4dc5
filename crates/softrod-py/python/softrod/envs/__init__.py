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
  circle in 3-D (:func:`track_env`, :class:`TrackTask`).

Both accept the keywords of :class:`RodEnv` through ``gymnasium.make``
(``scene=``, ``control_period=``, ``max_tension=``, ``observe=``, …), and
``gymnasium.make_vec(id, num_envs=n, vectorization_mode="vector_entry_point")``
gives a :class:`BatchedVectorEnv` whose copies step in Rust threads. Any
other scene with cables: ``RodEnv("my_scene.toml", ReachTask())``.
Documentation: docs/envs.md of the repository.
"""

from __future__ import annotations

import gymnasium

from ._core import (
    DEFAULT_MAX_TENSION,
    DEFAULT_Q_LIMIT,
    OBSERVATION_KEYS,
    REACH_SCENE,
    TRACK_SCENE,
    ReachTask,
    RodEnv,
    Task,
    TrackTask,
    reach_env,
    track_env,
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


def _vector(make, num_envs, threads, autoreset_mode, kwargs):
    kw = {} if autoreset_mode is None else {"autoreset_mode": autoreset_mode}
    # gymnasium.make_vec passes render_mode; these envs do not render.
    kwargs.pop("render_mode", None)
    return BatchedVectorEnv([lambda: make(**kwargs)] * num_envs, threads=threads, **kw)


def _register() -> None:
    for env_id, entry, vector in (
        ("softrod/Reach-v0", "softrod.envs:reach_env", "softrod.envs:reach_vector_env"),
        ("softrod/Track-v0", "softrod.envs:track_env", "softrod.envs:track_vector_env"),
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
    "REACH_SCENE",
    "TRACK_SCENE",
    "BatchedVectorEnv",
    "ReachTask",
    "RodEnv",
    "Task",
    "TrackTask",
    "reach_env",
    "reach_vector_env",
    "track_env",
    "track_vector_env",
]
