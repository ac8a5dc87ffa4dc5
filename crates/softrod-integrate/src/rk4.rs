//! Classical fixed-step Runge–Kutta of order 4 (Kutta 1901; Hairer–Nørsett–
//! Wanner, *ODEs I*, Table II.1.2):
//!
//! `k1 = f(t, y)`, `k2 = f(t + h/2, y + h/2·k1)`, `k3 = f(t + h/2, y + h/2·k2)`,
//! `k4 = f(t + h, y + h·k3)`, `y₁ = y + h/6·(k1 + 2k2 + 2k3 + k4)`.
//!
//! `f(t₁, y₁)` is evaluated at the end of each step (it is the next step's
//! `k1`, so 4 evaluations per step) and gives the cubic Hermite dense output.

use nalgebra::DVector;

use crate::driver::{Stepper, hermite};
use crate::error::{IntegrateError, first_non_finite};
use crate::options::{Options, Stats};
use crate::system::{Problem, sys_err};

/// RK4 state and buffers (allocated once).
pub(crate) struct Rk4 {
    t: f64,
    t_prev: f64,
    h: f64,
    y: DVector<f64>,
    f: DVector<f64>,
    y_prev: DVector<f64>,
    f_prev: DVector<f64>,
    k2: DVector<f64>,
    k3: DVector<f64>,
    ytmp: DVector<f64>,
}

impl Rk4 {
    pub(crate) fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        Self {
            t: 0.0,
            t_prev: 0.0,
            h: 0.0,
            y: z.clone(),
            f: z.clone(),
            y_prev: z.clone(),
            f_prev: z.clone(),
            k2: z.clone(),
            k3: z.clone(),
            ytmp: z,
        }
    }
}

impl<P: Problem> Stepper<P> for Rk4 {
    fn init(
        &mut self,
        p: &mut P,
        t0: f64,
        y0: &DVector<f64>,
        _t1: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        if opts.dt.is_none() {
            return Err(IntegrateError::InvalidInput {
                what: "RK4 needs a fixed step: set Options::dt".into(),
            });
        }
        self.t = t0;
        self.t_prev = t0;
        self.y.copy_from(y0);
        self.system_changed(p, stats)
    }

    fn step(
        &mut self,
        p: &mut P,
        t_end: f64,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<(), IntegrateError> {
        let dt = opts.dt.unwrap_or(f64::INFINITY).min(opts.h_max);
        let t = self.t;
        let (h, last) = crate::driver::clip_step(t, dt, t_end);
        let err = |what| sys_err(t, h, what);
        let (y, f) = (&self.y, &self.f);
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
        p.rhs(t + h, &self.ytmp, &mut self.f_prev)
            .map_err(err("rhs"))?;
        // y1 = y + h/6 (k1 + 2 k2 + 2 k3 + k4), into ytmp
        for i in 0..y.len() {
            self.ytmp[i] =
                y[i] + h / 6.0 * (f[i] + 2.0 * self.k2[i] + 2.0 * self.k3[i] + self.f_prev[i]);
        }
        stats.rhs_evaluations += 3;
        let t_new = if last { t_end } else { t + h };
        if let Some(index) = first_non_finite(self.ytmp.as_slice()) {
            return Err(IntegrateError::NonFinite {
                t: t_new,
                h,
                what: "state",
                index,
            });
        }
        // Shift: prev <- current, current <- new.
        std::mem::swap(&mut self.y_prev, &mut self.y);
        std::mem::swap(&mut self.y, &mut self.ytmp);
        std::mem::swap(&mut self.f_prev, &mut self.f);
        self.t_prev = t;
        self.t = t_new;
        self.h = h;
        p.rhs(self.t, &self.y, &mut self.f)
            .map_err(sys_err(self.t, h, "rhs"))?;
        stats.rhs_evaluations += 1;
        stats.steps += 1;
        if let Some(index) = first_non_finite(self.f.as_slice()) {
            return Err(IntegrateError::NonFinite {
                t: self.t,
                h,
                what: "derivative",
                index,
            });
        }
        Ok(())
    }

    fn t(&self) -> f64 {
        self.t
    }
    fn t_prev(&self) -> f64 {
        self.t_prev
    }
    fn y(&self) -> &DVector<f64> {
        &self.y
    }
    fn h_last(&self) -> f64 {
        self.h
    }
    fn dense(&self, t: f64, out: &mut DVector<f64>) {
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
    fn system_changed(&mut self, p: &mut P, stats: &mut Stats) -> Result<(), IntegrateError> {
        p.rhs(self.t, &self.y, &mut self.f)
            .map_err(sys_err(self.t, self.h, "rhs"))?;
        stats.rhs_evaluations += 1;
        if let Some(index) = first_non_finite(self.f.as_slice()) {
            return Err(IntegrateError::NonFinite {
                t: self.t,
                h: self.h,
                what: "derivative",
                index,
            });
        }
        Ok(())
    }
}
