//! The common driver: one loop for every method — output at requested times by
//! dense output, events, monitors, the per-step callback and the checks.

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::DVector;

use crate::control::min_step;
use crate::error::{IntegrateError, first_non_finite};
use crate::hooks::{Control, Direction, EventKind, Hooks, StepInfo};
use crate::integrator::Integrator;
use crate::methods::{Dopri5, Esdirk, Esdirk5, Esdirk43, GeneralizedAlpha, Radau5, Rk4, Rosw34};
use crate::options::{Options, StepControl};
use crate::problem::{FirstOrderProblem, Problem, SecondOrderProblem};
use crate::solution::{EventRecord, Solution, Stats, Status};
use crate::stepper::Stepper;
use crate::system::{OdeSystem, SecondOrderSystem};

/// Integrates a first-order system `y' = f(t, y)` over `t_span = (t0, t1)`,
/// `t1 ≥ t0`.
///
/// * `sys`: the system, dim `n`.
/// * `integrator`: one without [`Integrator::needs_second_order`]
///   ([`Integrator::GeneralizedAlpha`] and [`Integrator::Esdirk`] need a
///   [`SecondOrderSystem`]: use [`integrate_second_order`]).
/// * `y0`: initial state, dim `n`.
/// * `opts`: tolerances, steps, output times ([`Options`]).
/// * `hooks`: outputs as they are produced, accepted steps, checks and
///   events ([`Hooks`]; [`NoHooks`](crate::NoHooks) for none).
///
/// Returns the [`Solution`] (outputs, events, final state, [`Stats`]) or an
/// [`IntegrateError`] with the time, step size and the failed check. No
/// non-finite value is ever written to the solution. Same inputs give the same
/// bits (no threads, no hashing, fixed operation order).
pub fn integrate<S: OdeSystem>(
    sys: &mut S,
    integrator: Integrator,
    t_span: (f64, f64),
    y0: &DVector<f64>,
    opts: &Options,
    hooks: &mut dyn Hooks<S>,
) -> Result<Solution, IntegrateError> {
    let n = sys.dim();
    if y0.len() != n {
        return Err(IntegrateError::InvalidInput {
            what: format!("y0 has dimension {} but the system has {n}", y0.len()),
        });
    }
    opts.validate(integrator)?;
    let mut p = FirstOrderProblem::new(sys);
    let run = Run {
        t_span,
        y0,
        opts,
        hooks,
    };
    match integrator {
        Integrator::Rk4 => drive(&mut p, &mut Rk4::new(n), run),
        Integrator::Dopri5 => drive(&mut p, &mut Dopri5::new(n), run),
        Integrator::Rosenbrock => drive(&mut p, &mut Rosw34::new(n), run),
        Integrator::Radau5 => drive(&mut p, &mut Radau5::new(n, None), run),
        Integrator::GeneralizedAlpha | Integrator::Esdirk | Integrator::Esdirk5 => {
            Err(IntegrateError::InvalidInput {
                what: format!("{integrator} needs a SecondOrderSystem: use integrate_second_order"),
            })
        }
    }
}

/// Integrates a second-order system `q̈ = a(t, q, q̇)` over
/// `t_span = (t0, t1)`, `t1 ≥ t0`, with any [`Integrator`]; the first-order methods run on `y = (q, q̇)` (their
/// linear solves use an `n×n` Schur complement, not the `2n×2n` matrix).
///
/// * `q0`, `qd0`: initial positions and velocities, dim `n` each.
///
/// Outputs, events and the states the hooks see are in first-order form
/// `y = (q, q̇)` (dim `2n`). Otherwise as [`integrate`].
pub fn integrate_second_order<S: SecondOrderSystem>(
    sys: &mut S,
    integrator: Integrator,
    t_span: (f64, f64),
    q0: &DVector<f64>,
    qd0: &DVector<f64>,
    opts: &Options,
    hooks: &mut dyn Hooks<S>,
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
    opts.validate(integrator)?;
    let mut y0 = DVector::zeros(2 * n);
    y0.rows_mut(0, n).copy_from(q0);
    y0.rows_mut(n, n).copy_from(qd0);
    let mut p = SecondOrderProblem::new(sys);
    let m = 2 * n;
    let run = Run {
        t_span,
        y0: &y0,
        opts,
        hooks,
    };
    match integrator {
        Integrator::Rk4 => drive(&mut p, &mut Rk4::new(m), run),
        Integrator::Dopri5 => drive(&mut p, &mut Dopri5::new(m), run),
        Integrator::Rosenbrock => drive(&mut p, &mut Rosw34::new(m), run),
        Integrator::Radau5 => drive(&mut p, &mut Radau5::new(m, Some(n)), run),
        Integrator::Esdirk => drive(&mut p, &mut Esdirk::<Esdirk43>::new(n), run),
        Integrator::Esdirk5 => drive(&mut p, &mut Esdirk5::new(n), run),
        Integrator::GeneralizedAlpha => {
            drive(&mut p, &mut GeneralizedAlpha::new(n, opts.rho_inf), run)
        }
    }
}

/// The checks that depend on the run: time span, output times within it,
/// finite initial state (the settings were checked by [`Options::validate`]).
fn validate(t0: f64, t1: f64, y0: &DVector<f64>, opts: &Options) -> Result<(), IntegrateError> {
    let bad = |what: String| Err(IntegrateError::InvalidInput { what });
    if !(t0.is_finite() && t1.is_finite()) || t1 < t0 {
        return bad(format!(
            "time span [{t0}, {t1}] must be finite with t1 >= t0"
        ));
    }
    if let Some(te) = &opts.t_eval
        && te.iter().any(|&t| !(t >= t0 && t <= t1))
    {
        return bad(format!("t_eval must lie in [{t0}, {t1}]"));
    }
    if let Some(b) = opts.breakpoints.iter().find(|b| !b.is_finite()) {
        return bad(format!("breakpoint {b} is not finite"));
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

/// Where the next step must end at the latest: `t1`, or the first of the
/// [`Options::breakpoints`] after `t` when the steps adapt.
///
/// A breakpoint closer to `t` or to `t1` than the smallest step allowed
/// there ([`min_step`]) is not a step end: it is the same time up to
/// rounding (`0.1 + 0.2` beside `0.3`), and landing on it would leave a
/// step of a few ulps that the underflow check must refuse.
fn step_end(opts: &Options, t: f64, t1: f64) -> f64 {
    match opts.step {
        StepControl::Adaptive { .. } => opts
            .breakpoints
            .iter()
            .copied()
            .filter(|&b| b - t > min_step(b, opts) && t1 - b > min_step(t1, opts))
            .fold(t1, f64::min),
        StepControl::Fixed(_) => t1,
    }
}

/// Where the next step must end at the latest when the method's steps end
/// on the output times ([`Options::steps_to_outputs`]): the first output
/// time after `t` that comes before `end` (the breakpoint or `t1`), with
/// the same rounding rule as [`step_end`]; `end` otherwise, and always for
/// fixed steps.
fn output_end(opts: &Options, te: &[f64], next_out: usize, t: f64, end: f64) -> f64 {
    if !matches!(opts.step, StepControl::Adaptive { .. }) {
        return end;
    }
    te[next_out.min(te.len())..]
        .iter()
        .copied()
        .find(|&o| o - t > min_step(o, opts))
        .filter(|&o| end - o > min_step(end, opts))
        .unwrap_or(end)
}

/// State value at `t` from the stepper (exact at the step end).
fn eval<P: Problem, St: Stepper<P>>(st: &St, t: f64, out: &mut DVector<f64>) {
    if t == st.t() {
        out.copy_from(st.y());
    } else {
        st.dense(t, out);
    }
}

/// What a run is asked to do: the span, the initial state (first-order
/// form), the options and the hooks.
struct Run<'r, S> {
    t_span: (f64, f64),
    y0: &'r DVector<f64>,
    opts: &'r Options,
    hooks: &'r mut dyn Hooks<S>,
}

/// The outputs of a run: stored (unless the hooks say not to) and handed to
/// the output hook.
struct Outputs {
    ts: Vec<f64>,
    ys: Vec<DVector<f64>>,
    keep: bool,
}

impl Outputs {
    /// Records the output `(t, y)`; returns `(stop, system_changed)` from the
    /// output hook.
    fn emit<P: Problem>(
        &mut self,
        hooks: &mut dyn Hooks<P::User>,
        p: &mut P,
        t: f64,
        y: &DVector<f64>,
    ) -> (bool, bool) {
        if self.keep {
            self.ts.push(t);
            self.ys.push(y.clone());
        }
        match hooks.output(t, y, p.user()) {
            Control::Stop => (true, false),
            // An output hook's change of forces is rare: dropped as a
            // change of the system.
            Control::SystemChanged | Control::ForcesChanged => (false, true),
            Control::Continue => (false, false),
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
    run: Run<'_, P::User>,
) -> Result<Solution, IntegrateError> {
    let Run {
        t_span: (t0, t1),
        y0,
        opts,
        hooks,
    } = run;
    validate(t0, t1, y0, opts)?;
    let n = y0.len();
    let mut stats = Stats::default();
    st.init(p, t0, y0, opts, &mut stats)?;

    let mut out = Outputs {
        ts: Vec::new(),
        ys: Vec::new(),
        keep: hooks.keep_outputs(),
    };
    let mut next_out = 0usize;
    let te: &[f64] = opts.t_eval.as_deref().unwrap_or(&[]);
    let mut early_stop = false;
    let mut changed_at_t0 = false;
    match &opts.t_eval {
        None => {
            (early_stop, changed_at_t0) = out.emit(hooks, p, t0, y0);
        }
        Some(te) => {
            while next_out < te.len() && te[next_out] == t0 {
                next_out += 1;
                let (stop, ch) = out.emit(hooks, p, t0, y0);
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
    // The event functions' kinds, read once for the run.
    let kinds: Vec<EventKind> = hooks.events().to_vec();
    let mut g_prev: Vec<f64> = (0..kinds.len()).map(|i| hooks.event(i, t0, y0)).collect();
    let mut events = Vec::new();
    let mut scratch = DVector::zeros(n);
    let mut status = Status::Completed;
    let mut t_final = t0;
    let mut y_final = y0.clone();
    if early_stop {
        status = Status::Stopped;
    }
    let mut yo = DVector::zeros(n);
    let mut after_breakpoint = false;
    let mut h_next = 0.0;

    while !early_stop && st.t() < t1 {
        if stats.steps >= opts.max_steps {
            return Err(IntegrateError::MaxStepsExceeded {
                t: st.t(),
                h: st.h_last(),
                max_steps: opts.max_steps,
            });
        }
        if after_breakpoint {
            st.restart_after_breakpoint(p, &mut stats)?;
        }
        let bp_end = step_end(opts, st.t(), t1);
        let end = if opts.steps_to_outputs {
            output_end(opts, te, next_out, st.t(), bp_end)
        } else {
            bp_end
        };
        let h_proposed = st.state().h_next;
        st.step(p, end, opts, &mut stats)?;
        // A step shortened to land on t1 (or on an output time) says
        // nothing against the longer step proposed before it: a
        // continuation, or the step after the output, may try that one.
        h_next = if (st.t() == t1 || st.t() == end) && st.h_last() < h_proposed {
            st.state().h_next.max(h_proposed)
        } else {
            st.state().h_next
        };
        if st.t() == end && end < bp_end {
            st.state_mut().h_next = h_next;
        }
        after_breakpoint = bp_end < t1 && st.t() == bp_end;
        if opts.project_state {
            st.project(p, &mut stats)?;
        }
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
        if let Err(e) = hooks.check(t, st.y()) {
            return Err(IntegrateError::BoundExceeded {
                t,
                h,
                what: e.what,
                value: e.value,
                bound: e.bound,
            });
        }

        // Events in (t_prev, t].
        let t_prev = st.t_prev();
        let mut t_stop = f64::INFINITY;
        let mut stop_index = None;
        let first_new_event = events.len();
        for (i, kind) in kinds.iter().enumerate() {
            let gb = hooks.event(i, t, st.y());
            let ga = g_prev[i];
            g_prev[i] = gb;
            if crossed(ga, gb, kind.direction) {
                let g = &mut |t, y: &DVector<f64>| hooks.event(i, t, y);
                let te = locate(st, g, (t_prev, ga), (t, gb), &mut scratch);
                let mut ye = DVector::zeros(n);
                eval(st, te, &mut ye);
                events.push(EventRecord {
                    index: i,
                    t: te,
                    y: ye,
                });
                if kind.terminal && te < t_stop {
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
        let mut forces_changed = false;
        let mut stopped_at = None;
        if opts.t_eval.is_some() {
            while next_out < te.len() && te[next_out] <= t_out_end {
                let to = te[next_out];
                eval(st, to, &mut yo);
                next_out += 1;
                let (stop, ch) = out.emit(hooks, p, to, &yo);
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
            if opts.t_eval.is_none() && out.emit(hooks, p, t_stop, &y_final).0 {
                status = Status::Stopped;
                break;
            }
            status = Status::Event { index };
            break;
        }
        t_final = t;
        y_final.copy_from(st.y());
        if opts.t_eval.is_none() {
            let (stop, ch) = out.emit(hooks, p, t, st.y());
            changed |= ch;
            if stop {
                status = Status::Stopped;
                break;
            }
        }

        let info = StepInfo {
            t,
            h,
            y: st.y(),
            stats: &stats,
            stages: st.stage_accelerations(),
        };
        match hooks.step(&info, p.user()) {
            Control::Continue => {}
            Control::Stop => {
                status = Status::Stopped;
                break;
            }
            Control::SystemChanged => changed = true,
            Control::ForcesChanged => forces_changed = true,
        }
        if changed {
            st.system_changed(p, &mut stats)?;
        } else if forces_changed {
            st.forces_changed(p, &mut stats)?;
        }
        if changed || forces_changed {
            for (i, g) in g_prev.iter_mut().enumerate() {
                *g = hooks.event(i, st.t(), st.y());
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
        h_next,
    })
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
}
