//! The compiled module `softrod._softrod` of the Python package `softrod`:
//! the facade crate's [`softrod::Simulation`] with numpy arrays in and out,
//! rods built in Python, everything else a scene can say read from Python
//! values by the scene loader (`scene_dict`), contacts (`contacts`),
//! cable-tension inputs, a controller in the loop, a step API, parallel
//! runs and batched steps.
//!
//! Build and install with maturin (`scripts/install.sh`, or
//! `scripts/test.sh` for the tests); the Python sources, type stubs and
//! tests are beside this crate (`python/softrod/`, `tests/`). Units SI;
//! equations cite the labels of docs/theory.md.
//!
//! The rules the Python API keeps (and the facade's crate docs state for
//! Rust): time is an argument, never hidden state — the dynamics calls take
//! it first, `f(t, q, qdot)`, the kinematic queries as the keyword `t`
//! (default 0); durations default to the scene's `[run] duration` in
//! `simulate` and `simulate_many` alike; velocities are `qdot`; a rod is
//! named by its name or its index; an error's message states each of its
//! causes once (`softrod::report`). What a run records comes from the
//! facade's recorder (`softrod::record`), so a `Trajectory`'s `table` is
//! `trajectory.csv`'s rows.
//!
//! The test hooks the Python suite calls (`_panic`, `_simulate_many_timed`,
//! `_time_forward_dynamics`) are compiled only with the `test-hooks`
//! feature (the dev install's), never into the release wheel.
#![warn(missing_docs)]

use pyo3::prelude::*;

mod batch;
mod contacts;
mod control;
mod convert;
mod errors;
#[cfg(feature = "test-hooks")]
mod hooks;
mod many;
mod model;
mod results;
mod scene_dict;
mod settings;
mod simulation;
mod trajectory;

use crate::settings::overrides;

/// Runs independent simulations in parallel and returns their
/// trajectories, in order.
///
/// `sims`: a list of `softrod.Simulation` (each run from its own initial
/// state with its own settings), or one Simulation with a batch of initial
/// states `q0` and/or `qdot0` of shape (runs, n_dof). `duration` [s]: as
/// for `Simulation.simulate`, each simulation's scene `[run] duration`
/// when not given (a simulation built in Python has none and needs it);
/// `threads`: the pool size (default: the machine's cores). Keywords
/// `output_every`, `integrator`, `rtol`, `atol`, `dt` override every run's
/// settings. The GIL is released for the whole batch; the simulations are
/// copied, so the originals are not touched. The first run that fails
/// raises its exception, with a note naming the run.
#[pyfunction]
#[pyo3(signature = (sims, duration = None, *, threads = None, q0 = None, qdot0 = None,
                    output_every = None, integrator = None, rtol = None, atol = None, dt = None))]
#[allow(clippy::too_many_arguments)]
fn simulate_many(
    py: Python<'_>,
    sims: &Bound<'_, PyAny>,
    duration: Option<f64>,
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
        overrides(
            s,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            None,
            None,
            None,
            None,
        )
    };
    Ok(many::run_many(py, sims, duration, threads, q0, qdot0, &set)?.0)
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
    m.add_class::<settings::Settings>()?;
    m.add_class::<results::Energies>()?;
    m.add_class::<results::Statics>()?;
    m.add_class::<results::Modes>()?;
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
    m.add_class::<contacts::Contact>()?;
    m.add_function(wrap_pyfunction!(simulate_many, m)?)?;
    m.add_class::<batch::BatchStepper>()?;
    #[cfg(feature = "test-hooks")]
    hooks::register(m)?;
    Ok(())
}
