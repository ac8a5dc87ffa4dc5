//! Step control shared by every method, one floor below the steppers: the
//! error norm, landing on the end time, the starting step, the underflow
//! check and the checks of trial states.

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::DVector;

use crate::error::{IntegrateError, first_non_finite};
use crate::options::Options;
use crate::problem::{Problem, sys_err};
use crate::solution::Stats;

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

/// Starting step of an adaptive method of order `order` (Hairer–Nørsett–
/// Wanner, *ODEs I*, §II.4, "Starting step size"); one right-hand side.
#[allow(clippy::too_many_arguments)]
pub(crate) fn initial_step<P: Problem>(
    p: &mut P,
    t0: f64,
    y0: &DVector<f64>,
    f0: &DVector<f64>,
    order: i32,
    opts: &Options,
    stats: &mut Stats,
    scratch: (&mut DVector<f64>, &mut DVector<f64>),
) -> Result<f64, IntegrateError> {
    let (y1, f1) = scratch;
    let zero = y0;
    let d0 = wrms(y0, zero, zero, opts);
    let d1 = wrms(f0, zero, zero, opts);
    let mut h0 = if d0 < 1e-10 || d1 < 1e-10 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(opts.h_max);
    y1.copy_from(y0);
    y1.axpy(h0, f0, 1.0);
    p.rhs(t0 + h0, y1, f1).map_err(sys_err(t0, h0, "rhs"))?;
    stats.rhs_evaluations += 1;
    f1.axpy(-1.0, f0, 1.0);
    let d2 = wrms(f1, zero, zero, opts) / h0;
    let dm = d1.max(d2);
    let h1 = if !(dm > 1e-15) {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / dm).powf(1.0 / (order as f64 + 1.0))
    };
    let h = (100.0 * h0).min(h1).min(opts.h_max);
    Ok(if h.is_finite() { h } else { 1e-6 })
}

/// Checks the step size against `h_min` and the resolution of `t`.
pub(crate) fn check_underflow(
    t: f64,
    h: f64,
    opts: &Options,
    reason: &'static str,
) -> Result<(), IntegrateError> {
    let floor = opts.h_min.max(16.0 * f64::EPSILON * t.abs());
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
