//! A second-order system `q̈ = a(t, q, q̇)` as a [`Problem`](super::Problem)
//! on `y = (q, q̇)`: the adaptor, its buffers and the Jacobian updates (dense
//! `∂a/∂q`, `∂a/∂q̇`, the mass-matrix form `M`, `K`, `D`, or the system's
//! structured `M + aK + bD`). The first-order view with its Schur-complement
//! solves is in `first_order_view`, the iteration matrix of the methods that
//! solve for accelerations in `newton`.

use nalgebra::{Complex, DMatrix, DVector};

use crate::error::{SystemError, first_non_finite};
use crate::linalg::{ComplexLu, DenseLu};
use crate::system::SecondOrderSystem;

mod first_order_view;
mod newton;

/// What the last Jacobian update of a [`SecondOrderProblem`] left for the
/// iteration matrices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum JacKind {
    /// Nothing yet (or the system changed).
    None,
    /// Dense `∂a/∂q`, `∂a/∂q̇` ([`SecondOrderSystem::jacobians`]).
    Full,
    /// Dense `M(q_J)` and the constant `K`, `D`
    /// ([`SecondOrderSystem::mass_form_jacobians`]).
    MassForm,
    /// The system's structured `M(q_J) + aK + bD`
    /// ([`SecondOrderSystem::factor_shifted_mass`]) with the force residual,
    /// or for a constrained system (`m > 0`) its KKT form
    /// ([`SecondOrderSystem::factor_shifted_constrained`]) with the force
    /// and constraint residuals: no dense matrix.
    Structured,
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
///
/// The dense `n×n` buffers are allocated on first use only: a run whose
/// iteration matrices are all structured never allocates one.
pub(crate) struct SecondOrderProblem<'a, S: SecondOrderSystem> {
    pub(crate) sys: &'a mut S,
    n: usize,
    /// Constraint rows of the structured KKT solve
    /// ([`SecondOrderSystem::n_constraints`]; 0: none).
    m: usize,
    /// Constraint residuals (m each): a Newton step's, and two of the
    /// error filter.
    cres: DVector<f64>,
    cres0: DVector<f64>,
    cres1: DVector<f64>,
    q: DVector<f64>,
    qd: DVector<f64>,
    qdd: DVector<f64>,
    /// `∂a/∂q`, or `M` in mass-matrix form (0×0 until needed).
    jq: DMatrix<f64>,
    /// `∂a/∂q̇` (0×0 until needed; unused in mass-matrix form).
    jv: DMatrix<f64>,
    /// `K`, `D` in mass-matrix form (0×0 until the system first provides
    /// them).
    k: DMatrix<f64>,
    d: DMatrix<f64>,
    /// What the last Jacobian update produced.
    kind: JacKind,
    /// Configuration of the last structured update (`S` is factored there).
    jac_t: f64,
    jac_q: DVector<f64>,
    /// Whether `k`, `d` hold the system's constant `K`, `D`.
    kd_valid: bool,
    /// Whether the system provides [`SecondOrderSystem::force_residual`]
    /// (`None`: not asked yet).
    has_residual: Option<bool>,
    /// Whether the system provides [`SecondOrderSystem::factor_shifted_mass`]
    /// (`None`: not asked yet).
    has_structured: Option<bool>,
    /// `D ≠ 0` (else its products are skipped).
    damped: bool,
    /// `K`, `D` symmetric (the bracket is then factored by Cholesky, else
    /// by LU).
    symmetric: bool,
    lu: DenseLu,
    shift: f64,
    tmp: DVector<f64>,
    /// The complex Schur complement `c²I − cJv − Jq` (or `c²M + cD + K`)
    /// for `c = α + iβ`, its shift and a right-hand side (allocated on
    /// first use).
    clu: ComplexLu,
    cshift: Complex<f64>,
    cb: Vec<Complex<f64>>,
    /// Zeros, and two residuals (error filter).
    zero: DVector<f64>,
    r0: DVector<f64>,
    r1: DVector<f64>,
    /// The time at which `r0` (and `cres0`) hold the filter's residual at
    /// `(q_J, 0, 0)` of the current structured update (NaN: not held). The
    /// Jacobian is kept over several steps; for an autonomous system the
    /// residual at `q_J` is then the same at every step's `t`, so it is
    /// evaluated once per update instead of once per step.
    r0_t: f64,
}

impl<'a, S: SecondOrderSystem> SecondOrderProblem<'a, S> {
    pub(crate) fn new(sys: &'a mut S) -> Self {
        let n = sys.dim();
        let m = sys.n_constraints();
        Self {
            sys,
            n,
            m,
            cres: DVector::zeros(m),
            cres0: DVector::zeros(m),
            cres1: DVector::zeros(m),
            q: DVector::zeros(n),
            qd: DVector::zeros(n),
            qdd: DVector::zeros(n),
            jq: DMatrix::zeros(0, 0),
            jv: DMatrix::zeros(0, 0),
            k: DMatrix::zeros(0, 0),
            d: DMatrix::zeros(0, 0),
            kind: JacKind::None,
            jac_t: 0.0,
            jac_q: DVector::zeros(n),
            kd_valid: false,
            has_residual: None,
            has_structured: None,
            damped: false,
            symmetric: false,
            lu: DenseLu::new(0),
            shift: 0.0,
            tmp: DVector::zeros(n),
            clu: ComplexLu::new(0),
            cshift: Complex::new(0.0, 0.0),
            cb: Vec::new(),
            zero: DVector::zeros(n),
            r0: DVector::zeros(n),
            r1: DVector::zeros(n),
            r0_t: f64::NAN,
        }
    }

    /// Allocates the dense `Jq` (or `M`) and factorization buffers, and `Jv`
    /// if `full`.
    fn ensure_dense(&mut self, full: bool) {
        let n = self.n;
        if self.jq.nrows() != n {
            self.jq = DMatrix::zeros(n, n);
            self.lu = DenseLu::new(n);
        }
        if full && self.jv.nrows() != n {
            self.jv = DMatrix::zeros(n, n);
        }
    }

    /// Whether the system asks for its structured matrix to be
    /// re-linearized at every Newton iterate
    /// ([`SecondOrderSystem::relinearize_in_newton`]).
    pub(crate) fn relinearize_in_newton(&self) -> bool {
        self.sys.relinearize_in_newton()
    }

    /// [`SecondOrderSystem::step_event_fraction`].
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn step_event_fraction(
        &mut self,
        h: f64,
        t0: f64,
        q0: &DVector<f64>,
        qd0: &DVector<f64>,
        t1: f64,
        q1: &DVector<f64>,
        qd1: &DVector<f64>,
    ) -> Result<Option<f64>, SystemError> {
        self.sys
            .step_event_fraction(h, t0, q0, qd0, t1, q1, qd1)
            .map_err(|e| Box::new(e) as SystemError)
    }

    /// What the last Jacobian update produced.
    pub(crate) fn kind(&self) -> JacKind {
        self.kind
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
        self.ensure_dense(false);
        let constant = if self.kd_valid {
            None
        } else {
            if self.k.nrows() != n {
                self.k = DMatrix::zeros(n, n);
                self.d = DMatrix::zeros(n, n);
            }
            Some((&mut self.k, &mut self.d))
        };
        let mass_form = self
            .sys
            .mass_form_jacobians(t, q, qd, &mut self.jq, constant)
            .map_err(|e| Box::new(e) as SystemError)?;
        if mass_form {
            self.kind = JacKind::MassForm;
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
        self.eval_full(t, q, qd)
    }

    /// Dense `∂a/∂q`, `∂a/∂q̇` from [`SecondOrderSystem::jacobians`].
    fn eval_full(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<Option<usize>, SystemError> {
        self.ensure_dense(true);
        self.kind = JacKind::Full;
        self.sys
            .jacobians(t, q, qd, &mut self.jq, &mut self.jv)
            .map_err(|e| Box::new(e) as SystemError)?;
        Ok(first_non_finite(self.jq.as_slice()).or_else(|| first_non_finite(self.jv.as_slice())))
    }

    /// Whether the system provides the structured shifted-mass solve and the
    /// force residual it needs (asked once per run: one factorization of
    /// `M(q)` and one residual at `(t, q, q̇, 0)`).
    fn structured_available(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<bool, SystemError> {
        let map = |e| Box::new(e) as SystemError;
        if self.has_structured.is_none() {
            let has = if self.m > 0 {
                self.sys.factor_shifted_constrained(t, q, 0.0, 0.0)
            } else {
                self.sys.factor_shifted_mass(t, q, 0.0, 0.0)
            }
            .map_err(map)?;
            self.has_structured = Some(has);
        }
        if self.has_structured == Some(true) && self.has_residual.is_none() {
            self.qdd.fill(0.0);
            let has = if self.m > 0 {
                self.sys
                    .constrained_residual(t, q, qd, &self.qdd, &mut self.tmp, &mut self.cres)
            } else {
                self.sys.force_residual(t, q, qd, &self.qdd, &mut self.tmp)
            }
            .map_err(map)?;
            self.has_residual = Some(has);
        }
        Ok(self.has_structured == Some(true) && self.has_residual == Some(true))
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

    /// The Jacobian update of the implicit second-order methods at
    /// `(t, q, q̇)`: the system's structured `M(q) + aK + bD` if it provides
    /// one and `structured` allows it (only its state-dependent extras are
    /// evaluated now, [`SecondOrderSystem::linearize_shifted`]; the
    /// factorization happens at `q`), else the dense mass-matrix form if the
    /// system provides it, else the dense `∂a/∂q`, `∂a/∂q̇`. Non-finite
    /// entries are reported as `Ok(Some(index))`.
    pub(crate) fn update_jacobians_qv(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        structured: bool,
    ) -> Result<Option<usize>, SystemError> {
        if structured && self.structured_available(t, q, qd)? {
            // The contact's linearization, or a closed model's multipliers
            // for the KKT matrix's geometric terms (CD11).
            self.sys
                .linearize_shifted(t, q, qd)
                .map_err(|e| Box::new(e) as SystemError)?;
            self.kind = JacKind::Structured;
            self.jac_t = t;
            self.jac_q.copy_from(q);
            self.r0_t = f64::NAN;
            return Ok(None);
        }
        self.eval_jacobians(t, q, qd)
    }

    /// The exact Jacobian update: the dense `∂a/∂q`, `∂a/∂q̇` of
    /// [`SecondOrderSystem::jacobians`], whatever else the system provides.
    pub(crate) fn update_full_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<Option<usize>, SystemError> {
        self.eval_full(t, q, qd)
    }

    /// Whether the system asks for the mass-matrix form (generalized-α then
    /// uses the structured solve in its place when there is one).
    pub(crate) fn has_mass_form(&self) -> bool {
        self.sys.has_mass_form()
    }

    /// `qdd = a(t, q, q̇)` without splitting a first-order state.
    /// [`SecondOrderSystem::project`] of the user's system.
    pub(crate) fn project(
        &mut self,
        t: f64,
        q: &mut DVector<f64>,
        qd: &mut DVector<f64>,
    ) -> Result<bool, SystemError> {
        self.sys
            .project(t, q, qd)
            .map_err(|e| Box::new(e) as SystemError)
    }

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

/// Whether `a` is symmetric to rounding (`|aᵢⱼ − aⱼᵢ| ≤ 1e-12·max|a|`).
fn is_symmetric(a: &DMatrix<f64>) -> bool {
    let n = a.nrows();
    let tol = 1e-12 * a.amax();
    (0..n).all(|j| (0..j).all(|i| (a[(i, j)] - a[(j, i)]).abs() <= tol))
}
