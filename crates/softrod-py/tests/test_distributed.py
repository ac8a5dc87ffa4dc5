"""softrod.distributed on a real local Ray cluster (ray.init(num_cpus=2)),
compared with the local softrod.simulate_many bit for bit; a worker that
dies mid-sweep is retried by Ray and every result comes back once."""

from __future__ import annotations

import functools
import os
import re
import sys

import numpy as np
import pytest

import softrod
import softrod.distributed as sd

from conftest import EXAMPLES

ray = pytest.importorskip("ray")
# The functions of this test module travel to the workers by value: the
# workers do not have tests/ on their path.
ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])


@pytest.fixture
def cluster(ray_cluster):
    """The session's local Ray cluster (conftest.ray_cluster)."""
    return ray_cluster


def cantilever(young: float) -> softrod.Simulation:
    """The shipped cantilever with another Young's modulus (a sweep's
    parameter)."""
    text = (EXAMPLES / "cantilever_gravity.toml").read_text()
    text, n = re.subn(r"young = [0-9.e+-]+", f"young = {young!r}", text)
    assert n == 1
    return softrod.Simulation.from_toml(text)


def assert_same(a: sd.Run, traj: softrod.Trajectory) -> None:
    for field in ("t", "q", "qdot", "tip_position", "table"):
        np.testing.assert_array_equal(getattr(a, field), getattr(traj, field))
    assert a.columns == tuple(traj.columns) and a.status == traj.status


def test_ray_backend_equals_local_simulate_many(cluster):
    text = (EXAMPLES / "cantilever_gravity.toml").read_text()
    specs = [str(EXAMPLES / "cable_planar_arm.toml")]
    specs += [functools.partial(softrod.Simulation.from_toml, text)] * 4
    runs = sd.simulate_many(specs, 0.2, backend="ray", chunk_size=2, output_every=0.01)
    sims = [softrod.Simulation.from_file(specs[0])] + [
        softrod.Simulation.from_toml(text) for _ in range(4)
    ]
    local = softrod.simulate_many(sims, 0.2, output_every=0.01)
    assert len(runs) == 5
    for r, tr in zip(runs, local):
        assert_same(r, tr)
    # The local backend gives the same Runs (Simulations accepted there).
    for r, tr in zip(sd.simulate_many(sims, 0.2, output_every=0.01, threads=2), local):
        assert_same(r, tr)
    # Simulations travel too (pickled: scene text, settings, initial
    # state), one with its initial state changed: the same runs bit for bit.
    q0, qd0 = sims[1].initial_state()
    sims[1].set_initial_state(q0, qd0 + 0.1)
    local = softrod.simulate_many(sims[:3], 0.2, output_every=0.01)
    runs = sd.simulate_many(sims[:3], 0.2, backend="ray", chunk_size=2, output_every=0.01)
    for r, tr in zip(runs, local):
        assert_same(r, tr)


def test_ray_sweep_equals_local_and_differs_by_parameter(cluster):
    youngs = [2e6, 5e6, 1e7, 2e7, 5e7]
    runs = sd.sweep(cantilever, youngs, 0.2, chunk_size=2)
    local = softrod.simulate_many([cantilever(e) for e in youngs], 0.2)
    for r, tr in zip(runs, local):
        assert_same(r, tr)
    # A stiffer rod sags less: the sweep's parameter reached each run.
    sag = [-r.tip_position[-1, 2] for r in runs]
    assert all(a != b for a, b in zip(sag, sag[1:]))


def dying(arg: tuple[float, str]) -> softrod.Simulation:
    """Builds the run; the first time the run marked to die is built, its
    worker process exits (as a crashed or lost node would)."""
    young, marker = arg
    if marker and not os.path.exists(marker):
        with open(marker, "w") as f:
            f.write("died once\n")
        os._exit(1)
    return cantilever(young)


def test_a_worker_that_dies_mid_sweep_is_retried_and_every_result_returned_once(
    cluster, tmp_path
):
    marker = str(tmp_path / "died")
    youngs = [2e6, 5e6, 1e7, 2e7, 5e7, 1e8]
    params = [(e, marker if i == 3 else "") for i, e in enumerate(youngs)]
    runs = sd.sweep(dying, params, 0.1, chunk_size=2, max_retries=2)
    assert os.path.exists(marker)  # the worker did die once
    local = softrod.simulate_many([cantilever(e) for e in youngs], 0.1)
    assert len(runs) == len(youngs)
    for r, tr in zip(runs, local):
        assert_same(r, tr)


def test_a_failing_simulation_raises_and_is_not_retried(cluster):
    with pytest.raises(softrod.InputError):
        sd.sweep(cantilever, [-1.0], 0.1)
