//! ESDIRK4(3)6L\[2\]SA for second-order systems `q̈ = a(t, q, q̇)`: the
//! implicit tableau of Kennedy & Carpenter's ARK4(3)6L\[2\]SA (C. A. Kennedy,
//! M. H. Carpenter, "Additive Runge–Kutta schemes for convection–diffusion–
//! reaction equations", Appl. Numer. Math. 44 (2003) 139–181, Table 5): six
//! stages, the first explicit, five implicit with the same diagonal
//! `γ = 1/4`, order 4 with an embedded order-3 solution, L-stable, stiffly
//! accurate (`b` is the last row of `A`), stage order 2.
//!
//! On `y = (q, v)`, `y' = (v, a)`, stage `i ≥ 2` is, with the explicit parts
//! `v̂ᵢ = vₙ + h Σⱼ<ᵢ aᵢⱼ Aⱼ`, `q̂ᵢ = qₙ + h Σⱼ<ᵢ aᵢⱼ Vⱼ`,
//!
//! `Vᵢ = v̂ᵢ + hγ Aᵢ`, `Qᵢ = q̂ᵢ + hγ Vᵢ`, `Aᵢ = a(tₙ + cᵢh, Qᵢ, Vᵢ)`,
//!
//! one nonlinear equation in the stage acceleration `Aᵢ` (n unknowns, not
//! 2n). Its Newton matrix is `I − hγ ∂a/∂q̇ − h²γ² ∂a/∂q`, i.e.
//! `M⁻¹(M + hγ ∂r/∂q̇ + h²γ² ∂r/∂q)` for the force residual
//! `r = M(q) A − f(q, q̇)`: the real shift of the shifted mass matrix
//! `M + aK + bD` with `a = h²γ²`, `b = hγ` when only the elastic/viscous
//! part is kept. So the simplified Newton iteration runs on
//! [`SecondOrderSystem::factor_shifted_mass`] (O(N) for a rod, no `n×n`
//! matrix) with the O(N) inverse-dynamics residual, and falls back to the
//! exact dense Jacobian ([`SecondOrderSystem::jacobians`]) when that
//! converges badly — the fixed point is the same either way, so the
//! approximation costs iterations, never accuracy.
//!
//! Error estimate: the embedded solution gives `(e_q, e_v) = h Σ (bᵢ − b̂ᵢ)
//! (Vᵢ, Aᵢ)`, filtered by `(I − hγJ)⁻¹` as in Hairer–Wanner's RADAU5
//! (*ODEs II* §IV.8; a stiff component is divided by `|1 − hγλ|`), and
//! measured as positions: `‖(e_q, h·e_v)‖` in the weighted RMS norm with the
//! position weights `atol + rtol·max(|qₙ|, |qₙ₊₁|)` — the velocity error
//! counts as the position error it makes over the step. Why: with the usual
//! first-order norm `‖(e_q, e_v)‖` the controller resolves every bending
//! mode whose *velocity* amplitude `ω·A` exceeds the tolerance, although its
//! displacement `A` is far below it; on the planar release (docs/theory.md
//! §8(h), `atol = rtol`) that took 3 277 steps at `rtol = 1e-4` for a tip
//! error of 1.0e-5 m, against 142 steps for 1.3e-4 m and 432 steps for
//! 1.8e-5 m at `rtol = 1e-5` with the position norm, whose tip error stays
//! within 1–2.5× `rtol` (in m) from `rtol = 1e-3` to `1e-7`
//! (docs/performance.md). The step follows Gustafsson's predictive
//! controller for an `O(h⁴)` estimate, as RADAU5's, with `h` kept for
//! factors in `[1, 1.2]` so the factorization is reused. Dense output: the
//! quintic Hermite interpolant of `(q, q̇, q̈)` at both ends of the step
//! (`O(h⁶)` in `q`, `O(h⁵)` in `q̇`: it does not lower the method's order;
//! on a quasi-static settle the steps outgrow the decay of the damped
//! modes and the interpolant across them does not follow it, so
//! outputs can be step ends instead: `Options::steps_to_outputs`,
//! docs/theory-derivatives.md CD10).

// The coefficients are transcribed with all the digits published.
#![allow(clippy::excessive_precision)]
// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::DVector;

use crate::control::{check_finite, check_underflow, clip_step};
use crate::error::{IntegrateError, first_non_finite};
use crate::options::{Iteration, Options};
use crate::problem::{JacKind, Problem, SecondOrderProblem, sys_err};
use crate::solution::Stats;
use crate::state::StepState;
use crate::stepper::Stepper;
use crate::system::SecondOrderSystem;

const S: usize = 6;
/// The diagonal of the implicit stages.
pub(crate) const GAMMA: f64 = 0.25;
/// Nodes `cᵢ`.
pub(crate) const C: [f64; S] = [0.0, 0.5, 83.0 / 250.0, 31.0 / 50.0, 17.0 / 20.0, 1.0];
/// `aᵢⱼ` (lower triangular, `γ` on the diagonal from the second stage).
pub(crate) const A: [[f64; S]; S] = [
    [0.0; S],
    [GAMMA, GAMMA, 0.0, 0.0, 0.0, 0.0],
    [8611.0 / 62500.0, -1743.0 / 31250.0, GAMMA, 0.0, 0.0, 0.0],
    [
        5012029.0 / 34652500.0,
        -654441.0 / 2922500.0,
        174375.0 / 388108.0,
        GAMMA,
        0.0,
        0.0,
    ],
    [
        15267082809.0 / 155376265600.0,
        -71443401.0 / 120774400.0,
        730878875.0 / 902184768.0,
        2285395.0 / 8070912.0,
        GAMMA,
        0.0,
    ],
    [
        82889.0 / 524892.0,
        0.0,
        15625.0 / 83664.0,
        69875.0 / 102672.0,
        -2260.0 / 8211.0,
        GAMMA,
    ],
];
/// Weights of the embedded order-3 solution (`b` is the last row of `A`).
pub(crate) const B_HAT: [f64; S] = [
    4586570599.0 / 29645900160.0,
    0.0,
    178811875.0 / 945068544.0,
    814220225.0 / 1159782912.0,
    -3700637.0 / 11593932.0,
    61727.0 / 225920.0,
];

/// Step-size controller (RADAU5's defaults): safety factor, bounds of
/// `h_new/h`, and the band within which `h` is kept.
/// Stage `i`'s explicit part `(Q̂ᵢ, V̂ᵢ) = (q, v) + h Σ_{j<i} a_ij (V_j, A_j)`
/// with `row` the coefficients `a_ij, j < i` of any tableau (shared with
/// the discrete derivatives' recomputed stages, so both take the same
/// rounding).
#[allow(clippy::too_many_arguments)]
pub(crate) fn explicit_part(
    row: &[f64],
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
    for (j, &a) in row.iter().enumerate() {
        if a != 0.0 {
            qhat.axpy(h * a, &vs[j], 1.0);
            vhat.axpy(h * a, &accs[j], 1.0);
        }
    }
}

/// A stage's values from its acceleration `x`: `Vᵢ = V̂ᵢ + hγ x`,
/// `Qᵢ = Q̂ᵢ + hγ Vᵢ`.
pub(crate) fn stage_values(
    hg: f64,
    qhat: &DVector<f64>,
    vhat: &DVector<f64>,
    x: &DVector<f64>,
    vi: &mut DVector<f64>,
    qi: &mut DVector<f64>,
) {
    for r in 0..x.len() {
        let vr = vhat[r] + hg * x[r];
        vi[r] = vr;
        qi[r] = qhat[r] + hg * vr;
    }
}

/// An ESDIRK tableau for [`Esdirk`]: explicit first stage, the same
/// diagonal `γ` on the implicit ones, stiffly accurate (`b` is the last row
/// of `A`), with an embedded solution `b̂` one order lower.
pub(crate) trait Tableau {
    /// Stages (the first explicit).
    const S: usize;
    /// The diagonal of the implicit stages.
    const GAMMA: f64;
    /// Nodes `cᵢ`.
    const C: &'static [f64];
    /// Rows of `aᵢⱼ`.
    const A: &'static [&'static [f64]];
    /// Weights of the embedded solution.
    const B_HAT: &'static [f64];
    /// The step controller's exponent, `1/(order of the estimate + 1)`.
    const EXPONENT: f64;
    /// The driver's starting-step order ([`Stepper::START_ORDER`]).
    const START_ORDER: i32;
}

/// ESDIRK4(3)6L\[2\]SA (the module's tableau; the default method).
pub(crate) struct Esdirk43;

impl Tableau for Esdirk43 {
    const S: usize = S;
    const GAMMA: f64 = GAMMA;
    const C: &'static [f64] = &C;
    const A: &'static [&'static [f64]] = &[&A[0], &A[1], &A[2], &A[3], &A[4], &A[5]];
    const B_HAT: &'static [f64] = &B_HAT;
    const EXPONENT: f64 = 0.25;
    const START_ORDER: i32 = 3;
}

/// A [`Tableau`]'s coefficients as a value: what the discrete adjoint and
/// the forward sensitivities (`crate::adjoint`, `crate::sensitivity`) run
/// on, one code for every stiffly accurate ESDIRK with an explicit first
/// stage (docs/theory-control.md G27).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coefficients {
    /// The diagonal `γ` of the implicit stages.
    pub(crate) gamma: f64,
    /// Nodes `cᵢ` (one per stage).
    pub(crate) c: &'static [f64],
    /// Rows of `aᵢⱼ` (the last is `b`).
    pub(crate) a: &'static [&'static [f64]],
}

impl Coefficients {
    pub(crate) fn of<T: Tableau>() -> Self {
        debug_assert!(T::C.len() == T::S && T::A.len() == T::S);
        Self {
            gamma: T::GAMMA,
            c: T::C,
            a: T::A,
        }
    }

    /// Number of stages `s` (the first explicit).
    pub(crate) fn stages(&self) -> usize {
        self.c.len()
    }
}

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
/// At most this many retries of one step to land on a stopping slide
/// (docs/theory-contact.md CT29): the secant of a constant friction force
/// is exact, a varying one converges in a few.
const MAX_LOCATE: usize = 4;
/// The smallest fraction of a step a stop location retries it at.
const LOCATE_MIN: f64 = 0.01;

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

/// The state and buffers of an ESDIRK method with tableau `T` (allocated
/// once); `Esdirk<Esdirk43>` is ESDIRK4(3)6L\[2\]SA.
pub(crate) struct Esdirk<T: Tableau = Esdirk43> {
    n: usize,
    /// First-order views `y = (q, q̇)`, `f = (q̇, q̈)` for the driver and the
    /// dense output.
    s: StepState,
    q: DVector<f64>,
    v: DVector<f64>,
    acc: DVector<f64>,
    /// Stage values; stage 0 is the step start.
    qs: Vec<DVector<f64>>,
    vs: Vec<DVector<f64>>,
    accs: Vec<DVector<f64>>,
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
    /// The structured matrix was re-linearized within the step (CT27): it
    /// no longer holds the step start's linearization.
    relinearized: bool,
    tableau: std::marker::PhantomData<T>,
}

impl<T: Tableau> Esdirk<T> {
    pub(crate) fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        Self {
            n,
            s: StepState::new(2 * n),
            q: z.clone(),
            v: z.clone(),
            acc: z.clone(),
            qs: vec![z.clone(); T::S],
            vs: vec![z.clone(); T::S],
            accs: vec![z.clone(); T::S],
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
            relinearized: false,
            tableau: std::marker::PhantomData,
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
        self.relinearized = false;
        Ok(())
    }

    /// Solves the five implicit stages of a step of size `h` to `t_new`.
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
        let (hg, hg2) = (h * T::GAMMA, h * h * T::GAMMA * T::GAMMA);
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
        let relinearize = self.matrix == Matrix::Cheap
            && p.kind() == JacKind::Structured
            && p.relinearize_in_newton();
        for i in 1..T::S {
            let ti = if i == T::S - 1 {
                t_new
            } else {
                t + T::C[i] * h
            };
            // Explicit parts.
            explicit_part(
                &T::A[i][..i],
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
            // the step start before it, starts from that). On the cable arm of
            // `softrod/Reach-v0` at rtol 1e-2 this saved 10 % of the Newton
            // iterations against the previous stage's value alone
            // (docs/performance.md, "Learning environments"); a parabola
            // through three stages saved no more: the first correction is
            // then dominated by the stiff components, which do not
            // extrapolate.
            let (done, rest) = self.accs.split_at_mut(i);
            let x = &mut rest[0];
            x.copy_from(&done[i - 1]);
            if i >= 2 {
                let w = (T::C[i] - T::C[i - 1]) / (T::C[i - 1] - T::C[i - 2]);
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
                if k >= 2 && relinearize {
                    // Active-set Newton on the structured matrix (CT27): the
                    // contact linearized and the matrix factored again at
                    // the current iterate, O(N) each.
                    p.update_jacobians_qv(ti, &self.qs[i], &self.vs[i], true)
                        .map_err(sys_err(t, h, "jacobian"))?;
                    stats.factorizations += 1;
                    if !p
                        .factor_newmark(hg2, hg)
                        .map_err(sys_err(t, h, "factorization"))?
                    {
                        return Ok(Err("singular iteration matrix"));
                    }
                    self.factored_h = f64::NAN;
                    self.relinearized = true;
                }
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
            for i in 0..T::S {
                let d = T::A[T::S - 1][i] - T::B_HAT[i];
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
            p.filter_error(t, h * T::GAMMA, &mut self.eq, &mut self.ev)
                .map_err(sys_err(t, h, "error filter"))?;
            stats.lu_solves += 1;
        }
        let mut s = 0.0;
        let qn = &self.qs[T::S - 1];
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
        std::mem::swap(&mut self.q, &mut self.qs[T::S - 1]);
        std::mem::swap(&mut self.v, &mut self.vs[T::S - 1]);
        // Copied, not swapped: `accs` keeps the step's stages for
        // `stage_accelerations` (the adjoint's tape, G34).
        self.acc.copy_from(&self.accs[T::S - 1]);
        self.set_first_order();
        self.s.advance(t_new, h, stats);
        self.accepted += 1;
    }
}

impl<T: Tableau, Sys: SecondOrderSystem> Stepper<SecondOrderProblem<'_, Sys>> for Esdirk<T> {
    const START_ORDER: i32 = T::START_ORDER;

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
        let mut relinearized_failed = false;
        let mut located = 0;
        let mut shrunk = false;
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
                    .factor_newmark(h * h * T::GAMMA * T::GAMMA, h * T::GAMMA)
                    .map_err(sys_err(t, h, "factorization"))?;
                if !ok {
                    self.factored_h = f64::NAN;
                    stats.rejected_steps += 1;
                    reason = "singular iteration matrix";
                    if !self.jac_fresh {
                        self.jac_valid = false;
                    } else {
                        h *= 0.5;
                        shrunk = true;
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
                    reason = why;
                    if self.relinearized && !relinearized_failed {
                        // The active-set iteration (CT27) already followed
                        // the contact through its iterates: first a smaller
                        // step from a linearization at the step start, then
                        // (a second failure) the exact Jacobian as usual.
                        relinearized_failed = true;
                        self.jac_valid = false;
                        h *= 0.5;
                        shrunk = true;
                    } else if !self.jac_fresh {
                        self.jac_valid = false;
                    } else if self.matrix == Matrix::Cheap && p.kind() != JacKind::Full {
                        self.matrix = Matrix::Exact;
                        self.exact_left = EXACT_STEPS;
                        self.jac_valid = false;
                    } else {
                        h *= 0.5;
                        shrunk = true;
                    }
                    continue;
                }
            };
            let accept = match fixed {
                Some(_) => err.is_finite(),
                None => err <= 1.0,
            };
            if accept && fixed.is_none() && located < MAX_LOCATE {
                // A slide that stopped inside the step (CT29): the step
                // again, ending at the stop.
                let stop = p
                    .step_event_fraction(
                        h,
                        t,
                        &self.q,
                        &self.v,
                        t_new,
                        &self.qs[T::S - 1],
                        &self.vs[T::S - 1],
                    )
                    .map_err(sys_err(t, h, "friction stop"))?;
                if let Some(theta) = stop {
                    located += 1;
                    stats.rejected_steps += 1;
                    reason = "friction stop";
                    h *= theta.clamp(LOCATE_MIN, 1.0);
                    continue;
                }
            }
            if accept {
                self.accept(t_new, h, stats);
                // The next step size.
                let h_new = match fixed {
                    Some(dt) => dt.min(opts.h_max),
                    None => {
                        let e = err.max(1e-10);
                        let mut fac = SAFETY * e.powf(-T::EXPONENT);
                        if self.accepted > 1 && self.h_acc > 0.0 {
                            // Gustafsson's predictive controller.
                            let gus = SAFETY
                                * (h / self.h_acc)
                                * (self.err_acc / (e * e)).powf(T::EXPONENT);
                            fac = fac.min(gus);
                        }
                        let mut fac = fac.clamp(FAC_MIN, FAC_MAX);
                        // Only a step that had to shrink caps the growth: a
                        // Newton failure retried at the same `h` with a
                        // fresh or exact matrix, or a step shortened to a
                        // friction stop, says nothing of the error
                        // (CT25 (b), CT29).
                        if shrunk {
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
                if self.theta_max > keep || self.relinearized {
                    self.jac_valid = false;
                }
                return Ok(());
            }
            stats.rejected_steps += 1;
            shrunk = true;
            reason = if err.is_finite() {
                "error test"
            } else {
                "non-finite trial state"
            };
            h *= if err.is_finite() {
                (SAFETY * err.powf(-T::EXPONENT)).clamp(FAC_MIN, 1.0)
            } else {
                FAC_MIN
            };
        }
    }

    fn stage_accelerations(&self) -> &[DVector<f64>] {
        &self.accs
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

    /// Projects `(q, v)` (docs/theory.md D121) and, if they moved, takes
    /// the step-start acceleration there; the Jacobian and its
    /// factorization are kept, as for [`forces_changed`](Self::forces_changed)
    /// (the projection moves the state by about the step's constraint
    /// drift, far less than a step).
    fn project(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        stats: &mut Stats,
    ) -> Result<bool, IntegrateError> {
        let (t, h) = (self.s.t, self.s.h);
        let moved = p
            .project(t, &mut self.q, &mut self.v)
            .map_err(sys_err(t, h, "projection"))?;
        if moved {
            self.forces_changed(p, stats)?;
        }
        Ok(moved)
    }

    /// Friction anchors or healed offsets only (CT25 (a)): the step-start
    /// acceleration again, the Jacobian and its factorization kept — they
    /// are refreshed when the Newton iteration's own tests ask (a stale
    /// matrix that fails, a contraction above `THETA_KEEP_*`). The slope
    /// of the law moves only where a branch flips, which the active-set
    /// iteration (CT27) re-linearizes anyway.
    fn forces_changed(
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
        Ok(())
    }

    fn system_changed(
        &mut self,
        p: &mut SecondOrderProblem<'_, Sys>,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        self.forces_changed(p, stats)?;
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

    /// Order conditions up to order 4 for `b` (the last row of `A`) and up
    /// to order 3 for `b̂` (Hairer–Nørsett–Wanner, *ODEs I*, Table II.2.2),
    /// and row sums `cᵢ = Σⱼ aᵢⱼ`.
    #[test]
    fn tableau_satisfies_the_order_conditions() {
        let b = A[S - 1];
        let tol = 1e-15;
        for i in 0..S {
            let c: f64 = A[i].iter().sum();
            assert!((c - C[i]).abs() < tol, "row {i}: {c} vs {}", C[i]);
        }
        let dot = |w: &[f64; S], f: &dyn Fn(usize) -> f64| (0..S).map(|i| w[i] * f(i)).sum::<f64>();
        let ac = |i: usize| (0..S).map(|j| A[i][j] * C[j]).sum::<f64>();
        let ac2 = |i: usize| (0..S).map(|j| A[i][j] * C[j] * C[j]).sum::<f64>();
        let aac = |i: usize| (0..S).map(|j| A[i][j] * ac(j)).sum::<f64>();
        for (w, order) in [(&b, 4), (&B_HAT, 3)] {
            assert!((dot(w, &|_| 1.0) - 1.0).abs() < tol);
            assert!((dot(w, &|i| C[i]) - 0.5).abs() < tol);
            assert!((dot(w, &|i| C[i] * C[i]) - 1.0 / 3.0).abs() < tol);
            assert!((dot(w, &ac) - 1.0 / 6.0).abs() < tol);
            if order == 4 {
                assert!((dot(w, &|i| C[i].powi(3)) - 0.25).abs() < tol);
                assert!((dot(w, &|i| C[i] * ac(i)) - 1.0 / 8.0).abs() < tol);
                assert!((dot(w, &ac2) - 1.0 / 12.0).abs() < tol);
                assert!((dot(w, &aac) - 1.0 / 24.0).abs() < tol);
            } else {
                // The embedded solution is of order 3 only.
                assert!((dot(w, &aac) - 1.0 / 24.0).abs() > 1e-6);
            }
        }
    }

    /// `R(z) = 1 + z bᵀ(I − zA)⁻¹𝟙 → 0` as `z → −∞` (L-stability), and
    /// `|R(iω)| ≤ 1` on the imaginary axis (A-stability's boundary, where
    /// the undamped modes of a rod live).
    #[test]
    fn stability_function_is_l_stable() {
        let r = |z: f64| -> f64 {
            // Real z: solve (I − zA) k = 𝟙 by forward substitution.
            let mut k = [0.0; S];
            for i in 0..S {
                let mut s = 1.0;
                for j in 0..i {
                    s += z * A[i][j] * k[j];
                }
                k[i] = s / (1.0 - z * A[i][i]);
            }
            1.0 + z * (0..S).map(|i| A[S - 1][i] * k[i]).sum::<f64>()
        };
        assert!(r(-1e8).abs() < 1e-6, "R(-1e8) = {}", r(-1e8));
        let rc = |w: f64| -> f64 {
            let z = nalgebra::Complex::new(0.0, w);
            let one = nalgebra::Complex::new(1.0, 0.0);
            let mut k = [nalgebra::Complex::new(0.0, 0.0); S];
            for i in 0..S {
                let mut s = one;
                for j in 0..i {
                    s += z * A[i][j] * k[j];
                }
                k[i] = s / (one - z * A[i][i]);
            }
            (one + z
                * (0..S)
                    .map(|i| k[i] * A[S - 1][i])
                    .sum::<nalgebra::Complex<f64>>())
            .norm()
        };
        for w in [0.1, 1.0, 3.0, 10.0, 100.0, 1e4] {
            assert!(rc(w) <= 1.0 + 1e-14, "|R({w}i)| = {}", rc(w));
        }
    }
}
