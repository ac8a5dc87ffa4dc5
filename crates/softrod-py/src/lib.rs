//! The compiled module `softrod._softrod` of the Python package `softrod`:
//! the facade crate's [`softrod::Simulation`] with numpy arrays in and out,
//! rods built in Python, cable-tension inputs, a controller in the loop,
//! a step API and parallel runs.
//!
//! Build and install with maturin (`scripts/install.sh`, or
//! `scripts/test.sh` for the tests); the Python sources, type stubs and
//! tests are beside this crate (`python/softrod/`, `tests/`). Units SI;
//! equations cite the labels of docs/theory.md.
#![warn(missing_docs)]

use pyo3::prelude::*;

mod control;
mod convert;
mod errors;
mod many;
mod model;
mod simulation;
mod trajectory;

use crate::simulation::overrides;

/// Runs independent simulations in parallel and returns their
/// trajectories, in order.
///
/// `sims`: a list of `softrod.Simulation` (each run from its own initial
/// state with its own settings), or one Simulation with a batch of initial
/// states `q0` and/or `qdot0` of shape (runs, n_dof). `duration` [s];
/// `threads`: the pool size (default: the machine's cores). Keywords
/// `output_every`, `integrator`, `rtol`, `atol`, `dt` override every run's
/// settings. The GIL is released for the whole batch; the simulations are
/// copied, so the originals are not touched. The first run that fails
/// raises its exception, with a note naming the run.
#[pyfunction]
#[pyo3(signature = (sims, duration, *, threads = None, q0 = None, qdot0 = None,
                    output_every = None, integrator = None, rtol = None, atol = None, dt = None))]
#[allow(clippy::too_many_arguments)]
fn simulate_many(
    py: Python<'_>,
    sims: &Bound<'_, PyAny>,
    duration: f64,
    threads: Option<usize>,
    q0: Option<&Bound<'_, PyAny>>,
    qdot0: Option<&Bound<'_, PyAny>>,
    output_every: Option<f64>,
    integrator: Option<&str>,
    rtol: Option<f64>,
    atol: Option<f64>,
    dt: Option<f64>,
) -> PyResult<Vec<trajectory::Trajectory>> {
    let set = |s: &mut softrod::Settings| {
        overrides(s, integrator, rtol, atol, dt, output_every, None, None)
    };
    Ok(many::run_many(py, sims, duration, threads, q0, qdot0, &set)?.0)
}

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
    many::run_many(py, sims, duration, threads, None, None, &|_| Ok(()))
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

/// The compiled part of the `softrod` package.
#[pymodule]
fn _softrod(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The one list of integrators (softrod-integrate's), by scene name.
    let integrators = softrod::Integrator::ALL.map(softrod::Integrator::name);
    m.add(
        "INTEGRATORS",
        pyo3::types::PyTuple::new(m.py(), integrators)?,
    )?;
    m.add_class::<simulation::Simulation>()?;
    m.add_class::<simulation::Settings>()?;
    m.add_class::<simulation::Energies>()?;
    m.add_class::<simulation::Statics>()?;
    m.add_class::<simulation::Modes>()?;
    m.add_class::<trajectory::Trajectory>()?;
    m.add_class::<trajectory::State>()?;
    m.add_class::<model::Section>()?;
    m.add_class::<model::Circle>()?;
    m.add_class::<model::Tube>()?;
    m.add_class::<model::Rectangle>()?;
    m.add_class::<model::TaperedCircle>()?;
    m.add_class::<model::Material>()?;
    m.add_class::<model::Cable>()?;
    m.add_class::<model::PointLoad>()?;
    m.add_class::<model::Rod>()?;
    m.add_function(wrap_pyfunction!(simulate_many, m)?)?;
    m.add_function(wrap_pyfunction!(_simulate_many_timed, m)?)?;
    m.add_function(wrap_pyfunction!(_panic, m)?)?;
    m.add_function(wrap_pyfunction!(_time_forward_dynamics, m)?)?;
    Ok(())
}
