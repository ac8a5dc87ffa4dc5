//! ESDIRK5(4)7L\[2\]SA for second-order systems `q̈ = a(t, q, q̇)`: the
//! tableau of Kennedy & Carpenter's ESDIRK5(4)7L\[2\]SA₁ (C. A. Kennedy,
//! M. H. Carpenter, "Diagonally implicit Runge–Kutta methods for ordinary
//! differential equations. A review", NASA/TM-2016-219173, Table 25): seven
//! stages, the first explicit, six implicit with the same diagonal
//! `γ = 0.184`, order 5 with an embedded order-4 solution, L-stable, stiffly
//! accurate (`b` is the last row of `A`), stage order 2. The order
//! conditions (all 17 trees to order 5 for `b`, the 8 to order 4 for `b̂`),
//! the row sums, the stage order and the stability function are checked by
//! this module's tests, not taken from the transcription.
//!
//! Everything else is [`super::Esdirk`]'s (ESDIRK4(3)6L\[2\]SA): each implicit
//! stage `Vᵢ = v̂ᵢ + hγ Aᵢ`, `Qᵢ = q̂ᵢ + hγ Vᵢ`, `Aᵢ = a(tₙ + cᵢh, Qᵢ, Vᵢ)` is
//! one equation in its acceleration, solved by simplified Newton on the
//! force residual with the structured O(N) matrix `M + h²γ²K + hγD`
//! ([`SecondOrderSystem::factor_shifted_mass`]) and the exact dense Jacobian
//! as fallback; the embedded estimate `h Σ (bᵢ − b̂ᵢ)(Vᵢ, Aᵢ)` filtered by
//! `(I − hγJ)⁻¹` and measured as positions; quintic Hermite dense output
//! (`O(h⁶)` in `q`, `O(h⁵)` in `q̇`: not below the method's order). What
//! differs: the estimate is `O(h⁵)`, so the controller's exponent is `1/5`
//! (Gustafsson's predictive form as before), and a step costs six implicit
//! stages instead of five. Why a second ESDIRK rather than a changed
//! tableau: the discrete adjoint (`crate::adjoint`) is built on the
//! ESDIRK4(3)6L\[2\]SA tableau; this method has none, and the gradient API
//! refuses it.

// The coefficients are transcribed with all the digits published.
#![allow(clippy::excessive_precision)]
// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::DVector;

use super::esdirk::stage_values;
use crate::control::{check_finite, check_underflow, clip_step};
use crate::error::{IntegrateError, first_non_finite};
use crate::options::{Iteration, Options};
use crate::problem::{JacKind, Problem, SecondOrderProblem, sys_err};
use crate::solution::Stats;
use crate::state::StepState;
use crate::stepper::Stepper;
use crate::system::SecondOrderSystem;

const S: usize = 7;
/// The diagonal of the implicit stages.
const GAMMA: f64 = 0.184;
/// Nodes `cᵢ = Σⱼ aᵢⱼ` (`c₆ = 1.04` lies beyond the step: the stage is
/// evaluated there all the same, as the method is defined).
const C: [f64; S] = [
    0.0,
    0.368,
    0.10778470452335051,
    0.52,
    0.6531582768582439,
    1.04,
    1.0,
];
/// `aᵢⱼ` (lower triangular, `γ` on the diagonal from the second stage).
const A: [[f64; S]; S] = [
    [0.0; S],
    [GAMMA, GAMMA, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        -0.038107647738324729,
        -0.038107647738324743,
        GAMMA,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        0.021677664958778542,
        0.0216776649587785,
        0.29264467008244299,
        GAMMA,
        0.0,
        0.0,
        0.0,
    ],
    [
        -0.85104626617351575,
        -0.85104626617351564,
        1.7533038157326979,
        0.41794699347257747,
        GAMMA,
        0.0,
        0.0,
    ],
    [
        -5.0356161217492197,
        -5.0356161217492197,
        8.9713052937951279,
        0.31505839963851934,
        1.6408685500647917,
        GAMMA,
        0.0,
    ],
    [
        -0.075998114543861517,
        -0.075998114543861378,
        0.42427748359919076,
        0.27546898147535387,
        0.32051077889797169,
        -0.052261014884793552,
        GAMMA,
    ],
];
/// Weights of the embedded order-4 solution (`b` is the last row of `A`).
const B_HAT: [f64; S] = [
    -0.108049345454303,
    -0.10804934545430295,
    0.48372757888653789,
    0.23595105756244605,
    0.37538336433425512,
    -0.032306662513724778,
    0.15334335263909166,
];
/// The step-size exponent: `1/(q + 1)` for the order-`q = 4` estimate.
const EXPONENT: f64 = 0.2;

/// Stage `i`'s explicit part `(Q̂ᵢ, V̂ᵢ) = (q, v) + h Σ_{j<i} a_ij (V_j, A_j)`.
#[allow(clippy::too_many_arguments)]
fn explicit_part(
    i: usize,
    h: f64,
    q: &DVector<f64>,
    v: &DVector<f64>,
    vs: &[DVector<f64>],
    accs: &[DVector<f64>],
    qhat: &mut DVector<f64>,
    vhat: &mut DVector<f64>,
) {
    qhat.copy_from(q);
    vhat.copy_from(v);
    for (j, &a) in A[i][..i].iter().enumerate() {
        if a != 0.0 {
            qhat.axpy(h * a, &vs[j], 1.0);
            vhat.axpy(h * a, &accs[j], 1.0);
        }
    }
}

// The step-size controller (RADAU5's defaults: safety factor, bounds of
// `h_new/h`, the band within which `h` is kept) and the Newton constants
// are ESDIRK4(3)'s.
const SAFETY: f64 = 0.9;
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 8.0;
const KEEP_MIN: f64 = 1.0;
const KEEP_MAX: f64 = 1.2;
/// Newton: a contraction rate above this is divergence.
const THETA_DIVERGED: f64 = 0.99;
/// Keep the Jacobian (and factorization) for the next step when the
/// largest contraction rate of this step was at most this; otherwise refresh
/// it (RADAU5's `THET`, raised as it recommends when Jacobians are costly:
/// the exact one costs many evaluations, the structured one a
/// factorization).
const THETA_KEEP_EXACT: f64 = 0.1;
const THETA_KEEP_CHEAP: f64 = 0.05;
/// Accepted steps on the exact Jacobian after a fallback before the cheap
/// (structured or mass-form) matrix is tried again.
const EXACT_STEPS: usize = 10;

/// Which iteration matrix the Newton iteration uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Matrix {
    /// The system's cheapest: structured `M + aK + bD`, else the dense mass
    /// form, else the dense exact Jacobian.
    Cheap,
    /// The dense exact Jacobian.
    Exact,
}

/// Why the Newton iteration of a step failed.
type NewtonFailure = &'static str;

/// ESDIRK5(4)7L\[2\]SA state and buffers (allocated once).
pub(crate) struct Esdirk5 {
    n: usize,
    /// First-order views `y = (q, q̇)`, `f = (q̇, q̈)` for the driver and the
    /// dense output.
    s: StepState,
    q: DVector<f64>,
    v: DVector<f64>,
    acc: DVector<f64>,
    /// Stage values; stage 0 is the step start.
    qs: [DVector<f64>; S],
    vs: [DVector<f64>; S],
    accs: [DVector<f64>; S],
    qhat: DVector<f64>,
    vhat: DVector<f64>,
    g: DVector<f64>,
    /// The error estimate.
    eq: DVector<f64>,
    ev: DVector<f64>,
    /// Last accepted step and error (predictive controller).
    h_acc: f64,
    err_acc: f64,
    accepted: usize,
    /// Newton: the contraction estimate carried between stages and steps
    /// (RADAU5's `FACCON`), and the largest rate of the current step.
    eta: f64,
    theta_max: f64,
    matrix: Matrix,
    exact_left: usize,
    /// A Jacobian is held, and whether it was taken at the current step's
    /// start.
    jac_valid: bool,
    jac_fresh: bool,
    /// The step size of the current factorization (NaN: none).
    factored_h: f64,
}

impl Esdirk5 {
    pub(crate) fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        Self {
            n,
            s: StepState::new(2 * n),
            q: z.clone(),
            v: z.clone(),
            acc: z.clone(),
            qs: std::array::from_fn(|_| z.clone()),
            vs: std::array::from_fn(|_| z.clone()),
            accs: std::array::from_fn(|_| z.clone()),
            qhat: z.clone(),
            vhat: z.clone(),
            g: z.clone(),
            eq: z.clone(),
            ev: z,
            h_acc: 0.0,
            err_acc: 1e-2,
            accepted: 0,
            eta: 1.0,
            theta_max: 0.0,
            matrix: Matrix::Cheap,
            exact_left: 0,
            jac_valid: false,
            jac_fresh: false,
            factored_h: f64::NAN,
        }
    }

    fn set_first_order(&mut self) {
        let n = self.n;
        self.s.y.rows_mut(0, n).copy_from(&self.q);
        self.s.y.rows_mut(n, n).copy_from(&self.v);
        self.s.f.rows_mut(0, n).copy_from(&self.v);
        self.s.f.rows_mut(n, n).copy_from(&self.acc);
    }

    /// Evaluates the Jacobian of the current mode at the step start.
    fn update_jacobian<Sys: SecondOrderSystem>(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        h: f64,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let t = self.s.t;
        let bad = match self.matrix {
            Matrix::Cheap => p.update_jacobians_qv(t, &self.q, &self.v, true),
            Matrix::Exact => p.update_full_jacobians(t, &self.q, &self.v),
        }
        .map_err(sys_err(t, h, "jacobian"))?;
        if p.kind() != JacKind::Structured {
            stats.jacobian_evaluations += 1;
        }
        if let Some(index) = bad {
            return Err(IntegrateError::NonFinite {
                t,
                h,
                what: "Jacobian",
                index,
            });
        }
        self.jac_valid = true;
        self.jac_fresh = true;
        self.factored_h = f64::NAN;
        Ok(())
    }

    /// Solves the six implicit stages of a step of size `h` to `t_new`.
    /// `Ok(Ok(()))`: converged (stages in `qs`, `vs`, `accs`);
    /// `Ok(Err(why))`: the Newton iteration failed.
    fn solve_stages<Sys: SecondOrderSystem>(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        h: f64,
        t_new: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<Result<(), NewtonFailure>, IntegrateError> {
        let n = self.n;
        let t = self.s.t;
        let (hg, hg2) = (h * GAMMA, h * h * GAMMA * GAMMA);
        let (tol, max_iter) = match opts.iteration {
            Iteration::Newton { tol, max_iter } => (tol, max_iter.max(1)),
            // Options::validate keeps this generalized-α's.
            Iteration::LinearlyImplicit => (f64::INFINITY, 1),
        };
        self.qs[0].copy_from(&self.q);
        self.vs[0].copy_from(&self.v);
        self.accs[0].copy_from(&self.acc);
        self.eta = self.eta.max(f64::EPSILON).powf(0.8);
        self.theta_max = 0.0;
        for i in 1..S {
            let ti = if i == S - 1 { t_new } else { t + C[i] * h };
            // Explicit parts.
            explicit_part(
                i,
                h,
                &self.q,
                &self.v,
                &self.vs,
                &self.accs,
                &mut self.qhat,
                &mut self.vhat,
            );
            // Predictor: the line through the two previous stages'
            // accelerations `(cⱼ, Aⱼ)`, at `cᵢ` (the second stage, with only
            // the step start before it, starts from that), as ESDIRK4(3)'s
            // (why: there). The nodes are not monotone here (`c₃ < c₂`,
            // `c₆ > c₇`); the line still interpolates or extrapolates by
            // less than a step.
            let (done, rest) = self.accs.split_at_mut(i);
            let x = &mut rest[0];
            x.copy_from(&done[i - 1]);
            if i >= 2 {
                let w = (C[i] - C[i - 1]) / (C[i - 1] - C[i - 2]);
                x.axpy(w, &done[i - 1], 1.0);
                x.axpy(-w, &done[i - 2], 1.0);
            }
            let mut dyno_prev = f64::NAN;
            let mut converged = false;
            for k in 1..=max_iter {
                // Stage values from the current acceleration.
                stage_values(
                    hg,
                    &self.qhat,
                    &self.vhat,
                    x,
                    &mut self.vs[i],
                    &mut self.qs[i],
                );
                p.newmark_correction(ti, &self.qs[i], &self.vs[i], x, &mut self.g)
                    .map_err(sys_err(t, h, "accel"))?;
                stats.rhs_evaluations += 1;
                stats.newton_iterations += 1;
                stats.lu_solves += 1;
                *x += &self.g;
                // The change of (Qᵢ, Vᵢ), weighted as the state.
                let mut s = 0.0;
                for r in 0..n {
                    let wq = opts.atol + opts.rtol * self.q[r].abs();
                    let wv = opts.atol + opts.rtol * self.v[r].abs();
                    let dq = hg2 * self.g[r] / wq;
                    let dv = hg * self.g[r] / wv;
                    s += dq * dq + dv * dv;
                }
                let dyno = if n == 0 {
                    0.0
                } else {
                    (s / (2 * n) as f64).sqrt()
                };
                if !dyno.is_finite() || first_non_finite(x.as_slice()).is_some() {
                    return Ok(Err("non-finite iterate"));
                }
                if k >= 2 {
                    let theta = dyno / dyno_prev;
                    self.theta_max = self.theta_max.max(theta);
                    if !(theta < THETA_DIVERGED) {
                        return Ok(Err("diverged"));
                    }
                    self.eta = theta / (1.0 - theta);
                    // Predicted not to converge within the iterations left
                    // (RADAU5's test).
                    let left = (max_iter - k) as i32;
                    if self.eta * dyno * theta.powi(left) > tol {
                        return Ok(Err("too slow"));
                    }
                }
                if self.eta * dyno <= tol || dyno == 0.0 {
                    converged = true;
                    break;
                }
                dyno_prev = dyno.max(f64::MIN_POSITIVE);
            }
            if !converged {
                return Ok(Err("max iterations"));
            }
            // The stage values of the converged acceleration.
            let x = &self.accs[i];
            stage_values(
                hg,
                &self.qhat,
                &self.vhat,
                x,
                &mut self.vs[i],
                &mut self.qs[i],
            );
        }
        Ok(Ok(()))
    }

    /// Weighted RMS of the embedded error estimate `h Σ (bᵢ − b̂ᵢ)(Vᵢ, Aᵢ)`,
    /// filtered by `(I − hγJ)⁻¹` (∞ if not finite).
    fn error_norm<Sys: SecondOrderSystem>(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        h: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<f64, IntegrateError> {
        let n = self.n;
        if n == 0 {
            return Ok(0.0);
        }
        for r in 0..n {
            let mut eq = 0.0;
            let mut ev = 0.0;
            for i in 0..S {
                let d = A[S - 1][i] - B_HAT[i];
                eq += d * self.vs[i][r];
                ev += d * self.accs[i][r];
            }
            self.eq[r] = h * eq;
            self.ev[r] = h * ev;
        }
        if first_non_finite(self.eq.as_slice()).is_some()
            || first_non_finite(self.ev.as_slice()).is_some()
        {
            return Ok(f64::INFINITY);
        }
        {
            let t = self.s.t;
            p.filter_error(t, h * GAMMA, &mut self.eq, &mut self.ev)
                .map_err(sys_err(t, h, "error filter"))?;
            stats.lu_solves += 1;
        }
        let mut s = 0.0;
        let qn = &self.qs[S - 1];
        for r in 0..n {
            let wq = opts.atol + opts.rtol * self.q[r].abs().max(qn[r].abs());
            // The velocity error as the position error it makes over the step.
            let (a, b) = (self.eq[r] / wq, h * self.ev[r] / wq);
            s += a * a + b * b;
        }
        let e = (s / (2 * n) as f64).sqrt();
        Ok(if e.is_finite() { e } else { f64::INFINITY })
    }

    fn accept(&mut self, t_new: f64, h: f64, stats: &mut Stats) {
        self.s.save_prev();
        std::mem::swap(&mut self.q, &mut self.qs[S - 1]);
        std::mem::swap(&mut self.v, &mut self.vs[S - 1]);
        std::mem::swap(&mut self.acc, &mut self.accs[S - 1]);
        self.set_first_order();
        self.s.advance(t_new, h, stats);
        self.accepted += 1;
    }
}

impl<Sys: SecondOrderSystem> Stepper<SecondOrderProblem<'_, Sys>> for Esdirk5 {
    const START_ORDER: i32 = 4;

    fn restart(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        _opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let n = self.n;
        self.q.copy_from(&self.s.y.rows(0, n));
        self.v.copy_from(&self.s.y.rows(n, n));
        self.system_changed(p, stats)?;
        self.matrix = Matrix::Cheap;
        self.accepted = 0;
        Ok(())
    }

    fn step(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let fixed = opts.fixed_dt();
        let mut h = self.s.h_next.min(opts.h_max);
        let mut rejected_before = false;
        let mut reason = "step size";
        loop {
            let t = self.s.t;
            let (hh, last) = clip_step(t, h, t_end);
            h = hh;
            check_underflow(t, h, opts, reason)?;
            if !self.jac_valid {
                self.update_jacobian(p, h, stats)?;
            }
            if h != self.factored_h {
                stats.factorizations += 1;
                let ok = p
                    .factor_newmark(h * h * GAMMA * GAMMA, h * GAMMA)
                    .map_err(sys_err(t, h, "factorization"))?;
                if !ok {
                    self.factored_h = f64::NAN;
                    stats.rejected_steps += 1;
                    rejected_before = true;
                    reason = "singular iteration matrix";
                    if !self.jac_fresh {
                        self.jac_valid = false;
                    } else {
                        h *= 0.5;
                    }
                    continue;
                }
                self.factored_h = h;
            }
            let t_new = if last { t_end } else { t + h };
            let err = match self.solve_stages(p, h, t_new, opts, stats)? {
                Ok(()) => self.error_norm(p, h, opts, stats)?,
                Err(why) => {
                    // A Newton failure: a stale matrix first, then the exact
                    // Jacobian, then a smaller step.
                    stats.rejected_steps += 1;
                    rejected_before = true;
                    reason = why;
                    if !self.jac_fresh {
                        self.jac_valid = false;
                    } else if self.matrix == Matrix::Cheap && p.kind() != JacKind::Full {
                        self.matrix = Matrix::Exact;
                        self.exact_left = EXACT_STEPS;
                        self.jac_valid = false;
                    } else {
                        h *= 0.5;
                    }
                    continue;
                }
            };
            let accept = match fixed {
                Some(_) => err.is_finite(),
                None => err <= 1.0,
            };
            if accept {
                self.accept(t_new, h, stats);
                // The next step size.
                let h_new = match fixed {
                    Some(dt) => dt.min(opts.h_max),
                    None => {
                        let e = err.max(1e-10);
                        let mut fac = SAFETY * e.powf(-EXPONENT);
                        if self.accepted > 1 && self.h_acc > 0.0 {
                            // Gustafsson's predictive controller.
                            let gus =
                                SAFETY * (h / self.h_acc) * (self.err_acc / (e * e)).powf(EXPONENT);
                            fac = fac.min(gus);
                        }
                        let mut fac = fac.clamp(FAC_MIN, FAC_MAX);
                        if rejected_before {
                            fac = fac.min(1.0);
                        }
                        self.h_acc = h;
                        self.err_acc = e.max(1e-2);
                        if (KEEP_MIN..=KEEP_MAX).contains(&fac) {
                            h
                        } else {
                            h * fac
                        }
                    }
                };
                self.s.h_next = h_new.min(opts.h_max);
                // The matrices for the next step.
                self.jac_fresh = false;
                let keep = match self.matrix {
                    Matrix::Exact => THETA_KEEP_EXACT,
                    Matrix::Cheap => THETA_KEEP_CHEAP,
                };
                if self.matrix == Matrix::Exact {
                    self.exact_left = self.exact_left.saturating_sub(1);
                    if self.exact_left == 0 {
                        self.matrix = Matrix::Cheap;
                        self.jac_valid = false;
                    }
                }
                if self.theta_max > keep {
                    self.jac_valid = false;
                }
                return Ok(());
            }
            stats.rejected_steps += 1;
            rejected_before = true;
            reason = if err.is_finite() {
                "error test"
            } else {
                "non-finite trial state"
            };
            h *= if err.is_finite() {
                (SAFETY * err.powf(-EXPONENT)).clamp(FAC_MIN, 1.0)
            } else {
                FAC_MIN
            };
        }
    }

    fn state(&self) -> &StepState {
        &self.s
    }
    fn state_mut(&mut self) -> &mut StepState {
        &mut self.s
    }

    fn dense(&self, t: f64, out: &mut DVector<f64>) {
        self.s.quintic_dense(t, out);
    }

    fn system_changed(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let (t, h) = (self.s.t, self.s.h);
        p.accel(t, &self.q, &self.v, &mut self.acc)
            .map_err(sys_err(t, h, "accel"))?;
        stats.rhs_evaluations += 1;
        check_finite(&self.acc, t, h, "acceleration")?;
        self.set_first_order();
        p.system_changed();
        self.jac_valid = false;
        self.factored_h = f64::NAN;
        // The matrix kind stays (CT25): a step hook that changes the system
        // after every step (a model with friction commits its anchors, CT5)
        // would otherwise send every step back to the cheap matrix the
        // previous one failed with, and pay a failed Newton iteration per
        // step before the exact Jacobian (the capstan: 46 of 48 steps;
        // docs/performance.md, "Contact-heavy scenes"). It returns to the
        // cheap matrix after `EXACT_STEPS` accepted steps as usual.
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The row sums `cᵢ = Σⱼ aᵢⱼ`, stage order 2 (`Σⱼ aᵢⱼ cⱼ = cᵢ²/2`), and
    /// the order conditions of every rooted tree up to order 5 for `b` (the
    /// last row of `A`) and up to order 4 for `b̂`, with the order-5 ones
    /// violated by `b̂` (Butcher's conditions `Φ(t) = 1/t!`: Hairer–Nørsett–
    /// Wanner, *ODEs I*, Table II.2.2, the nine trees of order 5 from §II.2).
    #[test]
    fn tableau_satisfies_the_order_conditions() {
        let b = A[S - 1];
        let tol = 2e-14;
        for i in 0..S {
            let c: f64 = A[i].iter().sum();
            assert!((c - C[i]).abs() < tol, "row {i}: {c} vs {}", C[i]);
            let ac: f64 = (0..S).map(|j| A[i][j] * C[j]).sum();
            if i >= 1 {
                assert!((ac - C[i] * C[i] / 2.0).abs() < tol, "stage order, row {i}");
            }
        }
        // Vectors over the stages and the products that build the trees.
        type V = [f64; S];
        let mul = |x: &V, y: &V| -> V { std::array::from_fn(|i| x[i] * y[i]) };
        let am = |x: &V| -> V { std::array::from_fn(|i| (0..S).map(|j| A[i][j] * x[j]).sum()) };
        let dot = |w: &V, x: &V| (0..S).map(|i| w[i] * x[i]).sum::<f64>();
        let one: V = [1.0; S];
        let c = C;
        let c2 = mul(&c, &c);
        let c3 = mul(&c2, &c);
        let c4 = mul(&c3, &c);
        let ac = am(&c);
        let ac2 = am(&c2);
        let aac = am(&ac);
        // (tree's elementary weight argument, 1/γ(t)), by order.
        let trees: [(usize, V, f64); 17] = [
            (1, one, 1.0),
            (2, c, 1.0 / 2.0),
            (3, c2, 1.0 / 3.0),
            (3, ac, 1.0 / 6.0),
            (4, c3, 1.0 / 4.0),
            (4, mul(&c, &ac), 1.0 / 8.0),
            (4, ac2, 1.0 / 12.0),
            (4, aac, 1.0 / 24.0),
            (5, c4, 1.0 / 5.0),
            (5, mul(&c2, &ac), 1.0 / 10.0),
            (5, mul(&c, &ac2), 1.0 / 15.0),
            (5, mul(&c, &aac), 1.0 / 30.0),
            (5, mul(&ac, &ac), 1.0 / 20.0),
            (5, am(&c3), 1.0 / 20.0),
            (5, am(&mul(&c, &ac)), 1.0 / 40.0),
            (5, am(&ac2), 1.0 / 60.0),
            (5, am(&aac), 1.0 / 120.0),
        ];
        for (k, (order, x, want)) in trees.iter().enumerate() {
            let got = dot(&b, x);
            assert!(
                (got - want).abs() < tol,
                "b, tree {k} (order {order}): {got} vs {want}"
            );
            let got = dot(&B_HAT, x);
            if *order <= 4 {
                assert!(
                    (got - want).abs() < tol,
                    "b̂, tree {k} (order {order}): {got} vs {want}"
                );
            }
        }
        // The embedded solution is of order 4 only: some order-5 tree fails.
        let worst = trees
            .iter()
            .filter(|t| t.0 == 5)
            .map(|(_, x, want)| (dot(&B_HAT, x) - want).abs())
            .fold(0.0, f64::max);
        assert!(worst > 1e-6, "b̂ satisfies order 5: {worst}");
    }

    /// The stability function `R(z) = 1 + z bᵀ(I − zA)⁻¹𝟙` of `b` and of
    /// `b̂` at complex `z` by forward substitution.
    fn stability(w: &[f64; S], z: nalgebra::Complex<f64>) -> f64 {
        let one = nalgebra::Complex::new(1.0, 0.0);
        let mut k = [nalgebra::Complex::new(0.0, 0.0); S];
        for i in 0..S {
            let mut s = one;
            for j in 0..i {
                s += z * A[i][j] * k[j];
            }
            k[i] = s / (one - z * A[i][i]);
        }
        (one + z * (0..S).map(|i| k[i] * w[i]).sum::<nalgebra::Complex<f64>>()).norm()
    }

    /// L-stability: `R(z) → 0` as `z → −∞`; `|R| ≤ 1` on the imaginary axis
    /// (where the undamped modes of a rod live) and in the left half-plane
    /// on a grid (A-stability, by the maximum principle the axis suffices
    /// for a function analytic there: the poles are at `1/γ > 0`).
    #[test]
    fn stability_function_is_l_stable() {
        let z = |re: f64, im: f64| nalgebra::Complex::new(re, im);
        let b = A[S - 1];
        assert!(stability(&b, z(-1e8, 0.0)) < 1e-6);
        for k in -40..=60 {
            let w = 10f64.powf(k as f64 / 10.0);
            let r = stability(&b, z(0.0, w));
            assert!(r <= 1.0 + 1e-14, "|R({w}i)| = {r}");
        }
        for re in [-0.1, -1.0, -10.0, -100.0] {
            for im in [0.0, 0.5, 3.0, 30.0] {
                assert!(stability(&b, z(re, im)) <= 1.0 + 1e-14);
            }
        }
    }
}
