//! ROS34PW2: a Rosenbrock–W method, 4 stages, order 3 with an embedded order-2
//! solution, L-stable, stiffly accurate (J. Rang, L. Angermann, "New
//! Rosenbrock W-methods of order 3 for partial differential algebraic
//! equations of index 1", BIT 45 (2005) 761–787, Table "ROS34PW2").
//!
//! In the `(α, Γ, b, b̂)` form of Hairer–Wanner (*Solving ODEs II*, §IV.7,
//! eq. 7.4'), with `W ≈ ∂f/∂y`:
//!
//! `(I − hγW) kᵢ = h f(t + αᵢh, y + Σⱼ<ᵢ αᵢⱼ kⱼ) + hW Σⱼ<ᵢ γᵢⱼ kⱼ + γᵢ h² ∂f/∂t`,
//! `y₁ = y + Σ bᵢ kᵢ`, error `Σ (bᵢ − b̂ᵢ) kᵢ`,
//!
//! implemented in the transformed variables `uᵢ = Σⱼ≤ᵢ γᵢⱼ kⱼ` (*ODEs II*
//! eq. 7.25), which needs no product with `W`:
//! `(I/(hγ) − W) uᵢ = f(t + αᵢh, y + Σ aᵢⱼ uⱼ) + Σ (cᵢⱼ/h) uⱼ + γᵢ h ∂f/∂t`,
//! `(aᵢⱼ) = (αᵢⱼ) Γ⁻¹`, `(cᵢⱼ) = diag(1/γ) − Γ⁻¹`, `m = b Γ⁻¹`.
//!
//! Because the method is a W-method (order 3 for *any* `W`), the Jacobian is
//! reused across steps (re-evaluated after a rejection or after
//! [`Options::jacobian_max_age`] steps) and the LU of `I/(hγ) − W` is reused
//! while `h` does not change; the controller keeps `h` when it would grow by
//! less than 20 % (as RADAU5 does) so that reuse actually happens.
//! When the problem's Jacobian is a cheap approximation (the mass-matrix
//! form) ROS34PW2 watches it: rejections clustering, the step collapsing or
//! drifting down, or an imminent underflow switch it to the exact Jacobian
//! for a window of accepted steps (see `Choice`), so a poor `W` costs steps,
//! never the run.
//! `∂f/∂t` is a forward difference (one right-hand side per step) unless the
//! system declares itself autonomous. Dense output: cubic Hermite from the
//! step's end values and derivatives (`f(t₁, y₁)` is the next step's first
//! stage, so it costs nothing extra).

// The coefficients are transcribed with all the digits published.
#![allow(clippy::excessive_precision)]

use nalgebra::DVector;

use crate::control::{check_underflow, clip_step, non_finite_trial, rejection_reason, wrms};
use crate::error::{IntegrateError, first_non_finite};
use crate::options::Options;
use crate::problem::{Problem, sys_err};
use crate::solution::Stats;
use crate::state::StepState;
use crate::stepper::Stepper;

const S: usize = 4;
/// Diagonal `γ` of ROS34PW2.
pub(crate) const GAMMA: f64 = 4.3586652150845900e-01;
/// `αᵢⱼ`, strictly lower.
pub(crate) const ALPHA: [[f64; S]; S] = [
    [0.0; 4],
    [8.7173304301691801e-01, 0.0, 0.0, 0.0],
    [8.4457060015369423e-01, -1.1299064236484185e-01, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
];
/// `γᵢⱼ`, lower with `γ` on the diagonal.
pub(crate) const GAMMA_IJ: [[f64; S]; S] = [
    [GAMMA, 0.0, 0.0, 0.0],
    [-8.7173304301691801e-01, GAMMA, 0.0, 0.0],
    [-9.0338057013044082e-01, 5.4180672388095326e-02, GAMMA, 0.0],
    [
        2.4212380706095346e-01,
        -1.2232505839045147e+00,
        5.4526025533510214e-01,
        GAMMA,
    ],
];
/// Weights of the order-3 solution.
pub(crate) const B: [f64; S] = [
    2.4212380706095346e-01,
    -1.2232505839045147e+00,
    1.5452602553351020e+00,
    GAMMA,
];
/// Weights of the embedded order-2 solution.
pub(crate) const BHAT: [f64; S] = [
    3.7810903145819369e-01,
    -9.6042292212423178e-02,
    0.5,
    2.1793326075422950e-01,
];

const SAFETY: f64 = 0.9;
const FAC_MIN: f64 = 0.2;
const FAC_MAX: f64 = 6.0;

/// Transformed coefficients, computed once from the published tableau.
struct Tableau {
    a: [[f64; S]; S],
    c: [[f64; S]; S],
    m: [f64; S],
    me: [f64; S],
    alpha_i: [f64; S],
    gamma_i: [f64; S],
}

impl Tableau {
    fn new() -> Self {
        // Inverse of the lower-triangular Γ by forward substitution.
        let g = GAMMA_IJ;
        let mut gi = [[0.0; S]; S];
        for i in 0..S {
            gi[i][i] = 1.0 / g[i][i];
            for j in (0..i).rev() {
                let mut s = 0.0;
                for k in j..i {
                    s += g[i][k] * gi[k][j];
                }
                gi[i][j] = -s / g[i][i];
            }
        }
        let mut a = [[0.0; S]; S];
        let mut c = [[0.0; S]; S];
        let mut m = [0.0; S];
        let mut me = [0.0; S];
        let mut alpha_i = [0.0; S];
        let mut gamma_i = [0.0; S];
        for i in 0..S {
            for j in 0..S {
                a[i][j] = (0..S).map(|k| ALPHA[i][k] * gi[k][j]).sum();
                c[i][j] = if i == j { 1.0 / g[i][i] } else { 0.0 } - gi[i][j];
                m[j] += B[i] * gi[i][j];
                me[j] += (B[i] - BHAT[i]) * gi[i][j];
            }
            alpha_i[i] = ALPHA[i].iter().sum();
            gamma_i[i] = g[i][..=i].iter().sum();
        }
        Self {
            a,
            c,
            m,
            me,
            alpha_i,
            gamma_i,
        }
    }
}

/// ROS34PW2 state and buffers (allocated once).
pub(crate) struct Rosw34 {
    tab: Tableau,
    s: StepState,
    ft: DVector<f64>,
    ft_valid: bool,
    u: [DVector<f64>; S],
    ynew: DVector<f64>,
    ytmp: DVector<f64>,
    /// Steps since the Jacobian was evaluated; `usize::MAX`: none valid.
    jac_age: usize,
    /// The shift `c = 1/(hγ)` of the current LU (NaN: none).
    lu_shift: f64,
    /// Cheap or exact Jacobian, when the problem offers a cheap one.
    choice: Choice,
}

/// Which Jacobian ROS34PW2 uses when the problem offers a cheap
/// approximation (the mass-matrix form): the cheap one while it works, the
/// exact one after trouble — rejections clustering, the step collapsing or
/// about to underflow, or the step size drifting down — for a window of
/// accepted steps, kept (and the window doubled) while it takes clearly
/// larger steps than the cheap one did, given up otherwise.
#[derive(Clone, Debug)]
struct Choice {
    exact: bool,
    /// Accepted steps left in the exact window, and its length.
    left: usize,
    window: usize,
    /// Outcomes of the last attempts, newest in bit 0 (1: rejected).
    history: u32,
    /// A decaying maximum of the accepted step sizes.
    h_ref: f64,
    /// `Σ ln h` and count of the accepted steps in the current block (cheap
    /// or exact).
    block: (f64, usize),
    /// Mean `ln h` of the cheap steps before the last switch to exact.
    cheap_level: f64,
    /// Mean `ln h` of a cheap block to which a downward drift is compared
    /// (NaN: none yet).
    drift_ref: f64,
    /// Accepted cheap steps before a cluster may trigger again.
    cooldown: usize,
    cooldown_len: usize,
}

/// Trouble: this many rejections among the last [`CLUSTER_OF`] attempts ...
const CLUSTER: u32 = 4;
const CLUSTER_OF: u32 = 8;
/// ... or the step below this fraction of a maximum of the accepted steps
/// that decays by [`H_REF_DECAY`] per accepted step ...
const COLLAPSE: f64 = 1e-2;
const H_REF_DECAY: f64 = 0.95;
/// ... or the mean step of a block of [`DRIFT_BLOCK`] cheap steps below
/// `1/DRIFT` of the reference block's (a gradual collapse).
const DRIFT_BLOCK: usize = 100;
const DRIFT: f64 = 4.0;
/// Accepted steps of the first exact window.
const EXACT_WINDOW: usize = 20;
/// The exact Jacobian is kept when its steps are larger by this factor.
const EXACT_GAIN: f64 = 1.5;
/// Accepted steps between cluster triggers after a probe that did not pay.
const COOLDOWN: usize = 100;

impl Choice {
    fn new() -> Self {
        Self {
            exact: false,
            left: 0,
            window: EXACT_WINDOW,
            history: 0,
            h_ref: 0.0,
            block: (0.0, 0),
            cheap_level: f64::NAN,
            drift_ref: f64::NAN,
            cooldown: 0,
            cooldown_len: COOLDOWN,
        }
    }

    fn rejected(&mut self) {
        self.history = (self.history << 1) | 1;
    }

    fn block_mean(&self) -> f64 {
        if self.block.1 == 0 {
            f64::NAN
        } else {
            self.block.0 / self.block.1 as f64
        }
    }

    /// Records an accepted step of size `h`; returns whether the Jacobian
    /// must be refreshed (the choice changed).
    fn accepted(&mut self, h: f64) -> bool {
        self.history <<= 1;
        self.h_ref = h.max(H_REF_DECAY * self.h_ref);
        self.block.0 += h.ln();
        self.block.1 += 1;
        if self.exact {
            self.left = self.left.saturating_sub(1);
            if self.left > 0 {
                return false;
            }
            let level = self.block_mean();
            self.block = (0.0, 0);
            if level > self.cheap_level + EXACT_GAIN.ln() {
                // It pays: keep it, re-examined after a longer window.
                self.window = self.window.saturating_mul(2);
                self.left = self.window;
                return false;
            }
            self.exact = false;
            self.window = EXACT_WINDOW;
            self.drift_ref = level;
            self.cooldown = self.cooldown_len;
            self.cooldown_len = self.cooldown_len.saturating_mul(2);
            return true;
        }
        self.cooldown = self.cooldown.saturating_sub(1);
        false
    }

    /// Whether the cheap Jacobian is in trouble at step size `h` (`underflow`:
    /// the step is about to fall below the minimum); if so, switches to the
    /// exact one.
    fn trouble(&mut self, h: f64, underflow: bool) -> bool {
        if self.exact {
            return false;
        }
        let mask = (1u32 << CLUSTER_OF) - 1;
        let clustered = self.cooldown == 0 && (self.history & mask).count_ones() >= CLUSTER;
        let collapsed = h < COLLAPSE * self.h_ref;
        let mut drifted = false;
        if self.block.1 >= DRIFT_BLOCK {
            let level = self.block_mean();
            if self.drift_ref.is_nan() {
                self.drift_ref = level;
            }
            drifted = level < self.drift_ref - DRIFT.ln();
            self.block = (0.0, 0);
            if !drifted {
                self.drift_ref = self.drift_ref.max(level);
            }
        }
        if !(clustered || collapsed || drifted || underflow) {
            return false;
        }
        self.cheap_level = if self.block.1 > 0 {
            self.block_mean()
        } else {
            h.ln()
        };
        self.exact = true;
        self.left = self.window;
        self.history = 0;
        self.block = (0.0, 0);
        true
    }
}

impl Rosw34 {
    pub(crate) fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        Self {
            tab: Tableau::new(),
            s: StepState::new(n),
            ft: z.clone(),
            ft_valid: false,
            u: std::array::from_fn(|_| z.clone()),
            ynew: z.clone(),
            ytmp: z,
            jac_age: usize::MAX,
            lu_shift: f64::NAN,
            choice: Choice::new(),
        }
    }

    /// With a cheap Jacobian in trouble at step size `h` (`underflow`: the
    /// step is about to fall below the minimum), switches to the exact one
    /// and returns `true`.
    fn refresh_to_exact<P: Problem>(&mut self, p: &P, h: f64, underflow: bool) -> bool {
        if !p.has_cheap_jacobian() || !self.choice.trouble(h, underflow) {
            return false;
        }
        self.jac_age = usize::MAX;
        true
    }

    fn update_jacobian<P: Problem>(
        &mut self,
        p: &mut P,
        h: f64,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let bad = if self.choice.exact {
            p.update_exact_jacobian(self.s.t, &self.s.y)
        } else {
            p.update_jacobian(self.s.t, &self.s.y)
        }
        .map_err(sys_err(self.s.t, h, "jacobian"))?;
        stats.jacobian_evaluations += 1;
        if let Some(index) = bad {
            return Err(IntegrateError::NonFinite {
                t: self.s.t,
                h,
                what: "Jacobian",
                index,
            });
        }
        self.jac_age = 0;
        self.lu_shift = f64::NAN;
        Ok(())
    }

    /// One trial step; `ynew` gets `y₁`; returns the error norm (∞ if not
    /// finite).
    fn attempt<P: Problem>(
        &mut self,
        p: &mut P,
        h: f64,
        t_new: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<f64, IntegrateError> {
        let t = self.s.t;
        let tab = &self.tab;
        for i in 0..S {
            // Stage argument and right-hand side.
            let rhs_i = if i == 0 {
                self.ytmp.copy_from(&self.s.f);
                &mut self.ytmp
            } else {
                self.ynew.copy_from(&self.s.y);
                for j in 0..i {
                    if tab.a[i][j] != 0.0 {
                        self.ynew.axpy(tab.a[i][j], &self.u[j], 1.0);
                    }
                }
                let ti = if tab.alpha_i[i] == 1.0 {
                    t_new
                } else {
                    t + tab.alpha_i[i] * h
                };
                p.rhs(ti, &self.ynew, &mut self.ytmp)
                    .map_err(sys_err(t, h, "rhs"))?;
                stats.rhs_evaluations += 1;
                &mut self.ytmp
            };
            for j in 0..i {
                if tab.c[i][j] != 0.0 {
                    rhs_i.axpy(tab.c[i][j] / h, &self.u[j], 1.0);
                }
            }
            if self.ft_valid {
                rhs_i.axpy(tab.gamma_i[i] * h, &self.ft, 1.0);
            }
            p.solve_shifted(rhs_i);
            stats.lu_solves += 1;
            self.u[i].copy_from(rhs_i);
        }
        self.ynew.copy_from(&self.s.y);
        self.ytmp.fill(0.0);
        for j in 0..S {
            self.ynew.axpy(tab.m[j], &self.u[j], 1.0);
            self.ytmp.axpy(tab.me[j], &self.u[j], 1.0);
        }
        if first_non_finite(self.ynew.as_slice()).is_some() {
            return Ok(f64::INFINITY);
        }
        let e = wrms(&self.ytmp, &self.s.y, &self.ynew, opts);
        Ok(if e.is_finite() { e } else { f64::INFINITY })
    }
}

impl<P: Problem> Stepper<P> for Rosw34 {
    const START_ORDER: i32 = 3;

    fn restart(
        &mut self,
        p: &mut P,
        _opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        self.system_changed(p, stats)
    }

    fn step(
        &mut self,
        p: &mut P,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let mut h = self.s.h_next.min(opts.h_max);
        let adaptive = opts.is_adaptive();
        let mut rejected_before = false;
        // ∂f/∂t at (t, y), once per step.
        self.ft_valid = false;
        if !p.is_autonomous() {
            let t = self.s.t;
            let delta = (f64::EPSILON * t.abs().max(1e-5)).sqrt();
            p.rhs(t + delta, &self.s.y, &mut self.ft)
                .map_err(sys_err(t, h, "rhs"))?;
            stats.rhs_evaluations += 1;
            self.ft.axpy(-1.0, &self.s.f, 1.0);
            self.ft /= delta;
            if first_non_finite(self.ft.as_slice()).is_none() {
                self.ft_valid = true;
            }
        }
        loop {
            let (hh, last) = clip_step(self.s.t, h, t_end);
            h = hh;
            let reason = if rejected_before {
                "error test"
            } else {
                "step size"
            };
            if let Err(e) = check_underflow(self.s.t, h, opts, reason) {
                if !self.refresh_to_exact(p, h, true) {
                    return Err(e);
                }
                // Retry from the last good step size with the exact Jacobian.
                h = self.choice.h_ref.max(h);
                continue;
            }
            if self.jac_age >= opts.jacobian_max_age.max(1) {
                self.update_jacobian(p, h, stats)?;
            }
            let shift = 1.0 / (h * GAMMA);
            if shift != self.lu_shift {
                stats.factorizations += 1;
                if p.factor_shifted(shift) {
                    self.lu_shift = shift;
                } else {
                    self.lu_shift = f64::NAN;
                    if self.jac_age != 0 {
                        self.jac_age = usize::MAX;
                    } else if !adaptive {
                        return Err(IntegrateError::SingularMatrix {
                            t: self.s.t,
                            h,
                            what: "I/(hγ) − J",
                        });
                    } else {
                        h *= 0.5;
                    }
                    stats.rejected_steps += 1;
                    rejected_before = true;
                    continue;
                }
            }
            let t_new = if last { t_end } else { self.s.t + h };
            let err = self.attempt(p, h, t_new, opts, stats)?;
            let accept = if adaptive {
                err <= 1.0
            } else {
                err.is_finite()
            };
            if !adaptive && !accept {
                return Err(non_finite_trial(&self.ynew, t_new, h));
            }
            if accept {
                // Derivative at the new point (next step's first stage).
                let s = &mut self.s;
                std::mem::swap(&mut s.f_prev, &mut s.f);
                p.rhs(t_new, &self.ynew, &mut s.f)
                    .map_err(sys_err(t_new, h, "rhs"))?;
                stats.rhs_evaluations += 1;
                if first_non_finite(s.f.as_slice()).is_some() && adaptive {
                    // Treat like a non-finite trial: reject and shrink.
                    std::mem::swap(&mut s.f_prev, &mut s.f);
                    stats.rejected_steps += 1;
                    rejected_before = true;
                    h *= FAC_MIN;
                    check_underflow(s.t, h, opts, "non-finite derivative")?;
                    continue;
                }
                s.accept(&mut self.ynew, t_new, h, stats);
                self.jac_age = self.jac_age.saturating_add(1);
                if self.choice.accepted(h) {
                    self.jac_age = usize::MAX;
                }
                if !self.choice.exact && p.has_cheap_jacobian() && self.choice.trouble(h, false) {
                    // A drift seen at the end of a block.
                    self.jac_age = usize::MAX;
                }
                self.s.h_next = if adaptive {
                    let fac = (SAFETY * err.max(1e-300).powf(-1.0 / 3.0)).clamp(FAC_MIN, FAC_MAX);
                    let fac = if rejected_before { fac.min(1.0) } else { fac };
                    // Keep h (and the LU) for small increases.
                    if (1.0..=1.2).contains(&fac) {
                        h
                    } else {
                        h * fac
                    }
                } else {
                    opts.fixed_dt().unwrap_or(h)
                };
                return Ok(());
            }
            stats.rejected_steps += 1;
            rejected_before = true;
            self.choice.rejected();
            let reason = rejection_reason(err);
            if self.jac_age != 0 {
                // A stale W may be the cause: refresh it before shrinking much.
                self.jac_age = usize::MAX;
            }
            let fac = if err.is_finite() {
                (SAFETY * err.powf(-1.0 / 3.0)).clamp(FAC_MIN, 1.0)
            } else {
                FAC_MIN
            };
            h *= fac;
            if self.refresh_to_exact(p, h, false) {
                continue;
            }
            if let Err(e) = check_underflow(self.s.t, h, opts, reason) {
                if !self.refresh_to_exact(p, h, true) {
                    return Err(e);
                }
                h = self.choice.h_ref.max(h);
            }
        }
    }

    fn state(&self) -> &StepState {
        &self.s
    }
    fn state_mut(&mut self) -> &mut StepState {
        &mut self.s
    }
    fn system_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError> {
        p.system_changed();
        self.s.refresh_derivative(p, stats)?;
        self.jac_age = usize::MAX;
        self.lu_shift = f64::NAN;
        self.choice = Choice::new();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Order conditions of a Rosenbrock method up to order 3 (Hairer–Wanner,
    /// *ODEs II*, Table IV.7.1) with `βᵢⱼ = αᵢⱼ + γᵢⱼ`, and order 2 for `b̂`.
    #[test]
    fn tableau_satisfies_order_conditions() {
        let alpha_i: Vec<f64> = ALPHA.iter().map(|r| r.iter().sum()).collect();
        let beta = |i: usize, j: usize| ALPHA[i][j] + GAMMA_IJ[i][j];
        let beta_p: Vec<f64> = (0..S).map(|i| (0..i).map(|j| beta(i, j)).sum()).collect();
        let g = GAMMA;
        let dot = |w: &[f64; S], v: &dyn Fn(usize) -> f64| (0..S).map(|i| w[i] * v(i)).sum::<f64>();
        let tol = 1e-14;
        for w in [&B, &BHAT] {
            assert!((dot(w, &|_| 1.0) - 1.0).abs() < tol);
            assert!((dot(w, &|i| beta_p[i]) - (0.5 - g)).abs() < tol);
        }
        assert!((dot(&B, &|i| alpha_i[i] * alpha_i[i]) - 1.0 / 3.0).abs() < tol);
        let bb: f64 = (0..S)
            .map(|i| B[i] * (0..i).map(|k| beta(i, k) * beta_p[k]).sum::<f64>())
            .sum();
        assert!((bb - (1.0 / 6.0 - g + g * g)).abs() < tol);
        // Stiffly accurate: b = last row of β plus γ on the diagonal.
        for j in 0..S {
            assert!((B[j] - (ALPHA[S - 1][j] + GAMMA_IJ[S - 1][j])).abs() < tol);
        }
    }
}
