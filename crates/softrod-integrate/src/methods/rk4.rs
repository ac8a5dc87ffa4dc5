//! Classical fixed-step Runge–Kutta of order 4 (Kutta 1901; Hairer–Nørsett–
//! Wanner, *ODEs I*, Table II.1.2):
//!
//! `k1 = f(t, y)`, `k2 = f(t + h/2, y + h/2·k1)`, `k3 = f(t + h/2, y + h/2·k2)`,
//! `k4 = f(t + h, y + h·k3)`, `y₁ = y + h/6·(k1 + 2k2 + 2k3 + k4)`.
//!
//! `f(t₁, y₁)` is evaluated at the end of each step (it is the next step's
//! `k1`, so 4 evaluations per step) and gives the cubic Hermite dense output.

use nalgebra::DVector;

use crate::control::{check_finite, clip_step};
use crate::error::IntegrateError;
use crate::options::Options;
use crate::problem::{Problem, sys_err};
use crate::solution::Stats;
use crate::state::StepState;
use crate::stepper::Stepper;

/// RK4 state and buffers (allocated once).
pub(crate) struct Rk4 {
    s: StepState,
    k2: DVector<f64>,
    k3: DVector<f64>,
    ytmp: DVector<f64>,
}

impl Rk4 {
    pub(crate) fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        Self {
            s: StepState::new(n),
            k2: z.clone(),
            k3: z.clone(),
            ytmp: z,
        }
    }
}

impl<P: Problem> Stepper<P> for Rk4 {
    /// Unused: RK4 has fixed steps only (the first is `dt`).
    const START_ORDER: i32 = 4;

    fn restart(
        &mut self,
        p: &mut P,
        _opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        self.s.refresh_derivative(p, stats)
    }

    fn step(
        &mut self,
        p: &mut P,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        // Options::validate allows RK4 fixed steps only.
        let dt = opts.fixed_dt().unwrap_or(f64::INFINITY).min(opts.h_max);
        let t = self.s.t;
        let (h, last) = clip_step(t, dt, t_end);
        let err = |what| sys_err(t, h, what);
        let s = &mut self.s;
        let (y, f) = (&s.y, &s.f);
        // k2
        self.ytmp.copy_from(y);
        self.ytmp.axpy(0.5 * h, f, 1.0);
        p.rhs(t + 0.5 * h, &self.ytmp, &mut self.k2)
            .map_err(err("rhs"))?;
        // k3
        self.ytmp.copy_from(y);
        self.ytmp.axpy(0.5 * h, &self.k2, 1.0);
        p.rhs(t + 0.5 * h, &self.ytmp, &mut self.k3)
            .map_err(err("rhs"))?;
        // k4 (into f_prev as scratch)
        self.ytmp.copy_from(y);
        self.ytmp.axpy(h, &self.k3, 1.0);
        p.rhs(t + h, &self.ytmp, &mut s.f_prev)
            .map_err(err("rhs"))?;
        // y1 = y + h/6 (k1 + 2 k2 + 2 k3 + k4), into ytmp
        for i in 0..y.len() {
            self.ytmp[i] =
                y[i] + h / 6.0 * (f[i] + 2.0 * self.k2[i] + 2.0 * self.k3[i] + s.f_prev[i]);
        }
        stats.rhs_evaluations += 3;
        let t_new = if last { t_end } else { t + h };
        check_finite(&self.ytmp, t_new, h, "state")?;
        // Shift: prev <- current, current <- new; then f at the new point.
        std::mem::swap(&mut s.f_prev, &mut s.f);
        s.accept(&mut self.ytmp, t_new, h, stats);
        s.refresh_derivative(p, stats)
    }

    fn state(&self) -> &StepState {
        &self.s
    }
    fn state_mut(&mut self) -> &mut StepState {
        &mut self.s
    }
    fn system_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError> {
        self.s.refresh_derivative(p, stats)
    }
}
