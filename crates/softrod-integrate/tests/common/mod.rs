//! Test problems with known solutions.
#![allow(dead_code)]

use std::convert::Infallible;

use nalgebra::{DMatrix, DVector};
use softrod_integrate::{OdeSystem, SecondOrderSystem};

/// `q̈ = −K q − D q̇` (unit mass matrix), `n = 2`: a matrix-form linear
/// oscillator with coupled modes. `D = 0` is undamped.
#[derive(Clone)]
pub struct Linear {
    pub k: DMatrix<f64>,
    pub d: DMatrix<f64>,
    /// Count `accel` calls (to check the statistics).
    pub calls: usize,
}

impl Linear {
    /// Stiffness eigenvalues ω² ≈ 2.4 and 5.6 (periods ≈ 4 and 2.7).
    pub fn undamped() -> Self {
        let k = DMatrix::from_row_slice(2, 2, &[4.0, 1.5, 1.5, 4.0]);
        Self {
            d: DMatrix::zeros(2, 2),
            k,
            calls: 0,
        }
    }

    /// Rayleigh damping `D = 0.1 K + 0.2 I`.
    pub fn damped() -> Self {
        let mut s = Self::undamped();
        s.d = &s.k * 0.1 + DMatrix::identity(2, 2) * 0.2;
        s
    }

    /// First-order matrix `A` with `y' = A y`, `y = (q, q̇)`.
    pub fn a(&self) -> DMatrix<f64> {
        let mut a = DMatrix::zeros(4, 4);
        a.view_mut((0, 2), (2, 2)).fill_with_identity();
        a.view_mut((2, 0), (2, 2)).copy_from(&(-&self.k));
        a.view_mut((2, 2), (2, 2)).copy_from(&(-&self.d));
        a
    }

    /// Exact `y(t) = exp(A t) y0`.
    pub fn exact(&self, t: f64, y0: &DVector<f64>) -> DVector<f64> {
        (self.a() * t).exp() * y0
    }

    pub fn q0() -> DVector<f64> {
        dv(&[1.0, -0.5])
    }
    pub fn qd0() -> DVector<f64> {
        dv(&[0.3, 0.8])
    }
    pub fn y0() -> DVector<f64> {
        dv(&[1.0, -0.5, 0.3, 0.8])
    }
}

impl SecondOrderSystem for Linear {
    type Error = Infallible;
    fn dim(&self) -> usize {
        2
    }
    fn accel(
        &mut self,
        _t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Infallible> {
        self.calls += 1;
        qdd.gemv(-1.0, &self.k, q, 0.0);
        qdd.gemv(-1.0, &self.d, qd, 1.0);
        Ok(())
    }
    fn jacobians(
        &mut self,
        _t: f64,
        _q: &DVector<f64>,
        _qd: &DVector<f64>,
        dq: &mut DMatrix<f64>,
        dqd: &mut DMatrix<f64>,
    ) -> Result<(), Infallible> {
        dq.copy_from(&(-&self.k));
        dqd.copy_from(&(-&self.d));
        Ok(())
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// The same oscillator as a first-order system (`y' = A y`), using the
/// default finite-difference Jacobian.
pub struct LinearFirstOrder(pub DMatrix<f64>);

impl OdeSystem for LinearFirstOrder {
    type Error = Infallible;
    fn dim(&self) -> usize {
        self.0.nrows()
    }
    fn rhs(&mut self, _t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), Infallible> {
        dy.gemv(1.0, &self.0, y, 0.0);
        Ok(())
    }
}

/// Forced oscillator `q̈ = −ω² q + cos(Ω t)`, `q(0) = 0`, `q̇(0) = 0`;
/// non-autonomous (tests the Rosenbrock `∂f/∂t` term).
pub struct Forced {
    pub w: f64,
    pub big_w: f64,
}

impl Forced {
    /// `q(t) = (cos Ωt − cos ωt) / (ω² − Ω²)`.
    pub fn exact(&self, t: f64) -> (f64, f64) {
        let (w, o) = (self.w, self.big_w);
        let c = 1.0 / (w * w - o * o);
        (
            c * ((o * t).cos() - (w * t).cos()),
            c * (-o * (o * t).sin() + w * (w * t).sin()),
        )
    }
}

impl SecondOrderSystem for Forced {
    type Error = Infallible;
    fn dim(&self) -> usize {
        1
    }
    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        _qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Infallible> {
        qdd[0] = -self.w * self.w * q[0] + (self.big_w * t).cos();
        Ok(())
    }
}

/// Van der Pol `y₁' = y₂`, `y₂' = μ(1 − y₁²) y₂ − y₁` (`y'' − μ(1 − y²) y' + y
/// = 0`, relaxation period ≈ (3 − 2 ln 2) μ for large μ), analytic Jacobian.
pub struct VanDerPol {
    pub mu: f64,
}

impl OdeSystem for VanDerPol {
    type Error = Infallible;
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), Infallible> {
        dy[0] = y[1];
        dy[1] = self.mu * (1.0 - y[0] * y[0]) * y[1] - y[0];
        Ok(())
    }
    fn jacobian(
        &mut self,
        _t: f64,
        y: &DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<(), Infallible> {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -2.0 * self.mu * y[0] * y[1] - 1.0;
        jac[(1, 1)] = self.mu * (1.0 - y[0] * y[0]);
        Ok(())
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// Robertson's chemical kinetics (Hairer–Wanner, *ODEs II*, §IV.1, eq. 1.3).
pub struct Robertson;

impl OdeSystem for Robertson {
    type Error = Infallible;
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, _t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), Infallible> {
        let r1 = 0.04 * y[0];
        let r2 = 1e4 * y[1] * y[2];
        let r3 = 3e7 * y[1] * y[1];
        dy[0] = -r1 + r2;
        dy[1] = r1 - r2 - r3;
        dy[2] = r3;
        Ok(())
    }
    fn is_autonomous(&self) -> bool {
        true
    }
}

/// Max-norm distance.
pub fn dist(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax()
}

/// A vector from a slice.
pub fn dv(x: &[f64]) -> DVector<f64> {
    DVector::from_column_slice(x)
}
