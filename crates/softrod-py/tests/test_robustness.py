"""No panic crosses the boundary, and no call leaks memory."""

from __future__ import annotations

import gc
import os

import numpy as np
import pytest

import softrod
from conftest import rod, smooth_state


@pytest.mark.parametrize("release_gil", [False, True])
def test_a_panic_is_a_runtime_error(release_gil):
    with pytest.raises(softrod.InternalError, match="a Rust panic.*boom") as e:
        softrod._softrod._panic("boom", release_gil)
    assert isinstance(e.value, RuntimeError)
    # The interpreter and the package go on working.
    sim = softrod.Simulation(rods=[rod(pieces=2)])
    assert sim.mass_matrix(0.0, np.zeros(sim.n_dof)).shape == (12, 12)


def test_non_finite_input_is_reported_not_propagated():
    sim = softrod.Simulation(rods=[rod(pieces=2)])
    q = np.zeros(sim.n_dof)
    q[3] = np.nan
    with pytest.raises(softrod.SoftrodError):
        sim.forward_dynamics(0.0, q, np.zeros(sim.n_dof))


def test_a_failed_run_names_the_failure_time():
    """rk4 far past its stability limit: the run watch stops it at the first
    step whose energy balance breaks, with an error carrying the time,
    before the state can grow to NaN."""
    sim = softrod.Simulation(rods=[rod(pieces=4)], gravity=[0, 0, -9.81])
    with pytest.raises(softrod.SimulationError) as e:
        sim.simulate(1.0, integrator="rk4", dt=1e-2)
    assert isinstance(e.value, RuntimeError)
    assert e.value.time is not None and 0.0 <= e.value.time < 1.0
    assert "energy balance violated at t = 1e-2 s" in str(e.value)


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="Linux /proc")
def test_no_call_leaks_memory_over_10000_repetitions():
    """RSS after 10 000 calls of each entry point stays within 512 KiB of
    RSS after a warm-up of 1000 calls (measured growth: 0). A leak of 53
    bytes per call of any one entry point would pass the bound; the smallest
    thing a call allocates, an output array of this model (24 coordinates),
    is ~216 bytes: kept on purpose 10 000 times it grows RSS by 2.1 MiB."""
    growth_bound = 512 * 1024
    sim = softrod.Simulation(rods=[rod(pieces=4, strains=["ky", "qx", "qz"],
                                       cables=[softrod.Cable(offset=(0, 0.005))])],
                             gravity=[0, 0, -9.81])
    n = sim.n_dof
    q, qd = smooth_state(n, scale=0.1)
    st = sim.initial()
    calls = [
        lambda: sim.forward_dynamics(0.0, q, qd),
        lambda: sim.forward_dynamics(0.0, q, qd, u=[0.5]),
        lambda: sim.inverse_dynamics(0.0, q, qd, qd),
        lambda: sim.mass_matrix(0.0, q),
        lambda: sim.energies(0.0, q, qd),
        lambda: sim.pose(0, [0.1, 0.3], q),
        lambda: sim.jacobian(0, 0.3, q),
        lambda: sim.step(st, 1e-4, [0.2]),
    ]

    def failing():
        try:
            sim.mass_matrix(0.0, q[:3])
        except softrod.InputError:
            pass

    calls.append(failing)

    def run(k):
        for f in calls:
            for _ in range(k):
                f()
        gc.collect()

    run(1000)
    before = rss_bytes()
    run(10_000)
    growth = rss_bytes() - before
    assert growth < growth_bound, f"RSS grew by {growth / 1024:.0f} KiB"
    # Whole runs too (each keeps its trajectory until dropped).
    for _ in range(50):
        sim.simulate(0.002, output_every=0.001)
    gc.collect()
    before = rss_bytes()
    for _ in range(500):
        sim.simulate(0.002, output_every=0.001)
    gc.collect()
    assert rss_bytes() - before < growth_bound
