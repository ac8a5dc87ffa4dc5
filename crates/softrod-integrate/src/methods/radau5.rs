//! Radau IIA of order 5 (three stages, collocation at `c = ((4 − √6)/10,
//! (4 + √6)/10, 1)`), after the design of Hairer & Wanner's RADAU5
//! (*Solving ODEs II*, 2nd ed., §IV.8; facts of the published design, the
//! code is this crate's own):
//!
//! * stage increments `Zᵢ = Yᵢ − yₙ`, simplified Newton in the variables
//!   `W = T⁻¹Z` that diagonalize `A⁻¹` into the real eigenvalue `γ̂` and the
//!   complex pair `α ± iβ`: each iteration solves one real system with
//!   `γ̂/h·I − J` and one complex with `(α + iβ)/h·I − J` (for a
//!   second-order problem both through the `n×n` Schur complement);
//! * starting values from the previous step's collocation polynomial;
//!   Newton stopped when `θ/(1 − θ)·‖ΔW‖ ≤ κ`, abandoned when it diverges
//!   (`θ ≥ 0.99`) or is predicted not to converge in the iterations left
//!   (then `h` shrinks by the predicted factor);
//! * error estimate `(γ̂/h·I − J)⁻¹ (f(yₙ) + Σ eᵢ Zᵢ/h)` (filtered, so stiff
//!   components do not force small steps), recomputed once from
//!   `f(yₙ + err)` after a rejection or on the first step; for a
//!   second-order problem measured in positions, `‖(e_q, h·e_v)‖` (see
//!   [`Integrator::Esdirk`](crate::Integrator::Esdirk));
//! * the internal tolerances `rtol' = 0.1·rtol^(2/3)`, `atol' = rtol'·atol/rtol`
//!   (so that the global error is of the order of `rtol`);
//! * Gustafsson's predictive step-size controller, safety scaled by the
//!   Newton iterations taken; the Jacobian kept while Newton contracts
//!   faster than `θ ≤ 0.1` (RADAU5's advice when Jacobians are costly), the
//!   factorizations while also `h` changes by a factor in `[1, 1.2]`;
//! * dense output: the collocation polynomial (order 3 in between the
//!   steps, exact at the nodes).

// The transformation matrices are transcribed with all the digits
// published.
#![allow(clippy::excessive_precision)]
// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// The stage index runs over several arrays at once (Z, W, T, T⁻¹, nodes).
#![allow(clippy::needless_range_loop)]

use nalgebra::DVector;

use crate::control::{check_underflow, clip_step};
use crate::error::{IntegrateError, first_non_finite};
use crate::options::{Iteration, Options};
use crate::problem::{Problem, sys_err};
use crate::solution::Stats;
use crate::state::StepState;
use crate::stepper::Stepper;

/// `√6`.
const SQ6: f64 = 2.449489742783178098197284074705891391965947480656670128432692567;
const C1: f64 = (4.0 - SQ6) / 10.0;
const C2: f64 = (4.0 + SQ6) / 10.0;
/// The Radau IIA coefficients `A` (Hairer–Wanner, *ODEs II*, Table
/// IV.5.6) and the nodes `c` (`c₃ = 1`, `A`'s last row is `b`): the
/// collocation equations the discrete adjoint and the forward
/// sensitivities solve (docs/theory-control.md G25).
pub(crate) const RADAU_A: [[f64; 3]; 3] = [
    [
        (88.0 - 7.0 * SQ6) / 360.0,
        (296.0 - 169.0 * SQ6) / 1800.0,
        (-2.0 + 3.0 * SQ6) / 225.0,
    ],
    [
        (296.0 + 169.0 * SQ6) / 1800.0,
        (88.0 + 7.0 * SQ6) / 360.0,
        (-2.0 - 3.0 * SQ6) / 225.0,
    ],
    [(16.0 - SQ6) / 36.0, (16.0 + SQ6) / 36.0, 1.0 / 9.0],
];
/// The nodes of [`RADAU_A`].
pub(crate) const RADAU_C: [f64; 3] = [C1, C2, 1.0];
/// Error-estimate weights `eᵢ` (`e = b̂ − b` scaled by the real eigenvalue).
const DD1: f64 = -(13.0 + 7.0 * SQ6) / 3.0;
const DD2: f64 = (-13.0 + 7.0 * SQ6) / 3.0;
const DD3: f64 = -1.0 / 3.0;
/// `T` (third row `(t31, 1, 0)`) and `T⁻¹` of RADAU5.
const T: [[f64; 3]; 3] = [
    [
        9.1232394870892942792e-02,
        -1.4125529502095420843e-01,
        -3.0029194105147424492e-02,
    ],
    [
        2.4171793270710701896e-01,
        2.0412935229379993199e-01,
        3.8294211275726193779e-01,
    ],
    [9.6604818261509293619e-01, 1.0, 0.0],
];
const TI: [[f64; 3]; 3] = [
    [
        4.3255798900631553510e+00,
        3.3919925181580986954e-01,
        5.4177053993587487119e-01,
    ],
    [
        -4.1787185915519047273e+00,
        -3.2768282076106238708e-01,
        4.7662355450055045196e-01,
    ],
    [
        -5.0287263494578687595e-01,
        2.5719269498556054292e+00,
        -5.9603920482822492497e-01,
    ],
];

/// The eigenvalues of `A⁻¹`: real `γ̂`, complex `α ± iβ`.
fn eigenvalues() -> (f64, f64, f64) {
    let c81 = 81f64.cbrt();
    let c9 = 9f64.cbrt();
    let u1 = 30.0 / (6.0 + c81 - c9);
    let a = (12.0 - c81 + c9) / 60.0;
    let b = (c81 + c9) * 3f64.sqrt() / 60.0;
    let cno = a * a + b * b;
    (u1, a / cno, b / cno)
}

const SAFETY: f64 = 0.9;
/// `h_new/h ∈ [1/FAC_L, 1/FAC_R]`.
const FAC_L: f64 = 5.0;
const FAC_R: f64 = 0.125;
const KEEP_MIN: f64 = 1.0;
const KEEP_MAX: f64 = 1.2;
/// Keep the Jacobian when Newton contracted at least this fast.
const THETA_KEEP: f64 = 0.1;
const THETA_DIVERGED: f64 = 0.99;

/// Radau IIA 5 state and buffers (allocated once).
pub(crate) struct Radau5 {
    /// `f` is `f(t, y)`.
    s: StepState,
    /// `Some(n)`: `y = (q, q̇)` of a second-order problem (error in
    /// positions).
    second_order: Option<usize>,
    z: [DVector<f64>; 3],
    w: [DVector<f64>; 3],
    fz: [DVector<f64>; 3],
    /// Collocation polynomial of the last step (dense output, predictor).
    cont: [DVector<f64>; 3],
    ytmp: DVector<f64>,
    err: DVector<f64>,
    err2: DVector<f64>,
    scal: DVector<f64>,
    h_old: f64,
    h_acc: f64,
    err_acc: f64,
    accepted: usize,
    faccon: f64,
    theta: f64,
    jac_valid: bool,
    jac_fresh: bool,
    factored_h: f64,
    eig: (f64, f64, f64),
}

impl Radau5 {
    pub(crate) fn new(m: usize, second_order: Option<usize>) -> Self {
        let z = DVector::zeros(m);
        Self {
            s: StepState::new(m),
            second_order,
            z: std::array::from_fn(|_| z.clone()),
            w: std::array::from_fn(|_| z.clone()),
            fz: std::array::from_fn(|_| z.clone()),
            cont: std::array::from_fn(|_| z.clone()),
            ytmp: z.clone(),
            err: z.clone(),
            err2: z.clone(),
            scal: z,
            h_old: 0.0,
            h_acc: 0.0,
            err_acc: 1e-2,
            accepted: 0,
            faccon: 1.0,
            theta: 1.0,
            jac_valid: false,
            jac_fresh: false,
            factored_h: f64::NAN,
            eig: eigenvalues(),
        }
    }

    /// RADAU5's internal tolerances from the user's.
    fn tolerances(opts: &Options) -> (f64, f64) {
        if opts.rtol > 0.0 {
            let r = 0.1 * opts.rtol.powf(2.0 / 3.0);
            (r, r * opts.atol / opts.rtol)
        } else {
            (0.0, opts.atol)
        }
    }

    fn set_scal(&mut self, opts: &Options) {
        let (rtol, atol) = Self::tolerances(opts);
        for i in 0..self.scal.len() {
            self.scal[i] = atol + rtol * self.s.y[i].abs();
        }
    }

    /// Weighted RMS of the error vector `e` (positions only, velocities as
    /// `h·e_v`, for a second-order problem).
    fn norm(&self, e: &DVector<f64>, h: f64) -> f64 {
        let m = e.len();
        if m == 0 {
            return 0.0;
        }
        let mut s = 0.0;
        match self.second_order {
            Some(n) => {
                for i in 0..n {
                    let a = e[i] / self.scal[i];
                    let b = h * e[n + i] / self.scal[i];
                    s += a * a + b * b;
                }
            }
            None => {
                for i in 0..m {
                    let a = e[i] / self.scal[i];
                    s += a * a;
                }
            }
        }
        (s / m as f64).sqrt()
    }

    fn update_jacobian<P: Problem>(
        &mut self,
        p: &mut P,
        h: f64,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let t = self.s.t;
        // The exact Jacobian, never a cheap approximation: simplified Newton
        // converges only with a good one.
        let bad = p
            .update_exact_jacobian(t, &self.s.y)
            .map_err(sys_err(t, h, "jacobian"))?;
        stats.jacobian_evaluations += 1;
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

    /// The Newton iteration of a step of size `h`. `Ok(Ok(iterations))`:
    /// converged; `Ok(Err((why, factor)))`: failed, retry with `h·factor`.
    #[allow(clippy::type_complexity)]
    fn newton<P: Problem>(
        &mut self,
        p: &mut P,
        h: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<Result<usize, (&'static str, f64)>, IntegrateError> {
        let m = self.s.y.len();
        let t = self.s.t;
        let (u1, al, be) = self.eig;
        let (fac1, alphn, betan) = (u1 / h, al / h, be / h);
        let (fnewt, nit) = match opts.iteration {
            Iteration::Newton { tol, max_iter } => (tol, max_iter.max(1)),
            Iteration::LinearlyImplicit => (f64::INFINITY, 1),
        };
        // Starting values: the last collocation polynomial, extrapolated.
        if self.accepted == 0 {
            for i in 0..3 {
                self.z[i].fill(0.0);
                self.w[i].fill(0.0);
            }
        } else {
            let c3q = h / self.h_old;
            let cq = [C1 * c3q, C2 * c3q, c3q];
            let (c1m1, c2m1) = (C1 - 1.0, C2 - 1.0);
            for r in 0..m {
                let (a1, a2, a3) = (self.cont[0][r], self.cont[1][r], self.cont[2][r]);
                for (k, &c) in cq.iter().enumerate() {
                    self.z[k][r] = c * (a1 + (c - c2m1) * (a2 + (c - c1m1) * a3));
                }
                for k in 0..3 {
                    self.w[k][r] =
                        TI[k][0] * self.z[0][r] + TI[k][1] * self.z[1][r] + TI[k][2] * self.z[2][r];
                }
            }
        }
        self.faccon = self.faccon.max(f64::EPSILON).powf(0.8);
        self.theta = THETA_KEEP * 1e-2;
        let (mut dynold, mut thqold) = (0.0, 0.0);
        let cs = [C1, C2, 1.0];
        for newt in 0..nit {
            for k in 0..3 {
                self.ytmp.copy_from(&self.s.y);
                self.ytmp += &self.z[k];
                let tk = if k == 2 { t + h } else { t + cs[k] * h };
                p.rhs(tk, &self.ytmp, &mut self.fz[k])
                    .map_err(sys_err(t, h, "rhs"))?;
            }
            stats.rhs_evaluations += 3;
            stats.newton_iterations += 1;
            stats.lu_solves += 1;
            // Right-hand sides in the transformed variables, into fz.
            for r in 0..m {
                let (a1, a2, a3) = (self.fz[0][r], self.fz[1][r], self.fz[2][r]);
                let r1 = TI[0][0] * a1 + TI[0][1] * a2 + TI[0][2] * a3;
                let r2 = TI[1][0] * a1 + TI[1][1] * a2 + TI[1][2] * a3;
                let r3 = TI[2][0] * a1 + TI[2][1] * a2 + TI[2][2] * a3;
                let (w1, w2, w3) = (self.w[0][r], self.w[1][r], self.w[2][r]);
                self.fz[0][r] = r1 - fac1 * w1;
                self.fz[1][r] = r2 - alphn * w2 + betan * w3;
                self.fz[2][r] = r3 - alphn * w3 - betan * w2;
            }
            p.solve_shifted(&mut self.fz[0]);
            let (lo, hi) = self.fz.split_at_mut(2);
            p.solve_shifted_complex(&mut lo[1], &mut hi[0]);
            let mut s = 0.0;
            for k in 0..3 {
                for r in 0..m {
                    let d = self.fz[k][r] / self.scal[r];
                    s += d * d;
                }
            }
            let dyno = if m == 0 {
                0.0
            } else {
                (s / (3 * m) as f64).sqrt()
            };
            if !dyno.is_finite() {
                return Ok(Err(("non-finite iterate", 0.5)));
            }
            if newt >= 1 {
                let thq = dyno / dynold;
                self.theta = if newt == 1 {
                    thq
                } else {
                    (thq * thqold).sqrt()
                };
                thqold = thq;
                if self.theta < THETA_DIVERGED {
                    self.faccon = self.theta / (1.0 - self.theta);
                    let left = (nit - 1 - newt) as i32;
                    let dyth = self.faccon * dyno * self.theta.powi(left) / fnewt;
                    if dyth >= 1.0 {
                        let qnewt = dyth.clamp(1e-4, 20.0);
                        let f = 0.8 * qnewt.powf(-1.0 / (4.0 + left as f64));
                        return Ok(Err(("too slow", f)));
                    }
                } else {
                    return Ok(Err(("diverged", 0.5)));
                }
            }
            dynold = dyno.max(f64::EPSILON);
            for r in 0..m {
                for k in 0..3 {
                    self.w[k][r] += self.fz[k][r];
                }
                let (w1, w2, w3) = (self.w[0][r], self.w[1][r], self.w[2][r]);
                self.z[0][r] = T[0][0] * w1 + T[0][1] * w2 + T[0][2] * w3;
                self.z[1][r] = T[1][0] * w1 + T[1][1] * w2 + T[1][2] * w3;
                self.z[2][r] = T[2][0] * w1 + w2;
            }
            if first_non_finite(self.z[2].as_slice()).is_some() {
                return Ok(Err(("non-finite iterate", 0.5)));
            }
            if self.faccon * dyno <= fnewt {
                return Ok(Ok(newt + 1));
            }
        }
        Ok(Err(("max iterations", 0.5)))
    }

    /// The filtered error estimate (see the module documentation).
    fn error<P: Problem>(
        &mut self,
        p: &mut P,
        h: f64,
        retry: bool,
        stats: &mut Stats,
    ) -> Result<f64, IntegrateError> {
        let m = self.s.y.len();
        for r in 0..m {
            let f2 = (DD1 * self.z[0][r] + DD2 * self.z[1][r] + DD3 * self.z[2][r]) / h;
            self.err2[r] = f2;
            self.err[r] = f2 + self.s.f[r];
        }
        p.solve_shifted(&mut self.err);
        stats.lu_solves += 1;
        let mut e = self.norm(&self.err, h);
        if !(e < 1.0) && retry && e.is_finite() {
            let t = self.s.t;
            self.ytmp.copy_from(&self.s.y);
            self.ytmp += &self.err;
            p.rhs(t, &self.ytmp, &mut self.err)
                .map_err(sys_err(t, h, "rhs"))?;
            stats.rhs_evaluations += 1;
            self.err += &self.err2;
            p.solve_shifted(&mut self.err);
            stats.lu_solves += 1;
            e = self.norm(&self.err, h);
        }
        Ok(if e.is_finite() {
            e.max(1e-10)
        } else {
            f64::INFINITY
        })
    }
}

impl<P: Problem> Stepper<P> for Radau5 {
    const START_ORDER: i32 = 5;

    fn restart(
        &mut self,
        p: &mut P,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        self.system_changed(p, stats)?;
        self.accepted = 0;
        self.faccon = 1.0;
        self.set_scal(opts);
        Ok(())
    }

    fn step(
        &mut self,
        p: &mut P,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let fixed = opts.fixed_dt();
        let nit = opts.iteration.max_iter();
        let mut h = self.s.h_next.min(opts.h_max);
        let mut rejected = false;
        let mut reason = "step size";
        let (u1, al, be) = self.eig;
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
                if !(p.factor_shifted(u1 / h) && p.factor_shifted_complex(al / h, be / h)) {
                    self.factored_h = f64::NAN;
                    stats.rejected_steps += 1;
                    rejected = true;
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
            let newt = match self.newton(p, h, opts, stats)? {
                Ok(k) => k,
                Err((why, f)) => {
                    stats.rejected_steps += 1;
                    rejected = true;
                    reason = why;
                    if !self.jac_fresh {
                        self.jac_valid = false;
                    } else {
                        h *= f;
                    }
                    continue;
                }
            };
            let err = self.error(p, h, rejected || self.accepted == 0, stats)?;
            let accept = match fixed {
                Some(_) => err.is_finite(),
                None => err < 1.0,
            };
            let fac = SAFETY.min(SAFETY * (1.0 + 2.0 * nit as f64) / (newt + 2 * nit) as f64);
            let mut quot = if err.is_finite() {
                (err.powf(0.25) / fac).clamp(FAC_R, FAC_L)
            } else {
                FAC_L
            };
            if accept {
                if self.accepted > 0 && fixed.is_none() {
                    let gus = (self.h_acc / h) * (err * err / self.err_acc).powf(0.25) / SAFETY;
                    quot = quot.max(gus.clamp(FAC_R, FAC_L));
                }
                self.h_acc = h;
                self.err_acc = err.max(1e-2);
                let t_new = if last { t_end } else { t + h };
                // y₁ = y + Z₃ and the collocation polynomial.
                let (c1m1, c2m1) = (C1 - 1.0, C2 - 1.0);
                self.s.save_prev();
                for r in 0..self.s.y.len() {
                    let (z1, z2, z3) = (self.z[0][r], self.z[1][r], self.z[2][r]);
                    self.s.y[r] = self.s.y_prev[r] + z3;
                    let d1 = (z2 - z3) / c2m1;
                    let ak = (z1 - z2) / (C1 - C2);
                    let a3 = (ak - z1 / C1) / C2;
                    let d2 = (ak - d1) / c1m1;
                    self.cont[0][r] = d1;
                    self.cont[1][r] = d2;
                    self.cont[2][r] = d2 - a3;
                }
                p.rhs(t_new, &self.s.y, &mut self.s.f)
                    .map_err(sys_err(t_new, h, "rhs"))?;
                stats.rhs_evaluations += 1;
                self.s.advance(t_new, h, stats);
                self.h_old = h;
                self.accepted += 1;
                self.set_scal(opts);
                if first_non_finite(self.s.f.as_slice()).is_some() {
                    return Err(IntegrateError::NonFinite {
                        t: t_new,
                        h,
                        what: "derivative",
                        index: first_non_finite(self.s.f.as_slice()).unwrap_or(0),
                    });
                }
                let mut h_new = match fixed {
                    Some(dt) => dt,
                    None => h / quot,
                };
                if rejected {
                    h_new = h_new.min(h);
                }
                h_new = h_new.min(opts.h_max);
                self.jac_fresh = false;
                let qt = h_new / h;
                if self.theta <= THETA_KEEP && (KEEP_MIN..=KEEP_MAX).contains(&qt) {
                    self.s.h_next = h;
                } else {
                    self.s.h_next = h_new;
                }
                if self.theta > THETA_KEEP {
                    self.jac_valid = false;
                }
                return Ok(());
            }
            stats.rejected_steps += 1;
            reason = if err.is_finite() {
                "error test"
            } else {
                "non-finite trial state"
            };
            h = if self.accepted == 0 {
                0.1 * h
            } else {
                h / quot
            };
            rejected = true;
            if !self.jac_fresh {
                self.jac_valid = false;
            }
        }
    }

    fn state(&self) -> &StepState {
        &self.s
    }
    fn state_mut(&mut self) -> &mut StepState {
        &mut self.s
    }

    fn dense(&self, t: f64, out: &mut DVector<f64>) {
        let s = (t - self.s.t) / self.s.h;
        let (c1m1, c2m1) = (C1 - 1.0, C2 - 1.0);
        for r in 0..out.len() {
            out[r] = self.s.y[r]
                + s * (self.cont[0][r]
                    + (s - c2m1) * (self.cont[1][r] + (s - c1m1) * self.cont[2][r]));
        }
    }

    fn system_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError> {
        p.system_changed();
        self.s.refresh_derivative(p, stats)?;
        self.jac_valid = false;
        self.factored_h = f64::NAN;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Radau IIA 5 coefficients `A` (Hairer–Wanner, *ODEs II*, Table
    /// IV.5.6) and the transformation: the row sums of `A` are the nodes,
    /// `T⁻¹ T = I` and `T⁻¹ A⁻¹ T = diag(γ̂, [[α, −β], [β, α]])` with the
    /// eigenvalues of [`eigenvalues`].
    #[test]
    fn transformation_diagonalizes_the_inverse_coefficients() {
        let a = nalgebra::Matrix3::from_fn(|i, j| RADAU_A[i][j]);
        // Row sums are the nodes.
        let c = a * nalgebra::Vector3::repeat(1.0);
        assert!(
            (c[0] - C1).abs() < 1e-15 && (c[1] - C2).abs() < 1e-15 && (c[2] - 1.0).abs() < 1e-15
        );
        let t = nalgebra::Matrix3::from_fn(|i, j| T[i][j]);
        let ti = nalgebra::Matrix3::from_fn(|i, j| TI[i][j]);
        assert!((ti * t - nalgebra::Matrix3::identity()).amax() < 1e-14);
        let ai = a.try_inverse().unwrap();
        let l = ti * ai * t;
        let (u1, al, be) = eigenvalues();
        let expect = nalgebra::Matrix3::new(u1, 0.0, 0.0, 0.0, al, -be, 0.0, be, al);
        assert!((l - expect).amax() < 1e-12, "{l}");
    }
}
