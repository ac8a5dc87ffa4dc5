//! The first-order view of a second-order problem: `f(t, y)` on
//! `y = (q, q̇)`, its Jacobian `J = [[0, I], [Jq, Jv]]` and the solves with
//! `c·I − J` through the `n×n` Schur complement `c²I − cJv − Jq` (in
//! mass-matrix form `c²M + cD + K`), for a real or a complex shift `c`.

use nalgebra::{Complex, DVector};

use super::{JacKind, SecondOrderProblem};
use crate::error::SystemError;
use crate::linalg::ComplexLu;
use crate::problem::Problem;
use crate::system::SecondOrderSystem;

impl<S: SecondOrderSystem> Problem for SecondOrderProblem<'_, S> {
    type User = S;
    fn user(&mut self) -> &mut S {
        self.sys
    }
    fn is_autonomous(&self) -> bool {
        self.sys.is_autonomous()
    }
    fn rhs(&mut self, t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), SystemError> {
        let n = self.n;
        self.q.copy_from(&y.rows(0, n));
        self.qd.copy_from(&y.rows(n, n));
        self.sys
            .accel(t, &self.q, &self.qd, &mut self.qdd)
            .map_err(|e| Box::new(e) as SystemError)?;
        dy.rows_mut(0, n).copy_from(&self.qd);
        dy.rows_mut(n, n).copy_from(&self.qdd);
        Ok(())
    }
    fn update_jacobian(&mut self, t: f64, y: &DVector<f64>) -> Result<Option<usize>, SystemError> {
        let n = self.n;
        // Through buffers of their own: eval_jacobians borrows self.
        let mut q = std::mem::take(&mut self.q);
        let mut qd = std::mem::take(&mut self.qd);
        q.copy_from(&y.rows(0, n));
        qd.copy_from(&y.rows(n, n));
        let r = self.eval_jacobians(t, &q, &qd);
        self.q = q;
        self.qd = qd;
        r
    }
    fn system_changed(&mut self) {
        self.kd_valid = false;
        self.kind = JacKind::None;
        self.r0_t = f64::NAN;
    }
    fn has_cheap_jacobian(&self) -> bool {
        self.sys.has_mass_form()
    }
    fn update_exact_jacobian(
        &mut self,
        t: f64,
        y: &DVector<f64>,
    ) -> Result<Option<usize>, SystemError> {
        let n = self.n;
        let mut q = std::mem::take(&mut self.q);
        let mut qd = std::mem::take(&mut self.qd);
        q.copy_from(&y.rows(0, n));
        qd.copy_from(&y.rows(n, n));
        let r = self.eval_full(t, &q, &qd);
        self.q = q;
        self.qd = qd;
        r
    }
    fn factor_shifted(&mut self, c: f64) -> bool {
        let n = self.n;
        self.shift = c;
        if self.kind == JacKind::MassForm {
            return self.factor_bracket(c * c, c, 1.0);
        }
        let a = self.lu.matrix_mut();
        for j in 0..n {
            for i in 0..n {
                a[(i, j)] = -c * self.jv[(i, j)] - self.jq[(i, j)];
            }
            a[(j, j)] += c * c;
        }
        self.lu.factor()
    }
    fn solve_shifted(&mut self, b: &mut DVector<f64>) {
        let n = self.n;
        let c = self.shift;
        if self.kind == JacKind::MassForm {
            // tmp = M (b2 + c b1) + D b1
            self.q.copy_from(&b.rows(0, n)); // b1
            self.qd.copy_from(&b.rows(n, n));
            self.qd.axpy(c, &self.q, 1.0);
            self.tmp.gemv(1.0, &self.jq, &self.qd, 0.0);
            if self.damped {
                self.tmp.gemv(1.0, &self.d, &self.q, 1.0);
            }
            self.lu.solve_in_place(&mut self.tmp);
            for i in 0..n {
                let b1 = b[i];
                b[i] = self.tmp[i];
                b[n + i] = c * self.tmp[i] - b1;
            }
            return;
        }
        // tmp = b2 + c b1 − Jv b1
        self.q.copy_from(&b.rows(0, n)); // b1
        self.tmp.copy_from(&b.rows(n, n));
        self.tmp.axpy(c, &self.q, 1.0);
        self.tmp.gemv(-1.0, &self.jv, &self.q, 1.0);
        self.lu.solve_in_place(&mut self.tmp);
        // x1 = tmp, x2 = c x1 − b1
        for i in 0..n {
            let b1 = b[i];
            b[i] = self.tmp[i];
            b[n + i] = c * self.tmp[i] - b1;
        }
    }
    fn factor_shifted_complex(&mut self, alpha: f64, beta: f64) -> bool {
        let n = self.n;
        if self.clu.dim() != n {
            self.clu = ComplexLu::new(n);
            self.cb = vec![Complex::new(0.0, 0.0); n];
        }
        let c = Complex::new(alpha, beta);
        let c2 = c * c;
        self.cshift = c;
        let mass = self.kind == JacKind::MassForm;
        for j in 0..n {
            for i in 0..n {
                let v = if mass {
                    // c²M + cD + K
                    c2 * self.jq[(i, j)] + c * self.d[(i, j)] + self.k[(i, j)]
                } else {
                    let d = if i == j { c2 } else { Complex::new(0.0, 0.0) };
                    d - c * self.jv[(i, j)] - self.jq[(i, j)]
                };
                self.clu.set(i, j, v);
            }
        }
        self.clu.factor()
    }
    fn solve_shifted_complex(&mut self, br: &mut DVector<f64>, bi: &mut DVector<f64>) {
        let n = self.n;
        let c = self.cshift;
        // b1 = br[..n] + i bi[..n], b2 = br[n..] + i bi[n..].
        let mass = self.kind == JacKind::MassForm;
        for i in 0..n {
            let b1 = Complex::new(br[i], bi[i]);
            let b2 = Complex::new(br[n + i], bi[n + i]);
            self.cb[i] = b2 + c * b1;
        }
        if mass {
            // M (b2 + c b1) + D b1, by real products: real parts into qdd,
            // imaginary parts into tmp.
            for i in 0..n {
                self.q[i] = self.cb[i].re;
                self.qd[i] = self.cb[i].im;
            }
            self.qdd.gemv(1.0, &self.jq, &self.q, 0.0);
            self.tmp.gemv(1.0, &self.jq, &self.qd, 0.0);
            if self.damped {
                self.q.copy_from(&br.rows(0, n));
                self.qd.copy_from(&bi.rows(0, n));
                self.qdd.gemv(1.0, &self.d, &self.q, 1.0);
                self.tmp.gemv(1.0, &self.d, &self.qd, 1.0);
            }
            for i in 0..n {
                self.cb[i] = Complex::new(self.qdd[i], self.tmp[i]);
            }
        } else {
            // b2 + c b1 − Jv b1.
            for part in 0..2 {
                for i in 0..n {
                    self.q[i] = if part == 0 { br[i] } else { bi[i] };
                }
                self.tmp.gemv(1.0, &self.jv, &self.q, 0.0);
                for i in 0..n {
                    if part == 0 {
                        self.cb[i].re -= self.tmp[i];
                    } else {
                        self.cb[i].im -= self.tmp[i];
                    }
                }
            }
        }
        self.clu.solve_in_place(&mut self.cb);
        for i in 0..n {
            let b1 = Complex::new(br[i], bi[i]);
            let x1 = self.cb[i];
            let x2 = c * x1 - b1;
            br[i] = x1.re;
            bi[i] = x1.im;
            br[n + i] = x2.re;
            bi[n + i] = x2.im;
        }
    }
}
