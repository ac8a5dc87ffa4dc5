//! The common driver: one loop for every method — output at requested times by
//! dense output, events, monitors, the per-step callback and the checks.

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::DVector;

use crate::dopri5::Dopri5;
use crate::error::{IntegrateError, first_non_finite};
use crate::genalpha::GeneralizedAlpha;
use crate::options::{
    Control, Direction, EventRecord, Hooks, Method, Options, Solution, Stats, Status, StepInfo,
};
use crate::rk4::Rk4;
use crate::rosw::Rosw34;
use crate::state::StepState;
use crate::system::{FirstOrderProblem, OdeSystem, Problem, SecondOrderProblem, SecondOrderSystem};

/// One method's state between steps.
pub(crate) trait Stepper<P: Problem> {
    /// Sets the initial state (and evaluates what the first step needs).
    fn init(
        &mut self,
        p: &mut P,
        t0: f64,
        y0: &DVector<f64>,
        t1: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError>;
    /// Takes one accepted step, never beyond `t_end` (landing on it exactly
    /// when it is reached).
    fn step(
        &mut self,
        p: &mut P,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError>;
    /// The shared time/state/derivative bookkeeping.
    fn state(&self) -> &StepState;
    /// Current time.
    fn t(&self) -> f64 {
        self.state().t
    }
    /// Time at the start of the last step.
    fn t_prev(&self) -> f64 {
        self.state().t_prev
    }
    /// Current state.
    fn y(&self) -> &DVector<f64> {
        &self.state().y
    }
    /// Size of the last step.
    fn h_last(&self) -> f64 {
        self.state().h
    }
    /// Dense output at `t ∈ [t_prev, t]` into `out` (cubic Hermite unless
    /// the method has its own).
    fn dense(&self, t: f64, out: &mut DVector<f64>) {
        self.state().hermite_dense(t, out);
    }
    /// The user changed the system: drop cached derivatives/Jacobians.
    fn system_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError>;
}

/// Integrates a first-order system `y' = f(t, y)` from `t0` to `t1 ≥ t0`.
///
/// * `sys`: the system, dim `n`.
/// * `method`: [`Method::Rk4`], [`Method::Dopri5`] or [`Method::Rosw34`]
///   ([`Method::GeneralizedAlpha`] needs a [`SecondOrderSystem`]: use
///   [`integrate_second_order`]).
/// * `y0`: initial state, dim `n`.
/// * `opts`: tolerances, steps, output times ([`Options`]).
/// * `hooks`: per-step callback, events, monitors ([`Hooks::new()`] for none).
///
/// Returns the [`Solution`] (outputs, events, final state, [`Stats`]) or an
/// [`IntegrateError`] with the time, step size and the failed check. No
/// non-finite value is ever written to the solution. Same inputs give the same
/// bits (no threads, no hashing, fixed operation order).
pub fn integrate<S: OdeSystem>(
    sys: &mut S,
    method: Method,
    t0: f64,
    t1: f64,
    y0: &DVector<f64>,
    opts: &Options,
    hooks: Hooks<'_, S>,
) -> Result<Solution, IntegrateError> {
    let n = sys.dim();
    if y0.len() != n {
        return Err(IntegrateError::InvalidInput {
            what: format!("y0 has dimension {} but the system has {n}", y0.len()),
        });
    }
    let mut p = FirstOrderProblem::new(sys);
    match method {
        Method::Rk4 => drive(&mut p, &mut Rk4::new(n), t0, t1, y0, opts, hooks),
        Method::Dopri5 => drive(&mut p, &mut Dopri5::new(n), t0, t1, y0, opts, hooks),
        Method::Rosw34 => drive(&mut p, &mut Rosw34::new(n), t0, t1, y0, opts, hooks),
        Method::GeneralizedAlpha { .. } => Err(IntegrateError::InvalidInput {
            what: "generalized-α needs a SecondOrderSystem: use integrate_second_order".into(),
        }),
    }
}

/// Integrates a second-order system `q̈ = a(t, q, q̇)` from `t0` to `t1 ≥ t0`
/// with any [`Method`]; the first-order methods run on `y = (q, q̇)` (their
/// linear solves use an `n×n` Schur complement, not the `2n×2n` matrix).
///
/// * `q0`, `qd0`: initial positions and velocities, dim `n` each.
///
/// Outputs, events, monitors and callback states are in first-order form
/// `y = (q, q̇)` (dim `2n`). Otherwise as [`integrate`].
#[allow(clippy::too_many_arguments)]
pub fn integrate_second_order<S: SecondOrderSystem>(
    sys: &mut S,
    method: Method,
    t0: f64,
    t1: f64,
    q0: &DVector<f64>,
    qd0: &DVector<f64>,
    opts: &Options,
    hooks: Hooks<'_, S>,
) -> Result<Solution, IntegrateError> {
    let n = sys.dim();
    if q0.len() != n || qd0.len() != n {
        return Err(IntegrateError::InvalidInput {
            what: format!(
                "q0, qd0 have dimensions {}, {} but the system has {n}",
                q0.len(),
                qd0.len()
            ),
        });
    }
    let mut y0 = DVector::zeros(2 * n);
    y0.rows_mut(0, n).copy_from(q0);
    y0.rows_mut(n, n).copy_from(qd0);
    let mut p = SecondOrderProblem::new(sys);
    let m = 2 * n;
    match method {
        Method::Rk4 => drive(&mut p, &mut Rk4::new(m), t0, t1, &y0, opts, hooks),
        Method::Dopri5 => drive(&mut p, &mut Dopri5::new(m), t0, t1, &y0, opts, hooks),
        Method::Rosw34 => drive(&mut p, &mut Rosw34::new(m), t0, t1, &y0, opts, hooks),
        Method::GeneralizedAlpha { rho_inf } => {
            if !(0.0..=1.0).contains(&rho_inf) {
                return Err(IntegrateError::InvalidInput {
                    what: format!("rho_inf = {rho_inf} is not in [0, 1]"),
                });
            }
            drive(
                &mut p,
                &mut GeneralizedAlpha::new(n, rho_inf),
                t0,
                t1,
                &y0,
                opts,
                hooks,
            )
        }
    }
}

fn validate(t0: f64, t1: f64, y0: &DVector<f64>, opts: &Options) -> Result<(), IntegrateError> {
    let bad = |what: String| Err(IntegrateError::InvalidInput { what });
    if !(t0.is_finite() && t1.is_finite()) || t1 < t0 {
        return bad(format!(
            "time span [{t0}, {t1}] must be finite with t1 >= t0"
        ));
    }
    if !(opts.rtol >= 0.0 && opts.atol >= 0.0 && opts.rtol + opts.atol > 0.0) {
        return bad(format!(
            "tolerances rtol = {}, atol = {} must be >= 0 and not both 0",
            opts.rtol, opts.atol
        ));
    }
    if let Some(dt) = opts.dt
        && !(dt > 0.0 && dt.is_finite())
    {
        return bad(format!("dt = {dt} must be positive and finite"));
    }
    if !(opts.h_max > 0.0) || !(opts.h_min >= 0.0) || opts.h_min > opts.h_max {
        return bad(format!(
            "need 0 <= h_min ({}) <= h_max ({}), h_max > 0",
            opts.h_min, opts.h_max
        ));
    }
    if let Some(te) = &opts.t_eval {
        if te.windows(2).any(|w| !(w[0] <= w[1])) {
            return bad("t_eval must be sorted".into());
        }
        if te.iter().any(|&t| !(t >= t0 && t <= t1)) {
            return bad(format!("t_eval must lie in [{t0}, {t1}]"));
        }
    }
    if let Some(i) = first_non_finite(y0.as_slice()) {
        return Err(IntegrateError::NonFinite {
            t: t0,
            h: 0.0,
            what: "initial state",
            index: i,
        });
    }
    Ok(())
}

/// State value at `t` from the stepper (exact at the step end).
fn eval<P: Problem, St: Stepper<P>>(st: &St, t: f64, out: &mut DVector<f64>) {
    if t == st.t() {
        out.copy_from(st.y());
    } else {
        st.dense(t, out);
    }
}

/// The outputs of a run: stored (unless the hooks say not to) and handed to
/// the output callback.
struct Outputs {
    ts: Vec<f64>,
    ys: Vec<DVector<f64>>,
    keep: bool,
}

impl Outputs {
    /// Records the output `(t, y)`; returns `(stop, system_changed)` from the
    /// output callback.
    fn emit<P: Problem>(
        &mut self,
        hooks: &mut Hooks<'_, P::User>,
        p: &mut P,
        t: f64,
        y: &DVector<f64>,
    ) -> (bool, bool) {
        if self.keep {
            self.ts.push(t);
            self.ys.push(y.clone());
        }
        match hooks.on_output.as_mut().map(|f| f(t, y, p.user())) {
            Some(Control::Stop) => (true, false),
            Some(Control::SystemChanged) => (false, true),
            _ => (false, false),
        }
    }
}

fn crossed(ga: f64, gb: f64, dir: Direction) -> bool {
    // A crossing starts from a nonzero value; leaving an exact zero is not one.
    let rising = ga < 0.0 && gb >= 0.0;
    let falling = ga > 0.0 && gb <= 0.0;
    match dir {
        Direction::Rising => rising,
        Direction::Falling => falling,
        Direction::Either => rising || falling,
    }
}

/// Illinois (modified regula falsi) on the dense output: returns a time with
/// `g` on the far side of the crossing, within a few ulps of the root.
fn locate<P: Problem, St: Stepper<P>>(
    st: &St,
    g: &mut dyn FnMut(f64, &DVector<f64>) -> f64,
    (mut ta, mut ga): (f64, f64),
    (mut tb, mut gb): (f64, f64),
    scratch: &mut DVector<f64>,
) -> f64 {
    if gb == 0.0 {
        return tb;
    }
    let mut side = 0i32;
    for _ in 0..200 {
        let tol = 4.0 * f64::EPSILON * ta.abs().max(tb.abs()).max(1e-300);
        if tb - ta <= tol {
            break;
        }
        let mut tm = (ta * gb - tb * ga) / (gb - ga);
        if !(tm > ta && tm < tb) {
            tm = 0.5 * (ta + tb);
        }
        eval(st, tm, scratch);
        let gm = g(tm, scratch);
        if gm == 0.0 {
            return tm;
        }
        if (gm > 0.0) == (gb > 0.0) {
            tb = tm;
            gb = gm;
            if side == 1 {
                ga *= 0.5;
            }
            side = 1;
        } else {
            ta = tm;
            ga = gm;
            if side == -1 {
                gb *= 0.5;
            }
            side = -1;
        }
    }
    tb
}

fn drive<P: Problem, St: Stepper<P>>(
    p: &mut P,
    st: &mut St,
    t0: f64,
    t1: f64,
    y0: &DVector<f64>,
    opts: &Options,
    mut hooks: Hooks<'_, P::User>,
) -> Result<Solution, IntegrateError> {
    validate(t0, t1, y0, opts)?;
    let n = y0.len();
    let mut stats = Stats::default();
    st.init(p, t0, y0, t1, opts, &mut stats)?;

    let mut out = Outputs {
        ts: Vec::new(),
        ys: Vec::new(),
        keep: hooks.keep_outputs,
    };
    let mut next_out = 0usize;
    let te: &[f64] = opts.t_eval.as_deref().unwrap_or(&[]);
    let mut early_stop = false;
    let mut changed_at_t0 = false;
    match &opts.t_eval {
        None => {
            (early_stop, changed_at_t0) = out.emit(&mut hooks, p, t0, y0);
        }
        Some(te) => {
            while next_out < te.len() && te[next_out] == t0 {
                next_out += 1;
                let (stop, ch) = out.emit(&mut hooks, p, t0, y0);
                changed_at_t0 |= ch;
                if stop {
                    early_stop = true;
                    break;
                }
            }
        }
    }
    if changed_at_t0 && !early_stop {
        st.system_changed(p, &mut stats)?;
    }
    let mut g_prev: Vec<f64> = hooks.events.iter_mut().map(|e| (e.g)(t0, y0)).collect();
    let mut events = Vec::new();
    let mut scratch = DVector::zeros(n);
    let mut status = Status::Completed;
    let mut t_final = t0;
    let mut y_final = y0.clone();
    if early_stop {
        status = Status::Stopped;
    }
    let mut yo = DVector::zeros(n);

    while !early_stop && st.t() < t1 {
        if stats.steps >= opts.max_steps {
            return Err(IntegrateError::MaxStepsExceeded {
                t: st.t(),
                h: st.h_last(),
                max_steps: opts.max_steps,
            });
        }
        st.step(p, t1, opts, &mut stats)?;
        let (t, h) = (st.t(), st.h_last());
        if let Some(index) = first_non_finite(st.y().as_slice()) {
            return Err(IntegrateError::NonFinite {
                t,
                h,
                what: "state",
                index,
            });
        }
        let norm = st.y().amax();
        if norm > opts.max_norm {
            return Err(IntegrateError::BoundExceeded {
                t,
                h,
                what: "state max-norm",
                value: norm,
                bound: opts.max_norm,
            });
        }
        for m in hooks.monitors.iter_mut() {
            let v = (m.f)(t, st.y());
            if !(v.abs() <= m.bound) {
                return Err(IntegrateError::BoundExceeded {
                    t,
                    h,
                    what: m.name,
                    value: v,
                    bound: m.bound,
                });
            }
        }

        // Events in (t_prev, t].
        let t_prev = st.t_prev();
        let mut t_stop = f64::INFINITY;
        let mut stop_index = None;
        let first_new_event = events.len();
        for (i, e) in hooks.events.iter_mut().enumerate() {
            let gb = (e.g)(t, st.y());
            let ga = g_prev[i];
            g_prev[i] = gb;
            if crossed(ga, gb, e.direction) {
                let te = locate(st, &mut *e.g, (t_prev, ga), (t, gb), &mut scratch);
                let mut ye = DVector::zeros(n);
                eval(st, te, &mut ye);
                events.push(EventRecord {
                    index: i,
                    t: te,
                    y: ye,
                });
                if e.terminal && te < t_stop {
                    t_stop = te;
                    stop_index = Some(i);
                }
            }
        }
        if stop_index.is_some() {
            events.retain(|r: &EventRecord| r.t <= t_stop);
        }
        events[first_new_event..].sort_by(|a, b| a.t.total_cmp(&b.t).then(a.index.cmp(&b.index)));

        // Output.
        let t_out_end = t.min(t_stop);
        let mut changed = false;
        let mut stopped_at = None;
        if opts.t_eval.is_some() {
            while next_out < te.len() && te[next_out] <= t_out_end {
                let to = te[next_out];
                eval(st, to, &mut yo);
                next_out += 1;
                let (stop, ch) = out.emit(&mut hooks, p, to, &yo);
                changed |= ch;
                if stop {
                    stopped_at = Some(to);
                    break;
                }
            }
        }
        if let Some(to) = stopped_at {
            t_final = to;
            y_final.copy_from(&yo);
            events.retain(|r: &EventRecord| r.t <= to);
            status = Status::Stopped;
            break;
        }
        if let Some(index) = stop_index {
            eval(st, t_stop, &mut y_final);
            t_final = t_stop;
            if opts.t_eval.is_none() && out.emit(&mut hooks, p, t_stop, &y_final).0 {
                status = Status::Stopped;
                break;
            }
            status = Status::Event { index };
            break;
        }
        t_final = t;
        y_final.copy_from(st.y());
        if opts.t_eval.is_none() {
            let (stop, ch) = out.emit(&mut hooks, p, t, st.y());
            changed |= ch;
            if stop {
                status = Status::Stopped;
                break;
            }
        }

        if let Some(cb) = hooks.on_step.as_mut() {
            let info = StepInfo {
                t,
                h,
                y: st.y(),
                stats: &stats,
            };
            match cb(&info, p.user()) {
                Control::Continue => {}
                Control::Stop => {
                    status = Status::Stopped;
                    break;
                }
                Control::SystemChanged => changed = true,
            }
        }
        if changed {
            st.system_changed(p, &mut stats)?;
            let (t, y) = (st.t(), st.y().clone());
            for (i, e) in hooks.events.iter_mut().enumerate() {
                g_prev[i] = (e.g)(t, &y);
            }
        }
    }

    Ok(Solution {
        t: out.ts,
        y: out.ys,
        events,
        t_final,
        y_final,
        status,
        stats,
    })
}

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

/// Cubic Hermite interpolation on `[ta, tb]` from values and derivatives
/// (Hairer–Nørsett–Wanner, *ODEs I*, eq. II.6.7).
#[allow(clippy::too_many_arguments)]
pub(crate) fn hermite(
    ta: f64,
    ya: &DVector<f64>,
    fa: &DVector<f64>,
    tb: f64,
    yb: &DVector<f64>,
    fb: &DVector<f64>,
    t: f64,
    out: &mut DVector<f64>,
) {
    let h = tb - ta;
    let th = (t - ta) / h;
    let th1 = th - 1.0;
    for i in 0..out.len() {
        let dy = yb[i] - ya[i];
        out[i] = (1.0 - th) * ya[i]
            + th * yb[i]
            + th * th1 * ((1.0 - 2.0 * th) * dy + th1 * h * fa[i] + th * h * fb[i]);
    }
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
    p.rhs(t0 + h0, y1, f1)
        .map_err(crate::system::sys_err(t0, h0, "rhs"))?;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_rules() {
        assert!(crossed(-1.0, 1.0, Direction::Rising));
        assert!(!crossed(-1.0, 1.0, Direction::Falling));
        assert!(crossed(1.0, -1.0, Direction::Either));
        assert!(crossed(-1.0, 0.0, Direction::Rising));
        // Leaving a zero is not a new crossing.
        assert!(!crossed(0.0, 1.0, Direction::Either));
        assert!(!crossed(1.0, 2.0, Direction::Either));
    }

    #[test]
    fn hermite_reproduces_cubics() {
        // y = t³ − 2t, y' = 3t² − 2 on [0.5, 1.5].
        let y = |t: f64| DVector::from_element(1, t * t * t - 2.0 * t);
        let f = |t: f64| DVector::from_element(1, 3.0 * t * t - 2.0);
        let mut out = DVector::zeros(1);
        hermite(0.5, &y(0.5), &f(0.5), 1.5, &y(1.5), &f(1.5), 0.8, &mut out);
        assert!((out[0] - y(0.8)[0]).abs() < 1e-14);
    }
}
