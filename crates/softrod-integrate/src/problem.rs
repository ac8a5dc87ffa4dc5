//! The internal adaptors the methods run on: a [`Problem`] gives
//! evaluations, keeps a Jacobian and solves with the shifted matrix
//! `(c·I − J)`; a second-order problem does so through an `n×n` Schur
//! complement instead of the `2n×2n` matrix.

use nalgebra::{DMatrix, DVector};

use crate::error::{IntegrateError, SystemError, first_non_finite};
use crate::linalg::DenseLu;
use crate::system::{OdeSystem, SecondOrderSystem};

/// What the methods need from a problem: evaluations, a Jacobian kept inside,
/// and solves with the shifted matrix `(c·I − J)`. Implemented by the two
/// adaptors so a second-order problem is solved with an `n×n` Schur complement
/// instead of the `2n×2n` matrix.
pub(crate) trait Problem {
    /// The user's system type (handed to callbacks).
    type User;
    /// The user's system.
    fn user(&mut self) -> &mut Self::User;
    /// Whether `f` is autonomous.
    fn is_autonomous(&self) -> bool;
    /// `dy = f(t, y)`.
    fn rhs(&mut self, t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), SystemError>;
    /// Evaluates and stores `J = ∂f/∂y(t, y)`. Returns `Err(what)` on a system
    /// error; non-finite entries are reported as `Ok(Some(index))`.
    fn update_jacobian(&mut self, t: f64, y: &DVector<f64>) -> Result<Option<usize>, SystemError>;
    /// Factors `c·I − J`; `false` if singular.
    fn factor_shifted(&mut self, c: f64) -> bool;
    /// Solves `(c·I − J) x = b` in place with the last factorization.
    fn solve_shifted(&mut self, b: &mut DVector<f64>);
    /// The system changed (a callback said so): parts of the Jacobian kept
    /// for the whole run (the constant `K`, `D` of the mass-matrix form) are
    /// fetched again at the next update.
    fn system_changed(&mut self) {}
}

/// Maps a system error to an [`IntegrateError`].
pub(crate) fn sys_err(
    t: f64,
    h: f64,
    what: &'static str,
) -> impl FnOnce(SystemError) -> IntegrateError {
    move |source| IntegrateError::System { t, h, what, source }
}

/// A first-order system as a [`Problem`]: dense `J` and LU of `c·I − J`.
pub(crate) struct FirstOrderProblem<'a, S: OdeSystem> {
    sys: &'a mut S,
    jac: DMatrix<f64>,
    lu: DenseLu,
}

impl<'a, S: OdeSystem> FirstOrderProblem<'a, S> {
    pub(crate) fn new(sys: &'a mut S) -> Self {
        let n = sys.dim();
        Self {
            sys,
            jac: DMatrix::zeros(n, n),
            lu: DenseLu::new(n),
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
}

/// A second-order system as a first-order [`Problem`] on `y = (q, q̇)`.
///
/// `(c·I − J) x = b` with `J = [[0, I], [Jq, Jv]]` is solved through the
/// Schur complement `S = c²·I − c·Jv − Jq` (n×n):
/// `x₁ = S⁻¹ (b₂ + c·b₁ − Jv·b₁)`, `x₂ = c·x₁ − b₁`.
///
/// In mass-matrix form ([`SecondOrderSystem::mass_form_jacobians`]:
/// `Jq = −M⁻¹K`, `Jv = −M⁻¹D`) that is
/// `x₁ = (c²M + cD + K)⁻¹ (M (b₂ + c·b₁) + D b₁)`.
pub(crate) struct SecondOrderProblem<'a, S: SecondOrderSystem> {
    pub(crate) sys: &'a mut S,
    n: usize,
    q: DVector<f64>,
    qd: DVector<f64>,
    qdd: DVector<f64>,
    /// `∂a/∂q`, or `M` in mass-matrix form.
    jq: DMatrix<f64>,
    /// `∂a/∂q̇` (unused in mass-matrix form).
    jv: DMatrix<f64>,
    /// `K`, `D` in mass-matrix form (0×0 until the system first provides
    /// them).
    k: DMatrix<f64>,
    d: DMatrix<f64>,
    /// Whether the last Jacobian update was in mass-matrix form.
    mass_form: bool,
    /// Whether `k`, `d` hold the system's constant `K`, `D`.
    kd_valid: bool,
    /// Whether the system provides [`SecondOrderSystem::force_residual`]
    /// (`None`: not asked yet).
    has_residual: Option<bool>,
    /// `D ≠ 0` (else its products are skipped).
    damped: bool,
    /// `K`, `D` symmetric (the bracket is then factored by Cholesky, else
    /// by LU).
    symmetric: bool,
    lu: DenseLu,
    shift: f64,
    tmp: DVector<f64>,
}

impl<'a, S: SecondOrderSystem> SecondOrderProblem<'a, S> {
    pub(crate) fn new(sys: &'a mut S) -> Self {
        let n = sys.dim();
        Self {
            sys,
            n,
            q: DVector::zeros(n),
            qd: DVector::zeros(n),
            qdd: DVector::zeros(n),
            jq: DMatrix::zeros(n, n),
            jv: DMatrix::zeros(n, n),
            k: DMatrix::zeros(0, 0),
            d: DMatrix::zeros(0, 0),
            mass_form: false,
            kd_valid: false,
            has_residual: None,
            damped: false,
            symmetric: false,
            lu: DenseLu::new(n),
            shift: 0.0,
            tmp: DVector::zeros(n),
        }
    }

    /// Evaluates the Jacobians at `(t, q, q̇)`: the mass-matrix form if the
    /// system provides it, else `∂a/∂q`, `∂a/∂q̇`. Non-finite entries are
    /// reported as `Ok(Some(index))`.
    fn eval_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<Option<usize>, SystemError> {
        let n = self.n;
        let constant = if self.kd_valid {
            None
        } else {
            if self.k.nrows() != n {
                self.k = DMatrix::zeros(n, n);
                self.d = DMatrix::zeros(n, n);
            }
            Some((&mut self.k, &mut self.d))
        };
        self.mass_form = self
            .sys
            .mass_form_jacobians(t, q, qd, &mut self.jq, constant)
            .map_err(|e| Box::new(e) as SystemError)?;
        if self.mass_form {
            debug_assert!(
                is_symmetric(&self.jq),
                "mass_form_jacobians: M not symmetric"
            );
            if !self.kd_valid {
                if let Some(i) = first_non_finite(self.k.as_slice())
                    .or_else(|| first_non_finite(self.d.as_slice()))
                {
                    // Reported with the index into the n×n matrices.
                    return Ok(Some(i));
                }
                self.damped = self.d.iter().any(|&v| v != 0.0);
                self.symmetric = is_symmetric(&self.k) && is_symmetric(&self.d);
                self.kd_valid = true;
            }
            return Ok(first_non_finite(self.jq.as_slice()));
        }
        self.kd_valid = false;
        self.sys
            .jacobians(t, q, qd, &mut self.jq, &mut self.jv)
            .map_err(|e| Box::new(e) as SystemError)?;
        Ok(first_non_finite(self.jq.as_slice()).or_else(|| first_non_finite(self.jv.as_slice())))
    }

    /// Mass-matrix form: factors `a·M + b·D + c·K` (already SPD for the
    /// rod: Cholesky, an LU if that fails or the inputs are not symmetric).
    fn factor_bracket(&mut self, a_m: f64, b_d: f64, c_k: f64) -> bool {
        let n = self.n;
        let dst = self.lu.matrix_mut().as_mut_slice();
        let (m, k, d) = (self.jq.as_slice(), self.k.as_slice(), self.d.as_slice());
        if self.damped {
            for i in 0..n * n {
                dst[i] = a_m * m[i] + b_d * d[i] + c_k * k[i];
            }
        } else {
            for i in 0..n * n {
                dst[i] = a_m * m[i] + c_k * k[i];
            }
        }
        if self.symmetric && self.lu.factor_cholesky() {
            return true;
        }
        // Not SPD after all (or not symmetric): the Cholesky destroyed the
        // buffer, so form the bracket again for the LU.
        let dst = self.lu.matrix_mut().as_mut_slice();
        for i in 0..n * n {
            dst[i] = a_m * m[i] + b_d * d[i] + c_k * k[i];
        }
        self.lu.factor()
    }

    /// Second-order dimension `n`.
    pub(crate) fn n(&self) -> usize {
        self.n
    }

    /// Evaluates and stores `∂a/∂q`, `∂a/∂q̇` at `(t, q, q̇)`.
    pub(crate) fn update_jacobians_qv(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<Option<usize>, SystemError> {
        self.eval_jacobians(t, q, qd)
    }

    /// Factors `I − β'·Jq − γ'·Jv` (the generalized-α iteration matrix), in
    /// mass-matrix form `M + β'K + γ'D`.
    pub(crate) fn factor_newmark(&mut self, beta_p: f64, gamma_p: f64) -> bool {
        if self.mass_form {
            return self.factor_bracket(1.0, gamma_p, beta_p);
        }
        let n = self.n;
        let a = self.lu.matrix_mut();
        for j in 0..n {
            for i in 0..n {
                a[(i, j)] = -beta_p * self.jq[(i, j)] - gamma_p * self.jv[(i, j)];
            }
            a[(j, j)] += 1.0;
        }
        self.lu.factor()
    }

    /// Solves `(I − β'·Jq − γ'·Jv) x = b` in place with the last
    /// [`factor_newmark`](Self::factor_newmark) (in mass-matrix form:
    /// `(M + β'K + γ'D) x = M b`).
    pub(crate) fn solve_n(&mut self, b: &mut DVector<f64>) {
        if self.mass_form {
            self.tmp.gemv(1.0, &self.jq, b, 0.0);
            self.lu.solve_in_place(&mut self.tmp);
            b.copy_from(&self.tmp);
        } else {
            self.lu.solve_in_place(b);
        }
    }

    /// The generalized-α Newton correction at the trial `(q, q̇)` for the
    /// unknown `x = q̈ₙ₊₁`: `Δ = (I − β'Jq − γ'Jv)⁻¹ (a(t, q, q̇) − x)` with
    /// the last [`factor_newmark`](Self::factor_newmark), into `out`. In
    /// mass-matrix form with a force residual `r = M x − f`:
    /// `Δ = −(M_J + β'K + γ'D)⁻¹ r` (see
    /// [`SecondOrderSystem::force_residual`]).
    pub(crate) fn newmark_correction(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        x: &DVector<f64>,
        out: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        if self.mass_form && self.has_residual != Some(false) {
            let has = self
                .sys
                .force_residual(t, q, qd, x, out)
                .map_err(|e| Box::new(e) as SystemError)?;
            self.has_residual = Some(has);
            if has {
                out.neg_mut();
                self.lu.solve_in_place(out);
                return Ok(());
            }
        }
        self.accel(t, q, qd, out)?;
        *out -= x;
        self.solve_n(out);
        Ok(())
    }

    /// `qdd = a(t, q, q̇)` without splitting a first-order state.
    pub(crate) fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        self.sys
            .accel(t, q, qd, qdd)
            .map_err(|e| Box::new(e) as SystemError)
    }
}

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
    }
    fn factor_shifted(&mut self, c: f64) -> bool {
        let n = self.n;
        self.shift = c;
        if self.mass_form {
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
        if self.mass_form {
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
}

/// Whether `a` is symmetric to rounding (`|aᵢⱼ − aⱼᵢ| ≤ 1e-12·max|a|`).
fn is_symmetric(a: &DMatrix<f64>) -> bool {
    let n = a.nrows();
    let tol = 1e-12 * a.amax();
    (0..n).all(|j| (0..j).all(|i| (a[(i, j)] - a[(j, i)]).abs() <= tol))
}
