"""The batched vector environment: many :class:`RodEnv` copies whose physics
steps in one call to ``softrod.BatchStepper`` (Rust threads, GIL released).

Each copy keeps its own :class:`RodEnv` for everything but the physics
(action policy, task, observation, reward, seeded generator), and the
physics of copy ``i`` equals its own ``Simulation.step`` bit for bit, so
the batch gives exactly what ``gymnasium.vector.SyncVectorEnv`` over the
same envs gives (tests/test_envs.py compares them).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

import softrod
from softrod._errors import InputError

from ._core import RodEnv


class BatchedVectorEnv(VectorEnv):
    """A Gymnasium ``VectorEnv`` of ``RodEnv`` copies stepped together in
    Rust threads.

    ``env_fns``: callables that each build a :class:`RodEnv` (as for
    ``SyncVectorEnv``); the copies must have the same control period,
    spaces and sizes. ``threads``: the Rust pool's size (default: the
    machine's cores). ``autoreset_mode``: Gymnasium's
    (``AutoresetMode.NEXT_STEP``, the default, or ``SAME_STEP``), with the
    meaning Gymnasium gives it: in NEXT_STEP an episode that ended is reset
    by the next ``step`` call, whose action for that copy is ignored and
    whose reward, terminated and truncated are 0, False, False; in
    SAME_STEP it is reset in the step that ended it, the final observation
    and info in ``info["final_obs"]`` and ``info["final_info"]``.

    ``reset(seed=s)`` seeds copy i with ``s + i`` (a list: one seed per
    copy), as SyncVectorEnv does; ``options={"reset_mask": mask}`` resets
    only the copies where ``mask`` (bool, (num_envs,)) is True.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        env_fns: Sequence[Callable[[], RodEnv]],
        *,
        threads: int | None = None,
        autoreset_mode: str | AutoresetMode = AutoresetMode.NEXT_STEP,
    ):
        self.envs = [fn() for fn in env_fns]
        if not self.envs:
            raise InputError("env_fns must build at least one env")
        for i, e in enumerate(self.envs):
            e = getattr(e, "unwrapped", e)
            if not isinstance(e, RodEnv):
                raise InputError(f"env_fns[{i}] built a {type(e).__name__}, not a softrod RodEnv")
            self.envs[i] = e
        first = self.envs[0]
        for i, e in enumerate(self.envs[1:], 1):
            if (
                e.observation_space != first.observation_space
                or e.action_space != first.action_space
                or e.control_period != first.control_period
                or e.substeps != first.substeps
            ):
                raise InputError(
                    f"env {i} differs from env 0 in its spaces, control period or substeps: a batch's "
                    "copies must match"
                )
        self.num_envs = len(self.envs)
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        if self.autoreset_mode == AutoresetMode.DISABLED:
            raise InputError("autoreset_mode DISABLED is not supported (NEXT_STEP or SAME_STEP)")
        self.metadata = dict(self.metadata, autoreset_mode=self.autoreset_mode)
        self.single_observation_space = first.observation_space
        self.single_action_space = first.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.stepper = softrod.BatchStepper([e.sim for e in self.envs], threads=threads)
        self._autoreset = np.zeros(self.num_envs, dtype=np.bool_)
        self._obs = np.zeros((self.num_envs,) + self.single_observation_space.shape)

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options=None):
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, int):
            seeds = [seed + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise InputError(f"seed: {len(seeds)} seeds for {self.num_envs} envs")
        options = dict(options) if options else {}
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = np.ones(self.num_envs, dtype=np.bool_)
        elif not (isinstance(mask, np.ndarray) and mask.dtype == np.bool_
                  and mask.shape == (self.num_envs,) and mask.any()):
            raise InputError(
                f"options['reset_mask'] must be a bool array of shape ({self.num_envs},) "
                "with at least one True"
            )
        infos: dict[str, Any] = {}
        for i, (env, s) in enumerate(zip(self.envs, seeds)):
            if mask[i]:
                self._obs[i], info = env.reset(seed=s, options=options or None)
                self._restart(i)
                infos = self._add_info(infos, info, i)
        self._autoreset[mask] = False
        return self._obs.copy(), infos

    def step(self, actions: Any):
        actions = np.asarray(actions, dtype=np.float64)
        n = self.num_envs
        shape = (n,) + self.single_action_space.shape
        if actions.shape != shape:
            raise InputError(f"actions must have shape {shape}, got {actions.shape}")
        next_step = self.autoreset_mode == AutoresetMode.NEXT_STEP
        active = ~self._autoreset if next_step else np.ones(n, dtype=np.bool_)
        # Every action is checked before any copy moves.
        prepared: list[tuple[np.ndarray, bool] | None] = [
            env._prepare(a) if active[i] else None
            for i, (env, a) in enumerate(zip(self.envs, actions))
        ]
        e0 = self.envs[0]
        nc, nj, ne, npr = e0.n_cables, e0.n_joint_inputs, e0.n_effort, e0.n_prescribed
        a = np.zeros((n, ne + npr))
        for i, p in enumerate(prepared):
            if p is not None:
                a[i] = p[0]
        t = np.array([e.t for e in self.envs])
        q = np.array([e.q for e in self.envs])
        qd = np.array([e.qdot for e in self.envs])
        if npr:
            # An inactive copy's row is never read; keep it inside the box.
            a[~active, ne:] = e0.target_low
        q1, qd1, errors = self.stepper.step(
            t, q, qd, np.ascontiguousarray(a[:, :nc]), self.envs[0].control_period,
            [bool(x) for x in active], substeps=self.envs[0].substeps,
            joint_forces=np.ascontiguousarray(a[:, nc:ne]) if nj else None,
            prescribed_targets=np.ascontiguousarray(a[:, ne:]) if npr else None,
        )
        if npr:
            # Each env's own Simulation (its observations' poses) follows the
            # drive its stepper copy was commanded, as Simulation.step does.
            for i, env in enumerate(self.envs):
                if prepared[i] is not None:
                    env.sim.command_prescribed(t[i], env.control_period, a[i, ne:])
        rewards = np.zeros(n)
        terms = np.zeros(n, dtype=np.bool_)
        truncs = np.zeros(n, dtype=np.bool_)
        infos: dict[str, Any] = {}
        for i, env in enumerate(self.envs):
            p = prepared[i]
            if p is None:  # NEXT_STEP: this copy's episode ended last step
                self._obs[i], info = env.reset()
                self._restart(i)
            else:
                self._obs[i], rewards[i], terms[i], truncs[i], info = env._finish(
                    p[0], p[1], q1[i], qd1[i], errors[i]
                )
                if not next_step and (terms[i] or truncs[i]):
                    infos = self._add_info(
                        infos, {"final_obs": self._obs[i].copy(), "final_info": info}, i
                    )
                    self._obs[i], info = env.reset()
                    self._restart(i)
            infos = self._add_info(infos, info, i)
        self._autoreset = terms | truncs
        return self._obs.copy(), rewards, terms, truncs, infos

    def _restart(self, i: int) -> None:
        """Copy i's episode starts over: no friction history, the scene's
        prescribed curves (as ``RodEnv.reset`` does to its Simulation)."""
        self.stepper.reset_contact(i)
        if self.envs[i].n_prescribed:
            self.stepper.reset_prescribed(i)

    def close_extras(self, **kwargs):
        for e in self.envs:
            e.close()
