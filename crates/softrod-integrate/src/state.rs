//! The state every stepper keeps between steps, and the bookkeeping they share:
//! current and previous time, state and derivative, the last step size.

use nalgebra::DVector;

use crate::control::{check_finite, wrms};
use crate::error::IntegrateError;
use crate::options::{Options, StepControl};
use crate::problem::{Problem, sys_err};
use crate::solution::Stats;

/// Time, state and derivative at the end (`t`, `y`, `f`) and the start
/// (`t_prev`, `y_prev`, `f_prev`) of the last accepted step of size `h`
/// (first-order form, `f = y'`), and the step to try next.
pub(crate) struct StepState {
    pub(crate) t: f64,
    pub(crate) t_prev: f64,
    pub(crate) h: f64,
    /// The step the method tries next (its controller's proposal; the
    /// current step of a fixed-step run).
    pub(crate) h_next: f64,
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
            h_next: 0.0,
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
            (self.t_prev, &self.y_prev, &self.f_prev),
            (self.t, &self.y, &self.f),
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

    /// The first step of a method of order `order` from the start
    /// `(t, y, f)`: the fixed `dt` or the given `h0` (at most `h_max`), else
    /// [`initial_step`] (one right-hand side).
    pub(crate) fn first_step<P: Problem>(
        &self,
        p: &mut P,
        order: i32,
        opts: &Options,
        stats: &mut Stats,
    ) -> Result<f64, IntegrateError> {
        match opts.step {
            StepControl::Fixed(h) | StepControl::Adaptive { h0: Some(h) } => Ok(h.min(opts.h_max)),
            StepControl::Adaptive { h0: None } => initial_step(p, self, order, opts, stats),
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

/// Starting step of an adaptive method of order `order` from the start
/// `(t, y, f)` of `s` (Hairer–Nørsett–Wanner, *ODEs I*, §II.4, "Starting
/// step size"); one right-hand side, into scratch allocated here (once per
/// run).
// Negated comparison: a NaN derivative norm takes the fallback step.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn initial_step<P: Problem>(
    p: &mut P,
    s: &StepState,
    order: i32,
    opts: &Options,
    stats: &mut Stats,
) -> Result<f64, IntegrateError> {
    let (t0, y0, f0) = (s.t, &s.y, &s.f);
    let (y1, f1) = (&mut y0.clone(), &mut DVector::zeros(y0.len()));
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
    p.rhs(t0 + h0, y1, f1).map_err(sys_err(t0, h0, "rhs"))?;
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

impl StepState {
    /// Quintic Hermite dense output on `[t_prev, t]` for a second-order
    /// state `y = (q, q̇)`, `f = (q̇, q̈)` (dim `2n` each): `q` from its
    /// values, first and second derivatives at both ends (exact for quintic
    /// polynomials, error `O(h⁶)`), `q̇` the interpolant's derivative
    /// (`O(h⁵)`).
    pub(crate) fn quintic_dense(&self, t: f64, out: &mut DVector<f64>) {
        let n = out.len() / 2;
        let h = self.t - self.t_prev;
        let th = (t - self.t_prev) / h;
        let (t2, t3) = (th * th, th * th * th);
        let (t4, t5) = (t3 * th, t3 * t2);
        // Basis on [0, 1]: value, derivative and second derivative at 0 and 1.
        let h0 = 1.0 - 10.0 * t3 + 15.0 * t4 - 6.0 * t5;
        let h1 = th - 6.0 * t3 + 8.0 * t4 - 3.0 * t5;
        let h2 = 0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5;
        let h3 = 0.5 * t3 - t4 + 0.5 * t5;
        let h4 = -4.0 * t3 + 7.0 * t4 - 3.0 * t5;
        let h5 = 10.0 * t3 - 15.0 * t4 + 6.0 * t5;
        // Their θ-derivatives.
        let d0 = -30.0 * t2 + 60.0 * t3 - 30.0 * t4;
        let d1 = 1.0 - 18.0 * t2 + 32.0 * t3 - 15.0 * t4;
        let d2 = th - 4.5 * t2 + 6.0 * t3 - 2.5 * t4;
        let d3 = 1.5 * t2 - 4.0 * t3 + 2.5 * t4;
        let d4 = -12.0 * t2 + 28.0 * t3 - 15.0 * t4;
        let d5 = -d0;
        let (ya, fa, yb, fb) = (&self.y_prev, &self.f_prev, &self.y, &self.f);
        for i in 0..n {
            let (q0, v0, a0) = (ya[i], fa[i], fa[n + i]);
            let (q1, v1, a1) = (yb[i], fb[i], fb[n + i]);
            out[i] = h0 * q0 + h5 * q1 + h * (h1 * v0 + h4 * v1) + h * h * (h2 * a0 + h3 * a1);
            out[n + i] = (d0 * q0 + d5 * q1) / h + d1 * v0 + d4 * v1 + h * (d2 * a0 + d3 * a1);
        }
    }
}

/// A point of a trajectory: time, value and derivative.
type Node<'a> = (f64, &'a DVector<f64>, &'a DVector<f64>);

/// Cubic Hermite interpolation at `t` on `[ta, tb]` from the values and
/// derivatives at both ends (Hairer–Nørsett–Wanner, *ODEs I*, eq. II.6.7).
pub(crate) fn hermite(
    (ta, ya, fa): Node<'_>,
    (tb, yb, fb): Node<'_>,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quintic_hermite_reproduces_quintics() {
        // q = t⁵ − 2t³ + t, on [0.5, 1.3] (n = 1).
        let q = |t: f64| t.powi(5) - 2.0 * t.powi(3) + t;
        let v = |t: f64| 5.0 * t.powi(4) - 6.0 * t * t + 1.0;
        let a = |t: f64| 20.0 * t.powi(3) - 12.0 * t;
        let mut s = StepState::new(2);
        let (ta, tb) = (0.5, 1.3);
        s.t_prev = ta;
        s.t = tb;
        s.y_prev = DVector::from_row_slice(&[q(ta), v(ta)]);
        s.f_prev = DVector::from_row_slice(&[v(ta), a(ta)]);
        s.y = DVector::from_row_slice(&[q(tb), v(tb)]);
        s.f = DVector::from_row_slice(&[v(tb), a(tb)]);
        let mut out = DVector::zeros(2);
        for t in [0.5, 0.61, 0.9, 1.25, 1.3] {
            s.quintic_dense(t, &mut out);
            assert!((out[0] - q(t)).abs() < 1e-14, "q({t})");
            assert!((out[1] - v(t)).abs() < 1e-13, "v({t})");
        }
    }

    #[test]
    fn hermite_reproduces_cubics() {
        // y = t³ − 2t, y' = 3t² − 2 on [0.5, 1.5].
        let y = |t: f64| DVector::from_element(1, t * t * t - 2.0 * t);
        let f = |t: f64| DVector::from_element(1, 3.0 * t * t - 2.0);
        let mut out = DVector::zeros(1);
        hermite(
            (0.5, &y(0.5), &f(0.5)),
            (1.5, &y(1.5), &f(1.5)),
            0.8,
            &mut out,
        );
        assert!((out[0] - y(0.8)[0]).abs() < 1e-14);
    }
}
