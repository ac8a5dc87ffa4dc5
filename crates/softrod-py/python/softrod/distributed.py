"""Many simulations across processes and machines, with Ray.

``softrod.simulate_many`` runs a batch on the threads of one machine. When a
sweep outgrows one machine, the functions here schedule it on a Ray cluster
(``pip install softrod[ray]``) as Ray tasks, each running a chunk of the
simulations with ``softrod.simulate_many`` (one thread per task: Ray gives
each task its CPU), so a task is not one microsecond-long simulation. The
results are the same numbers, bit for bit, as the local run: each
simulation is integrated by the same code from the same inputs, whichever
process runs it.

What travels to a worker is a ``softrod.Simulation`` itself (it pickles:
its scene text, settings and initial state, rebuilt on the worker bit for
bit), a scene file path (on a cluster, a path every node can read), or
any picklable zero-argument function returning a Simulation
(``functools.partial(softrod.Simulation.from_toml, text)`` for scene
text). Each result comes back as a :class:`Run`: plain numpy arrays,
picklable.

Ray is imported only when ``backend="ray"`` is used: ``import softrod`` and
this module import neither Ray nor Gymnasium. Ray is started by the caller
(``ray.init(address=...)`` to join a cluster); when it is not, the first
task starts a local one (Ray's default).

A task whose worker process dies (a node lost, a crash) is retried by Ray
up to ``max_retries`` times; its chunk is then run again from the start,
and each result is still returned exactly once, in order. An exception
raised by a simulation is not retried (it would fail again): it propagates
with a note naming the run.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

import softrod

#: Settings keywords passed through to ``softrod.simulate_many``.
_SETTINGS = ("output_every", "integrator", "rtol", "atol", "dt")


@dataclass(frozen=True)
class Run:
    """One simulation's result as plain arrays (what crosses processes):
    the fields of ``softrod.Trajectory`` of the same names. ``t`` (n,) [s],
    ``q`` and ``qdot`` (n, n_dof), ``tip_position`` (n, 3) or (n, n_rods,
    3) as the Trajectory gives it, ``table`` (n, len(columns)) the rows of
    trajectory.csv, ``status`` and ``t_final`` [s]."""

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    tip_position: np.ndarray
    table: np.ndarray
    columns: tuple[str, ...]
    status: str
    t_final: float

    @classmethod
    def of(cls, traj: softrod.Trajectory) -> Run:
        """The arrays of ``traj`` (copies)."""
        return cls(
            t=np.array(traj.t),
            q=np.array(traj.q),
            qdot=np.array(traj.qdot),
            tip_position=np.array(traj.tip_position),
            table=np.array(traj.table),
            columns=tuple(traj.columns),
            status=traj.status,
            t_final=float(traj.t_final),
        )


def _itself(sim: softrod.Simulation) -> softrod.Simulation:
    return sim


def _builder(spec: Any, i: int) -> Callable[[], softrod.Simulation]:
    if isinstance(spec, (str, os.PathLike)):
        path = os.fspath(spec)
        return lambda: softrod.Simulation.from_file(path)
    if isinstance(spec, softrod.Simulation):
        # Pickled with the task (Simulation.__reduce__), rebuilt there.
        return functools.partial(_itself, spec)
    if callable(spec):
        return spec
    raise softrod.InputError(
        f"sims[{i}] must be a scene file path or a function returning a softrod.Simulation, "
        f"got {type(spec).__name__}"
    )


def _built(make: Callable[[], softrod.Simulation], i: int) -> softrod.Simulation:
    sim = make()
    if not isinstance(sim, softrod.Simulation):
        raise softrod.InputError(
            f"run {i}: the builder returned a {type(sim).__name__}, not a softrod.Simulation"
        )
    return sim


def _run_chunk(
    makers: list[Callable[[], softrod.Simulation]],
    first: int,
    duration: float | None,
    settings: dict[str, Any],
) -> list[Run]:
    """Builds and runs one chunk (runs ``first``, ``first + 1``, …) on one
    thread; what a Ray task executes."""
    sims = [_built(m, first + k) for k, m in enumerate(makers)]
    try:
        trajs = softrod.simulate_many(sims, duration, threads=1, **settings)
    except softrod.SoftrodError as e:
        e.add_note(f"in the chunk of runs {first}..{first + len(sims) - 1}")
        raise
    return [Run.of(tr) for tr in trajs]


def _settings(kw: dict[str, Any]) -> dict[str, Any]:
    unknown = sorted(set(kw) - set(_SETTINGS))
    if unknown:
        raise softrod.InputError(f"unknown keywords {unknown} (settings: {list(_SETTINGS)})")
    return {k: v for k, v in kw.items() if v is not None}


def _run(
    makers: list[Callable[[], softrod.Simulation]],
    duration: float | None,
    backend: str,
    chunk_size: int | None,
    max_retries: int,
    threads: int | None,
    settings: dict[str, Any],
) -> list[Run]:
    if backend == "local":
        sims = [_built(m, i) for i, m in enumerate(makers)]
        trajs = softrod.simulate_many(sims, duration, threads=threads, **settings)
        return [Run.of(tr) for tr in trajs]
    if backend != "ray":
        raise softrod.InputError(f'backend must be "local" or "ray", got {backend!r}')
    import ray  # the optional extra softrod[ray]

    if not makers:
        return []
    if chunk_size is None:
        # About four tasks per CPU of the cluster: enough to balance the
        # load, few enough that scheduling (milliseconds) stays small next
        # to a task's runs.
        cpus = int(ray.cluster_resources().get("CPU", 1)) if ray.is_initialized() else 1
        chunk_size = max(1, math.ceil(len(makers) / (4 * max(cpus, 1))))
    if chunk_size < 1:
        raise softrod.InputError(f"chunk_size must be at least 1, got {chunk_size}")
    task = ray.remote(num_cpus=1, max_retries=max_retries, retry_exceptions=False)(_run_chunk)
    refs = [
        task.remote(makers[k : k + chunk_size], k, duration, settings)
        for k in range(0, len(makers), chunk_size)
    ]
    out: list[Run] = []
    for chunk in ray.get(refs):
        out.extend(chunk)
    return out


def simulate_many(
    sims: Sequence[Any],
    duration: float | None = None,
    *,
    backend: str = "local",
    chunk_size: int | None = None,
    max_retries: int = 3,
    threads: int | None = None,
    **settings: Any,
) -> list[Run]:
    """Runs independent simulations and returns a :class:`Run` for each, in
    order.

    ``sims``: ``softrod.Simulation`` objects, scene file paths or
    zero-argument functions returning a Simulation.
    ``duration`` [s]: as for ``softrod.simulate_many`` (default: each
    scene's ``[run] duration``); keywords ``output_every``, ``integrator``,
    ``rtol``, ``atol``, ``dt`` override every run's settings.

    ``backend="local"``: ``softrod.simulate_many`` on ``threads`` threads of
    this machine. ``backend="ray"``: Ray tasks of ``chunk_size`` runs each
    (default: about four tasks per CPU of the cluster), each retried up to
    ``max_retries`` times if its worker dies. Both give the same numbers bit
    for bit.
    """
    makers = [
        # Locally a Simulation needs no building (simulate_many copies it).
        (lambda s=s: s) if backend == "local" and isinstance(s, softrod.Simulation)
        else _builder(s, i)
        for i, s in enumerate(sims)
    ]
    return _run(makers, duration, backend, chunk_size, max_retries, threads, _settings(settings))


def sweep(
    build: Callable[[Any], softrod.Simulation],
    params: Sequence[Any],
    duration: float | None = None,
    *,
    backend: str = "ray",
    chunk_size: int | None = None,
    max_retries: int = 3,
    threads: int | None = None,
    **settings: Any,
) -> list[Run]:
    """A parameter sweep: runs ``build(p)`` for every ``p`` in ``params``
    and returns the :class:`Run` of each, in the order of ``params``.

    ``build`` must be picklable for Ray (a module-level function, or any
    function cloudpickle takes); it runs on the worker, so only ``p``
    travels. Other arguments as for :func:`simulate_many`; the default
    backend here is Ray.
    """
    if not callable(build):
        raise softrod.InputError("build must be a function p -> softrod.Simulation")
    makers = [_Bound(build, p) for p in params]
    return _run(makers, duration, backend, chunk_size, max_retries, threads, _settings(settings))


class _Bound:
    """``build`` with its parameter: a picklable zero-argument builder."""

    __slots__ = ("build", "p")

    def __init__(self, build: Callable[[Any], softrod.Simulation], p: Any):
        self.build, self.p = build, p

    def __call__(self) -> softrod.Simulation:
        return self.build(self.p)

    def __getstate__(self):
        return (self.build, self.p)

    def __setstate__(self, state):
        self.build, self.p = state


__all__ = ["Run", "simulate_many", "sweep"]
