//! Dormand–Prince 5(4) (J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6
//! (1980) 19–26), as in Hairer's DOPRI5 (Hairer–Nørsett–Wanner, *Solving
//! ODEs I*, 2nd ed., §II.5 Table 5.2, §II.4 step control, §II.6 dense
//! output):
//!
//! * 7 stages, FSAL (`k7 = f(t₁, y₁)` is the next step's `k1`): 6 right-hand
//!   sides per accepted step; the 5th-order solution is propagated.
//! * Error `err = ‖h Σ eᵢ kᵢ‖` (weighted RMS, weights `atol + rtol·max(|y₀|,
//!   |y₁|)`), `e = b − b̂`.
//! * PI controller (Gustafsson; Hairer's `β = 0.04`):
//!   `h_new = h · clamp(0.9 · err^(−(0.2 − 0.75β)) · err_prev^β, 1/10, 5)`;
//!   after a rejection the step may not grow.
//! * Dense output of order 4 with Shampine's coefficients `d₁…d₇`.

use nalgebra::DVector;

use crate::control::{check_underflow, clip_step, non_finite_trial, rejection_reason, wrms};
use crate::error::{IntegrateError, first_non_finite};
use crate::options::{Options, StepControl};
use crate::problem::{Problem, sys_err};
use crate::solution::Stats;
use crate::state::StepState;
use crate::stepper::Stepper;

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

const SAFETY: f64 = 0.9;
const BETA: f64 = 0.04;
const FAC_MIN: f64 = 0.1; // smallest h_new / h
const FAC_MAX: f64 = 5.0; // largest h_new / h

/// DOPRI5 state and buffers (allocated once).
pub(crate) struct Dopri5 {
    /// `f` is the first stage `k1` (FSAL: the last stage of the step before).
    s: StepState,
    err_prev: f64,
    /// Stages `k2..k7`: `k[0]` is `k2`, …, `k[5]` is `k7`.
    k: [DVector<f64>; 6],
    ynew: DVector<f64>,
    ytmp: DVector<f64>,
    /// Dense-output coefficients of the last step (`rcont1..5` of DOPRI5).
    cont: [DVector<f64>; 5],
}

impl Dopri5 {
    pub(crate) fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        Self {
            s: StepState::new(n),
            err_prev: 1e-4,
            k: std::array::from_fn(|_| z.clone()),
            ynew: z.clone(),
            ytmp: z.clone(),
            cont: std::array::from_fn(|_| z.clone()),
        }
    }

    /// `ytmp = y + h Σ a_j k_{j+1}` (`j` = 0 is `k1 = f`).
    fn stage_arg(&mut self, h: f64, coef: &[(usize, f64)]) {
        self.ytmp.copy_from(&self.s.y);
        for &(j, a) in coef {
            let kj = if j == 0 { &self.s.f } else { &self.k[j - 1] };
            self.ytmp.axpy(h * a, kj, 1.0);
        }
    }

    /// Tries a step of size `h`; leaves `y₁` in `ynew`, `f(t+h, y₁)` in `k[5]`;
    /// returns the error norm (∞ if the trial is not finite).
    fn attempt<P: Problem>(
        &mut self,
        p: &mut P,
        h: f64,
        t_new: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<f64, IntegrateError> {
        let t = self.s.t;
        let err = |w| sys_err(t, h, w);
        let stages: [(f64, &[(usize, f64)]); 5] = [
            (C2, &[(0, A21)]),
            (C3, &[(0, A31), (1, A32)]),
            (C4, &[(0, A41), (1, A42), (2, A43)]),
            (C5, &[(0, A51), (1, A52), (2, A53), (3, A54)]),
            (1.0, &[(0, A61), (1, A62), (2, A63), (3, A64), (4, A65)]),
        ];
        for (s, (c, coef)) in stages.iter().enumerate() {
            self.stage_arg(h, coef);
            let (t_s, dst) = (if s == 4 { t_new } else { t + c * h }, s);
            let (ytmp, k) = (&self.ytmp, &mut self.k[dst]);
            p.rhs(t_s, ytmp, k).map_err(err("rhs"))?;
        }
        self.stage_arg(h, &[(0, A71), (2, A73), (3, A74), (4, A75), (5, A76)]);
        std::mem::swap(&mut self.ynew, &mut self.ytmp);
        p.rhs(t_new, &self.ynew, &mut self.k[5])
            .map_err(err("rhs"))?;
        stats.rhs_evaluations += 6;
        // Error estimate into ytmp.
        let n = self.s.y.len();
        let (k1, k) = (&self.s.f, &self.k);
        for i in 0..n {
            self.ytmp[i] = h
                * (E1 * k1[i]
                    + E3 * k[1][i]
                    + E4 * k[2][i]
                    + E5 * k[3][i]
                    + E6 * k[4][i]
                    + E7 * k[5][i]);
        }
        if first_non_finite(self.ynew.as_slice()).is_some()
            || first_non_finite(self.k[5].as_slice()).is_some()
        {
            return Ok(f64::INFINITY);
        }
        let e = wrms(&self.ytmp, &self.s.y, &self.ynew, opts);
        Ok(if e.is_finite() { e } else { f64::INFINITY })
    }
}

impl<P: Problem> Stepper<P> for Dopri5 {
    const START_ORDER: i32 = 5;

    fn restart(
        &mut self,
        p: &mut P,
        _opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        self.err_prev = 1e-4;
        self.s.refresh_derivative(p, stats)
    }

    fn step(
        &mut self,
        p: &mut P,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let mut h = self.s.h_next.min(opts.h_max);
        let mut rejected_before = false;
        loop {
            let (hh, last) = clip_step(self.s.t, h, t_end);
            h = hh;
            check_underflow(self.s.t, h, opts, "error test")?;
            let t_new = if last { t_end } else { self.s.t + h };
            let err = self.attempt(p, h, t_new, opts, stats)?;
            if let StepControl::Fixed(dt) = opts.step {
                if !err.is_finite() {
                    return Err(non_finite_trial(&self.ynew, t_new, h));
                }
                self.accept(h, t_new, stats);
                self.s.h_next = dt;
                return Ok(());
            }
            if err <= 1.0 {
                // PI controller.
                let fac11 = err.max(1e-300).powf(0.2 - 0.75 * BETA);
                let mut fac = fac11 / self.err_prev.powf(BETA) / SAFETY;
                fac = fac.clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                let mut h_new = h / fac;
                if rejected_before {
                    h_new = h_new.min(h);
                }
                self.err_prev = err.max(1e-4);
                self.accept(h, t_new, stats);
                self.s.h_next = h_new.min(opts.h_max);
                return Ok(());
            }
            stats.rejected_steps += 1;
            rejected_before = true;
            let fac = if err.is_finite() {
                (err.powf(0.2 - 0.75 * BETA) / SAFETY).min(1.0 / FAC_MIN)
            } else {
                1.0 / FAC_MIN
            };
            h /= fac;
            check_underflow(self.s.t, h, opts, rejection_reason(err))?;
        }
    }

    fn state(&self) -> &StepState {
        &self.s
    }
    fn state_mut(&mut self) -> &mut StepState {
        &mut self.s
    }
    fn dense(&self, t: f64, out: &mut DVector<f64>) {
        let th = (t - self.s.t_prev) / self.s.h;
        let th1 = 1.0 - th;
        let [r1, r2, r3, r4, r5] = &self.cont;
        for i in 0..out.len() {
            out[i] = r1[i] + th * (r2[i] + th1 * (r3[i] + th * (r4[i] + th1 * r5[i])));
        }
    }
    fn system_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError> {
        self.s.refresh_derivative(p, stats)
    }
}

impl Dopri5 {
    /// Accepts the trial in `ynew`/`k[5]`: dense coefficients, FSAL shift
    /// (`k7` becomes the next `k1 = f`).
    fn accept(&mut self, h: f64, t_new: f64, stats: &mut Stats) {
        let n = self.s.y.len();
        let (y, k1, k) = (&self.s.y, &self.s.f, &self.k);
        for i in 0..n {
            let y0 = y[i];
            let y1 = self.ynew[i];
            let ydiff = y1 - y0;
            let bspl = h * k1[i] - ydiff;
            self.cont[0][i] = y0;
            self.cont[1][i] = ydiff;
            self.cont[2][i] = bspl;
            self.cont[3][i] = ydiff - h * k[5][i] - bspl;
            self.cont[4][i] = h
                * (D1 * k1[i]
                    + D3 * k[1][i]
                    + D4 * k[2][i]
                    + D5 * k[3][i]
                    + D6 * k[4][i]
                    + D7 * k[5][i]);
        }
        std::mem::swap(&mut self.s.f_prev, &mut self.s.f);
        std::mem::swap(&mut self.s.f, &mut self.k[5]);
        self.s.accept(&mut self.ynew, t_new, h, stats);
    }
}
