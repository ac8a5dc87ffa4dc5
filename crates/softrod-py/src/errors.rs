//! Rust errors as Python exceptions, and the guard that keeps panics from
//! crossing the boundary.
//!
//! The exception classes live in `softrod/_errors.py` (pure Python, so that
//! they can inherit from both `SoftrodError` and the built-in `ValueError` or
//! `RuntimeError`); this module raises them.

use std::panic::{AssertUnwindSafe, catch_unwind};

use pyo3::prelude::*;
use softrod::Error;
use softrod::dynamics::DynamicsError;
use softrod::integrate::IntegrateError;

pyo3::import_exception!(softrod._errors, InputError);
pyo3::import_exception!(softrod._errors, SceneError);
pyo3::import_exception!(softrod._errors, SimulationError);
pyo3::import_exception!(softrod._errors, InternalError);
pyo3::import_exception!(softrod._errors, NotSupportedError);

/// A `softrod.InputError` (a `ValueError`) with `message`.
pub fn input(message: impl Into<String>) -> PyErr {
    InputError::new_err(message.into())
}

/// The time at which an integration failed, when the error knows it.
pub fn failure_time(e: &IntegrateError) -> Option<f64> {
    match e {
        IntegrateError::NonFinite { t, .. }
        | IntegrateError::StepSizeUnderflow { t, .. }
        | IntegrateError::NewtonNonConvergence { t, .. }
        | IntegrateError::SingularMatrix { t, .. }
        | IntegrateError::MaxStepsExceeded { t, .. }
        | IntegrateError::BoundExceeded { t, .. }
        | IntegrateError::System { t, .. } => Some(*t),
        _ => None,
    }
}

/// `softrod.SimulationError(message)` with its `time` attribute set.
pub fn simulation(message: String, time: Option<f64>) -> PyErr {
    Python::attach(|py| {
        let err = SimulationError::new_err(message);
        // Attribute set on the instance: `except SimulationError as e: e.time`.
        let value = err.value(py);
        if value.setattr("time", time).is_err() {
            return PyErr::fetch(py);
        }
        err
    })
}

/// The Python exception for a facade error: bad input (scene, settings,
/// sizes, invalid model) is a `ValueError` subclass, a method that does not
/// cover the model a `NotImplementedError` subclass, a failed evaluation or
/// run a `RuntimeError` subclass; the message is the Rust one.
pub fn to_py(e: Error) -> PyErr {
    let message = e.with_causes();
    match &e {
        Error::Scene(_) => SceneError::new_err(message),
        Error::Integration(inner) => simulation(message, failure_time(inner)),
        Error::Output { t, .. } | Error::EnergyBalance { t, .. } | Error::Stretch { t, .. } => {
            simulation(message, Some(*t))
        }
        Error::Dynamics(
            DynamicsError::Unsupported { .. } | DynamicsError::UnsupportedClosed { .. },
        ) => NotSupportedError::new_err(message),
        _ if e.is_input() => input(message),
        Error::Kinematics(_) | Error::UnknownRod(_) => input(message),
        _ => simulation(message, None),
    }
}

/// As [`to_py`] for an error of the dynamics layer.
pub fn dynamics(e: DynamicsError) -> PyErr {
    to_py(Error::Dynamics(e))
}

/// As [`to_py`] for an integration error raised outside the facade.
pub fn integrate(e: IntegrateError) -> PyErr {
    to_py(Error::Integration(Box::new(e)))
}

/// Runs `f`, turning a panic into `softrod.InternalError` (a
/// `RuntimeError`) instead of letting it reach PyO3, which would raise a
/// `BaseException` that `except Exception` does not catch. The buffers a
/// panicking call was writing are scratch space, overwritten by the next
/// call, so the object stays usable.
pub fn guard<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic payload".into());
            Err(InternalError::new_err(format!(
                "internal error in softrod (a Rust panic, please report it): {what}"
            )))
        }
    }
}

/// [`guard`] with the GIL released while `f` runs (for calls longer than
/// the few microseconds that releasing and re-taking it costs).
pub fn guard_detached<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    py.detach(|| guard(f))
}
