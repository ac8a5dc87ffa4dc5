//! The state every stepper keeps between steps, and the bookkeeping they share:
//! current and previous time, state and derivative, the last step size.

use nalgebra::DVector;

use crate::driver::{hermite, initial_step};
use crate::error::{IntegrateError, first_non_finite};
use crate::options::{Options, Stats};
use crate::system::{Problem, sys_err};

/// Time, state and derivative at the end (`t`, `y`, `f`) and the start
/// (`t_prev`, `y_prev`, `f_prev`) of the last accepted step of size `h`
/// (first-order form, `f = y'`).
pub(crate) struct StepState {
    pub(crate) t: f64,
    pub(crate) t_prev: f64,
    pub(crate) h: f64,
    pub(crate) y: DVector<f64>,
    pub(crate) f: DVector<f64>,
    pub(crate) y_prev: DVector<f64>,
    pub(crate) f_prev: DVector<f64>,
}

impl StepState {
    /// Zero state of dimension `n`.
    pub(crate) fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        Self {
            t: 0.0,
            t_prev: 0.0,
            h: 0.0,
            y: z.clone(),
            f: z.clone(),
            y_prev: z.clone(),
            f_prev: z,
        }
    }

    /// Starts at `(t0, y0)` (no step taken yet: `t_prev = t0`).
    pub(crate) fn start(&mut self, t0: f64, y0: &DVector<f64>) {
        self.t = t0;
        self.t_prev = t0;
        self.y.copy_from(y0);
    }

    /// Cubic Hermite dense output on `[t_prev, t]` from the step's end values
    /// and derivatives.
    pub(crate) fn hermite_dense(&self, t: f64, out: &mut DVector<f64>) {
        hermite(
            self.t_prev,
            &self.y_prev,
            &self.f_prev,
            self.t,
            &self.y,
            &self.f,
            t,
            out,
        );
    }

    /// Re-evaluates `f = f(t, y)` (one right-hand side) and checks it.
    pub(crate) fn refresh_derivative<P: Problem>(
        &mut self,
        p: &mut P,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        p.rhs(self.t, &self.y, &mut self.f)
            .map_err(sys_err(self.t, self.h, "rhs"))?;
        stats.rhs_evaluations += 1;
        check_finite(&self.f, self.t, self.h, "derivative")
    }

    /// `y_prev ← y`, `f_prev ← f` (by swapping buffers: `y` and `f` then
    /// hold stale values to be overwritten).
    pub(crate) fn save_prev(&mut self) {
        std::mem::swap(&mut self.y_prev, &mut self.y);
        std::mem::swap(&mut self.f_prev, &mut self.f);
    }

    /// Records an accepted step of size `h` ending at `t_new`.
    pub(crate) fn advance(&mut self, t_new: f64, h: f64, stats: &mut Stats) {
        self.t_prev = self.t;
        self.t = t_new;
        self.h = h;
        stats.steps += 1;
    }

    /// The first step of an adaptive method of order `order` from the start
    /// `(t, y, f)`: `dt` (at most `h_max`) if set, else [`initial_step`] (one
    /// right-hand side, in `scratch`).
    pub(crate) fn first_step<P: Problem>(
        &self,
        p: &mut P,
        order: i32,
        opts: &Options,
        stats: &mut Stats,
        scratch: (&mut DVector<f64>, &mut DVector<f64>),
    ) -> Result<f64, IntegrateError> {
        match opts.dt {
            Some(dt) => Ok(dt.min(opts.h_max)),
            None => initial_step(p, self.t, &self.y, &self.f, order, opts, stats, scratch),
        }
    }

    /// Accepts the step to `(t_new, ynew)`: `y_prev ← y`, `y ← ynew` (by
    /// swapping buffers; `ynew` then holds stale values), then
    /// [`advance`](Self::advance). `f`, `f_prev` are the caller's.
    pub(crate) fn accept(
        &mut self,
        ynew: &mut DVector<f64>,
        t_new: f64,
        h: f64,
        stats: &mut Stats,
    ) {
        std::mem::swap(&mut self.y_prev, &mut self.y);
        std::mem::swap(&mut self.y, ynew);
        self.advance(t_new, h, stats);
    }
}

/// An adaptive method run with `adaptive = false` needs a fixed step.
pub(crate) fn check_dt_if_fixed(opts: &Options) -> Result<(), IntegrateError> {
    if !opts.adaptive && opts.dt.is_none() {
        return Err(IntegrateError::InvalidInput {
            what: "a non-adaptive run needs Options::dt".into(),
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

/// A non-adaptive step whose trial `ynew` (or its error estimate) is not
/// finite: [`IntegrateError::NonFinite`] at the first bad entry of `ynew`
/// (index 0 if `ynew` itself is finite).
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
