//! Test hooks: functions the Python tests and benches call to reach what
//! the API does not show (a panic at the boundary, per-run timings of a
//! parallel batch, the Rust side of the call-overhead bench). Compiled
//! only with the `test-hooks` feature, which the dev install
//! (`scripts/install.sh --dev`) enables and the release wheel does not.

use pyo3::prelude::*;

use crate::{errors, many, simulation, trajectory};

/// `simulate_many` that also returns each run's (start, end, thread) —
/// seconds since the batch started and the pool thread's index — for the
/// tests of the parallel speed-up.
#[pyfunction]
#[pyo3(signature = (sims, duration, *, threads = None))]
fn _simulate_many_timed(
    py: Python<'_>,
    sims: &Bound<'_, PyAny>,
    duration: f64,
    threads: Option<usize>,
) -> PyResult<(Vec<trajectory::Trajectory>, Vec<many::Timing>)> {
    many::run_many(py, sims, Some(duration), threads, None, None, &|_| Ok(()))
}

/// Seconds per call of the facade's `forward_dynamics` at `(q, qdot)`,
/// `tau = 0`, timed over `calls` calls in a Rust loop: the Rust side of the
/// Python call-overhead bench (crates/softrod-py/bench/forward_dynamics.py).
#[pyfunction]
fn _time_forward_dynamics(
    sim: &mut simulation::Simulation,
    q: Vec<f64>,
    qdot: Vec<f64>,
    calls: usize,
) -> PyResult<f64> {
    let start = std::time::Instant::now();
    for _ in 0..calls {
        let qdd = sim
            .sim
            .forward_dynamics(0.0, &q, &qdot, None)
            .map_err(errors::to_py)?;
        std::hint::black_box(qdd);
    }
    Ok(start.elapsed().as_secs_f64() / calls.max(1) as f64)
}

/// Panics inside Rust, to test that a panic reaches Python as
/// `softrod.InternalError` (a `RuntimeError`) and not as an abort.
#[pyfunction]
fn _panic(py: Python<'_>, message: String, release_gil: bool) -> PyResult<()> {
    let f = move || -> PyResult<()> { panic!("{message}") };
    if release_gil {
        errors::guard_detached(py, f)
    } else {
        errors::guard(f)
    }
}

/// Adds the hooks to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_simulate_many_timed, m)?)?;
    m.add_function(wrap_pyfunction!(_panic, m)?)?;
    m.add_function(wrap_pyfunction!(_time_forward_dynamics, m)?)?;
    Ok(())
}
