//! Step control shared by every method, one floor below the steppers: the
//! error norm, landing on the end time, the underflow check and the checks
//! of trial states.

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::DVector;

use crate::error::{IntegrateError, first_non_finite};
use crate::options::Options;

/// Weighted RMS norm of `e` with weights `atol + rtol·max(|ya|, |yb|)`
/// (Hairer–Wanner's error norm).
pub(crate) fn wrms(e: &DVector<f64>, ya: &DVector<f64>, yb: &DVector<f64>, opts: &Options) -> f64 {
    let n = e.len();
    if n == 0 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..n {
        let sc = opts.atol + opts.rtol * ya[i].abs().max(yb[i].abs());
        let r = e[i] / sc;
        s += r * r;
    }
    (s / n as f64).sqrt()
}

/// The step to take toward `t_end` from `t` with proposed size `h`: returns
/// `(h, last)`; the step is stretched to `t_end` if it would leave less than
/// 1 % of `h` (Hairer's rule), and `last` means land exactly on `t_end`.
pub(crate) fn clip_step(t: f64, h: f64, t_end: f64) -> (f64, bool) {
    if t + 1.01 * h >= t_end {
        let rem = t_end - t;
        // Within rounding of h: keep h itself so a fixed-step method keeps its
        // LU (the time still lands exactly on t_end).
        if (rem - h).abs() <= 1e-12 * h {
            (h, true)
        } else {
            (rem, true)
        }
    } else {
        (h, false)
    }
}

/// The smallest step allowed at `t`: `h_min`, and never below the
/// resolution of `t` (16 ulps).
pub(crate) fn min_step(t: f64, opts: &Options) -> f64 {
    opts.h_min.max(16.0 * f64::EPSILON * t.abs())
}

/// Checks the step size against `h_min` and the resolution of `t`.
pub(crate) fn check_underflow(
    t: f64,
    h: f64,
    opts: &Options,
    reason: &'static str,
) -> Result<(), IntegrateError> {
    let floor = min_step(t, opts);
    if !(h >= floor) || h == 0.0 {
        return Err(IntegrateError::StepSizeUnderflow {
            t,
            h,
            h_min: floor,
            reason,
        });
    }
    Ok(())
}

/// [`IntegrateError::NonFinite`] for the first non-finite entry of `v`.
pub(crate) fn check_finite(
    v: &DVector<f64>,
    t: f64,
    h: f64,
    what: &'static str,
) -> Result<(), IntegrateError> {
    match first_non_finite(v.as_slice()) {
        Some(index) => Err(IntegrateError::NonFinite { t, h, what, index }),
        None => Ok(()),
    }
}

/// A fixed step whose trial `ynew` (or its error estimate) is not finite:
/// [`IntegrateError::NonFinite`] at the first bad entry of `ynew` (index 0
/// if `ynew` itself is finite).
pub(crate) fn non_finite_trial(ynew: &DVector<f64>, t_new: f64, h: f64) -> IntegrateError {
    let index = first_non_finite(ynew.as_slice()).unwrap_or(0);
    IntegrateError::NonFinite {
        t: t_new,
        h,
        what: "state",
        index,
    }
}

/// Why an adaptive step was rejected, from its error norm.
pub(crate) fn rejection_reason(err: f64) -> &'static str {
    if err.is_finite() {
        "error test"
    } else {
        "non-finite trial state"
    }
}
