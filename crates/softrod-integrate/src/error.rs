//! The crate's error type.

use std::error::Error as StdError;

/// A boxed error raised by the user's system (right-hand side, accelerations
/// or Jacobians).
pub type SystemError = Box<dyn StdError + Send + Sync + 'static>;

/// Why an integration failed. Every variant carries the time `t` at which it
/// happened and the step size `h` that was being tried (0 before the first
/// step), plus the check that fired.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IntegrateError {
    /// The arguments are inconsistent (dimensions, time span, options).
    #[error("invalid input: {what}")]
    InvalidInput {
        /// What is wrong.
        what: String,
    },
    /// A NaN or Inf appeared in an accepted state or in a derivative the
    /// integrator must use. No non-finite value is ever written to the output.
    #[error("non-finite value in {what} at t = {t:e} (h = {h:e}), component {index}")]
    NonFinite {
        /// Time of the state in which it was found.
        t: f64,
        /// Step size being tried.
        h: f64,
        /// Which quantity ("state", "derivative", "Jacobian", ...).
        what: &'static str,
        /// First offending component.
        index: usize,
    },
    /// The step-size controller asked for a step below the minimum (or below
    /// the resolution of `t`).
    #[error("step size underflow at t = {t:e}: h = {h:e} < h_min = {h_min:e} ({reason})")]
    StepSizeUnderflow {
        /// Time at which the step could not be taken.
        t: f64,
        /// The rejected step size.
        h: f64,
        /// The smallest step size allowed.
        h_min: f64,
        /// The check that kept shrinking the step (error test, non-finite
        /// trial, Newton failure).
        reason: &'static str,
    },
    /// The Newton iteration of an implicit method did not converge, even with
    /// a fresh Jacobian and the smallest allowed step.
    #[error(
        "Newton iteration did not converge at t = {t:e} (h = {h:e}) after {iterations} iterations: {what}"
    )]
    NewtonNonConvergence {
        /// Time at the start of the step.
        t: f64,
        /// Step size tried.
        h: f64,
        /// Iterations done in the last attempt.
        iterations: usize,
        /// Which check failed ("diverged", "too slow", "max iterations").
        what: &'static str,
    },
    /// The iteration matrix of an implicit method is singular.
    #[error("singular iteration matrix at t = {t:e} (h = {h:e}): {what}")]
    SingularMatrix {
        /// Time at the start of the step.
        t: f64,
        /// Step size tried.
        h: f64,
        /// Which matrix.
        what: &'static str,
    },
    /// More than [`Options::max_steps`](crate::Options::max_steps) accepted
    /// steps.
    #[error("maximum number of steps ({max_steps}) exceeded at t = {t:e} (h = {h:e})")]
    MaxStepsExceeded {
        /// Time reached.
        t: f64,
        /// Last step size.
        h: f64,
        /// The limit.
        max_steps: usize,
    },
    /// A norm or user monitor (e.g. energy) exceeded its bound.
    #[error("{what} = {value:e} exceeds its bound {bound:e} at t = {t:e} (h = {h:e})")]
    BoundExceeded {
        /// Time of the accepted state that broke the bound.
        t: f64,
        /// Step size that produced it.
        h: f64,
        /// Which quantity ("state max-norm" or the monitor's name).
        what: &'static str,
        /// Its value.
        value: f64,
        /// The bound.
        bound: f64,
    },
    /// The user's system returned an error.
    #[error("system error in {what} at t = {t:e} (h = {h:e})")]
    System {
        /// Time of the evaluation.
        t: f64,
        /// Step size being tried.
        h: f64,
        /// Which evaluation ("rhs", "accel", "jacobian").
        what: &'static str,
        /// The system's error.
        #[source]
        source: SystemError,
    },
}

/// Index of the first non-finite entry of `v`, if any.
pub(crate) fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}
