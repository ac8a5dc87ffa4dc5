//! The problem traits: a first-order system `y' = f(t, y)` and a second-order
//! system `q̈ = a(t, q, q̇)`, plus the internal adaptors the methods run on.

use nalgebra::{DMatrix, DVector};

use crate::error::{IntegrateError, SystemError};
use crate::linalg::DenseLu;

/// A first-order ODE `y' = f(t, y)`, `y ∈ Rⁿ`.
///
/// `&mut self` lets an implementor reuse internal buffers between calls. The
/// integrator never calls two methods concurrently.
pub trait OdeSystem {
    /// The error the system may return; it is wrapped in
    /// [`IntegrateError::System`].
    type Error: std::error::Error + Send + Sync + 'static;

    /// Dimension `n` of the state `y`.
    fn dim(&self) -> usize;

    /// Writes `f(t, y)` into `dy` (dim `n`).
    fn rhs(&mut self, t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), Self::Error>;

    /// Writes the Jacobian `∂f/∂y (t, y)` (n×n) into `jac`.
    ///
    /// Default: forward finite differences ([`fd_jacobian`]), `n` extra
    /// right-hand-side calls (not counted in [`Stats::rhs_evaluations`](crate::Stats)),
    /// allocating two scratch vectors. Override it with the analytic Jacobian
    /// where one is available.
    fn jacobian(
        &mut self,
        t: f64,
        y: &DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<(), Self::Error> {
        let n = y.len();
        let mut f0 = DVector::zeros(n);
        let mut scratch = (DVector::zeros(n), DVector::zeros(n));
        self.rhs(t, y, &mut f0)?;
        fd_jacobian(|t, y, dy| self.rhs(t, y, dy), t, y, &f0, jac, &mut scratch)
    }

    /// Whether `f` does not depend on `t` explicitly. The Rosenbrock method
    /// then skips the finite-difference `∂f/∂t` (one right-hand side per step).
    /// Default `false` (always correct).
    fn is_autonomous(&self) -> bool {
        false
    }
}

/// A second-order system `q̈ = a(t, q, q̇)`, e.g. `M(q) q̈ = τ(t, q, q̇)` solved
/// for `q̈`, with `q ∈ Rⁿ` a vector space (PCS strains).
///
/// Its first-order form is `y = (q, q̇)`, `y' = (q̇, a)`, with Jacobian
/// `[[0, I], [∂a/∂q, ∂a/∂q̇]]`.
pub trait SecondOrderSystem {
    /// The error the system may return; it is wrapped in
    /// [`IntegrateError::System`].
    type Error: std::error::Error + Send + Sync + 'static;

    /// Dimension `n` of `q` (the first-order state has dimension `2n`).
    fn dim(&self) -> usize;

    /// Writes the accelerations `a(t, q, q̇)` into `qdd` (all dim `n`).
    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Self::Error>;

    /// Writes `∂a/∂q` and `∂a/∂q̇` (both n×n).
    ///
    /// Default: forward finite differences, `2n` extra `accel` calls (not
    /// counted in the statistics), allocating scratch vectors.
    fn jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        dqdd_dq: &mut DMatrix<f64>,
        dqdd_dqd: &mut DMatrix<f64>,
    ) -> Result<(), Self::Error> {
        let n = q.len();
        let mut a0 = DVector::zeros(n);
        let mut scratch = (DVector::zeros(n), DVector::zeros(n));
        self.accel(t, q, qd, &mut a0)?;
        fd_jacobian(
            |t, x, dy| self.accel(t, x, qd, dy),
            t,
            q,
            &a0,
            dqdd_dq,
            &mut scratch,
        )?;
        fd_jacobian(
            |t, x, dy| self.accel(t, q, x, dy),
            t,
            qd,
            &a0,
            dqdd_dqd,
            &mut scratch,
        )
    }

    /// Whether `a` does not depend on `t` explicitly (see
    /// [`OdeSystem::is_autonomous`]). Default `false`.
    fn is_autonomous(&self) -> bool {
        false
    }
}

/// Forward-difference Jacobian of `f` at `x`: column `j` is
/// `(f(x + δ_j e_j) − f0) / δ_j`, `δ_j = √ε · max(|x_j|, 1e-5)` (Hairer–Wanner's
/// choice in RADAU5/RODAS), the increment rounded so that `x_j + δ_j` is exact.
///
/// * `f0`: `f(t, x)`, dim of the output `m`.
/// * `jac`: m×n result.
/// * `scratch`: two vectors, dims `n` (perturbed `x`) and `m` (perturbed `f`).
pub fn fd_jacobian<E>(
    mut f: impl FnMut(f64, &DVector<f64>, &mut DVector<f64>) -> Result<(), E>,
    t: f64,
    x: &DVector<f64>,
    f0: &DVector<f64>,
    jac: &mut DMatrix<f64>,
    scratch: &mut (DVector<f64>, DVector<f64>),
) -> Result<(), E> {
    let (xp, fp) = scratch;
    xp.copy_from(x);
    for j in 0..x.len() {
        let xj = x[j];
        let delta = {
            let d = f64::EPSILON.sqrt() * xj.abs().max(1e-5);
            (xj + d) - xj
        };
        xp[j] = xj + delta;
        f(t, xp, fp)?;
        xp[j] = xj;
        for i in 0..f0.len() {
            jac[(i, j)] = (fp[i] - f0[i]) / delta;
        }
    }
    Ok(())
}

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
pub(crate) struct SecondOrderProblem<'a, S: SecondOrderSystem> {
    pub(crate) sys: &'a mut S,
    n: usize,
    q: DVector<f64>,
    qd: DVector<f64>,
    qdd: DVector<f64>,
    pub(crate) jq: DMatrix<f64>,
    pub(crate) jv: DMatrix<f64>,
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
            lu: DenseLu::new(n),
            shift: 0.0,
            tmp: DVector::zeros(n),
        }
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
        self.sys
            .jacobians(t, q, qd, &mut self.jq, &mut self.jv)
            .map_err(|e| Box::new(e) as SystemError)?;
        Ok(crate::error::first_non_finite(self.jq.as_slice())
            .or_else(|| crate::error::first_non_finite(self.jv.as_slice())))
    }

    /// Factors `I − β'·Jq − γ'·Jv` (the generalized-α iteration matrix).
    pub(crate) fn factor_newmark(&mut self, beta_p: f64, gamma_p: f64) -> bool {
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

    /// Solves with the last factorization (whichever matrix it was).
    pub(crate) fn solve_n(&mut self, b: &mut DVector<f64>) {
        self.lu.solve_in_place(b);
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
        self.q.copy_from(&y.rows(0, n));
        self.qd.copy_from(&y.rows(n, n));
        self.sys
            .jacobians(t, &self.q, &self.qd, &mut self.jq, &mut self.jv)
            .map_err(|e| Box::new(e) as SystemError)?;
        Ok(crate::error::first_non_finite(self.jq.as_slice())
            .or_else(|| crate::error::first_non_finite(self.jv.as_slice())))
    }
    fn factor_shifted(&mut self, c: f64) -> bool {
        let n = self.n;
        self.shift = c;
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
