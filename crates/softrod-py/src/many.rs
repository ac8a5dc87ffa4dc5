//! `softrod.simulate_many`: independent runs in parallel on a rayon pool,
//! with the GIL released.

use std::time::Instant;

use nalgebra::DVector;
use pyo3::prelude::*;
use pyo3::types::PyList;
use rayon::prelude::*;

use crate::convert::array;
use crate::errors::{guard, input, to_py};
use crate::simulation::Simulation;
use crate::trajectory::Trajectory;

/// One run's timing: start and end [s] since the batch started, and the
/// index of the pool thread that ran it.
pub type Timing = (f64, f64, usize);

fn batch<'py>(
    obj: Option<&Bound<'py, PyAny>>,
    name: &str,
    runs: Option<usize>,
    n: usize,
) -> PyResult<Option<Vec<DVector<f64>>>> {
    let Some(obj) = obj else { return Ok(None) };
    let a = array(obj, name)?;
    let shape = a.shape().to_vec();
    let ok = shape.len() == 2 && shape[1] == n && runs.is_none_or(|r| r == shape[0]);
    if !ok {
        let want = match runs {
            Some(r) => format!("({r}, {n})"),
            None => format!("(runs, {n})"),
        };
        return Err(input(format!(
            "{name} must have shape {want}, got {shape:?}"
        )));
    }
    Ok(Some(
        a.slice()
            .chunks(n)
            .map(DVector::from_column_slice)
            .collect(),
    ))
}

/// The run's duration: `given`, else the simulation's scene `[run]
/// duration` (the rule of `Simulation.simulate`).
fn duration_of(given: Option<f64>, sim: &Simulation, which: &str) -> PyResult<f64> {
    let d = given.or(sim.duration).ok_or_else(|| {
        input(format!(
            "simulate_many needs a duration ({which} has no scene [run] duration)"
        ))
    })?;
    if !(d.is_finite() && d > 0.0) {
        return Err(to_py(softrod::Error::InvalidSetting {
            key: "duration",
            message: format!("must be positive and finite, got {d}"),
        }));
    }
    Ok(d)
}

/// Runs every job, returning the trajectories in order (the first error,
/// with its run index, if any fails) and each run's timing.
pub fn run_many(
    py: Python<'_>,
    sims: &Bound<'_, PyAny>,
    duration: Option<f64>,
    threads: Option<usize>,
    q0: Option<&Bound<'_, PyAny>>,
    qdot0: Option<&Bound<'_, PyAny>>,
    settings: &dyn Fn(&mut softrod::Settings) -> PyResult<()>,
) -> PyResult<(Vec<Trajectory>, Vec<Timing>)> {
    let mut jobs: Vec<softrod::Simulation> = Vec::new();
    let mut durations: Vec<f64> = Vec::new();
    if let Ok(one) = sims.cast::<Simulation>() {
        let base = one.borrow();
        let d = duration_of(duration, &base, "the simulation")?;
        let n = base.sim.n_dof();
        let qs = batch(q0, "q0", None, n)?;
        let runs = qs.as_ref().map(|v| v.len());
        let qds = batch(qdot0, "qdot0", runs, n)?;
        let runs = runs.or(qds.as_ref().map(|v| v.len())).ok_or_else(|| {
            input("simulate_many(sim, …) with one Simulation needs q0 and/or qdot0 of shape (runs, n_dof)")
        })?;
        let (iq, iqd) = base.sim.initial_state();
        for k in 0..runs {
            let mut s = base.sim.clone();
            let q = qs.as_ref().map_or(iq, |v| &v[k]);
            let qd = qds.as_ref().map_or(iqd, |v| &v[k]);
            s.set_initial_state(q.as_slice(), qd.as_slice())
                .map_err(to_py)?;
            jobs.push(s);
            durations.push(d);
        }
    } else {
        if q0.is_some() || qdot0.is_some() {
            return Err(input(
                "q0/qdot0 batches go with one Simulation; set each Simulation's initial state instead",
            ));
        }
        let list = sims
            .cast::<PyList>()
            .map_err(|_| input("sims must be a Simulation or a list of Simulations"))?;
        for (i, s) in list.iter().enumerate() {
            let s = s
                .cast::<Simulation>()
                .map_err(|_| input(format!("sims[{i}] is not a softrod.Simulation")))?;
            let s = s.borrow();
            durations.push(duration_of(duration, &s, &format!("sims[{i}]"))?);
            jobs.push(s.sim.clone());
        }
    }
    for s in jobs.iter_mut() {
        let mut st = s.settings().clone();
        settings(&mut st)?;
        s.set_settings(st).map_err(to_py)?;
    }
    if let Some(t) = threads {
        if t == 0 {
            return Err(input("threads must be at least 1"));
        }
    }
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let results = py.detach(|| {
        guard(|| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| input(format!("cannot start {threads} threads: {e}")))?;
            let start = Instant::now();
            Ok(pool.install(|| {
                jobs.par_iter_mut()
                    .zip(&durations)
                    .map(|(sim, &duration)| {
                        let t0 = start.elapsed().as_secs_f64();
                        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                            sim.simulate(duration)
                        }));
                        let t1 = start.elapsed().as_secs_f64();
                        let thread = rayon::current_thread_index().unwrap_or(0);
                        (r, (t0, t1, thread))
                    })
                    .collect::<Vec<_>>()
            }))
        })
    })?;
    let mut out = Vec::with_capacity(results.len());
    let mut timing = Vec::with_capacity(results.len());
    for (i, ((r, tm), sim)) in results.into_iter().zip(&jobs).enumerate() {
        let traj = match r {
            Ok(Ok(t)) => t,
            Ok(Err(e)) => {
                let err = to_py(e);
                // The same exception (type, message, `time`), with a note
                // saying which run.
                err.value(py)
                    .call_method1("add_note", (format!("in run {i} of simulate_many"),))?;
                return Err(err);
            }
            Err(_) => {
                return Err(crate::errors::InternalError::new_err(format!(
                    "internal error in softrod (a Rust panic in run {i}, please report it)"
                )));
            }
        };
        out.push(Trajectory::new(py, traj, sim.model())?);
        timing.push(tm);
    }
    Ok((out, timing))
}
