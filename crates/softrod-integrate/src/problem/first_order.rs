//! A first-order system `y' = f(t, y)` as a [`Problem`]: its dense
//! Jacobian and the LU of `c·I − J` (real or complex shift).

use nalgebra::{Complex, DMatrix, DVector};

use super::Problem;
use crate::error::SystemError;
use crate::linalg::{ComplexLu, DenseLu};
use crate::system::OdeSystem;

/// A first-order system as a [`Problem`]: dense `J` and LU of `c·I − J`.
pub(crate) struct FirstOrderProblem<'a, S: OdeSystem> {
    sys: &'a mut S,
    jac: DMatrix<f64>,
    lu: DenseLu,
    /// The complex factorization and its right-hand side (allocated on
    /// first use).
    clu: ComplexLu,
    cb: Vec<Complex<f64>>,
}

impl<'a, S: OdeSystem> FirstOrderProblem<'a, S> {
    pub(crate) fn new(sys: &'a mut S) -> Self {
        let n = sys.dim();
        Self {
            sys,
            jac: DMatrix::zeros(n, n),
            lu: DenseLu::new(n),
            clu: ComplexLu::new(0),
            cb: Vec::new(),
        }
    }
}

impl<S: OdeSystem> Problem for FirstOrderProblem<'_, S> {
    type User = S;
    fn user(&mut self) -> &mut S {
        self.sys
    }
    fn is_autonomous(&self) -> bool {
        self.sys.is_autonomous()
    }
    fn rhs(&mut self, t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), SystemError> {
        self.sys
            .rhs(t, y, dy)
            .map_err(|e| Box::new(e) as SystemError)
    }
    fn update_jacobian(&mut self, t: f64, y: &DVector<f64>) -> Result<Option<usize>, SystemError> {
        self.sys
            .jacobian(t, y, &mut self.jac)
            .map_err(|e| Box::new(e) as SystemError)?;
        Ok(crate::error::first_non_finite(self.jac.as_slice()))
    }
    fn factor_shifted(&mut self, c: f64) -> bool {
        let n = self.jac.nrows();
        let a = self.lu.matrix_mut();
        for j in 0..n {
            for i in 0..n {
                a[(i, j)] = -self.jac[(i, j)];
            }
            a[(j, j)] += c;
        }
        self.lu.factor()
    }
    fn solve_shifted(&mut self, b: &mut DVector<f64>) {
        self.lu.solve_in_place(b);
    }
    fn factor_shifted_complex(&mut self, alpha: f64, beta: f64) -> bool {
        let n = self.jac.nrows();
        if self.clu.dim() != n {
            self.clu = ComplexLu::new(n);
            self.cb = vec![Complex::new(0.0, 0.0); n];
        }
        for j in 0..n {
            for i in 0..n {
                let d = if i == j {
                    Complex::new(alpha, beta)
                } else {
                    Complex::new(0.0, 0.0)
                };
                self.clu.set(i, j, d - self.jac[(i, j)]);
            }
        }
        self.clu.factor()
    }
    fn solve_shifted_complex(&mut self, br: &mut DVector<f64>, bi: &mut DVector<f64>) {
        for i in 0..br.len() {
            self.cb[i] = Complex::new(br[i], bi[i]);
        }
        self.clu.solve_in_place(&mut self.cb);
        for i in 0..br.len() {
            br[i] = self.cb[i].re;
            bi[i] = self.cb[i].im;
        }
    }
}
