//! The internal adaptors the methods run on: a [`Problem`] gives
//! evaluations, keeps a Jacobian and solves with the shifted matrix
//! `(c·I − J)`; a second-order problem does so through an `n×n` Schur
//! complement instead of the `2n×2n` matrix.

use nalgebra::{DMatrix, DVector};

use crate::error::{IntegrateError, SystemError, first_non_finite};
use crate::linalg::{ComplexLu, DenseLu};
use crate::system::{OdeSystem, SecondOrderSystem};
use nalgebra::Complex;

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
    /// Whether [`update_jacobian`](Self::update_jacobian) gives a cheap
    /// approximation (the mass-matrix form) rather than the exact Jacobian.
    fn has_cheap_jacobian(&self) -> bool {
        false
    }
    /// Evaluates and stores the exact `J` (the same as
    /// [`update_jacobian`](Self::update_jacobian) unless that is a cheap
    /// approximation).
    fn update_exact_jacobian(
        &mut self,
        t: f64,
        y: &DVector<f64>,
    ) -> Result<Option<usize>, SystemError> {
        self.update_jacobian(t, y)
    }
    /// Factors `c·I − J`; `false` if singular.
    fn factor_shifted(&mut self, c: f64) -> bool;
    /// Solves `(c·I − J) x = b` in place with the last factorization.
    fn solve_shifted(&mut self, b: &mut DVector<f64>);
    /// Factors the complex `(α + iβ)·I − J` (kept beside the real one);
    /// `false` if singular.
    fn factor_shifted_complex(&mut self, alpha: f64, beta: f64) -> bool;
    /// Solves `((α + iβ)·I − J)(x_r + i x_i) = b_r + i b_i` in place with
    /// the last complex factorization.
    fn solve_shifted_complex(&mut self, br: &mut DVector<f64>, bi: &mut DVector<f64>);
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
    /// ([`SecondOrderSystem::factor_shifted_mass`]) with the force residual:
    /// no dense matrix.
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
        if self.has_structured.is_none() {
            let has = self
                .sys
                .factor_shifted_mass(t, q, 0.0, 0.0)
                .map_err(|e| Box::new(e) as SystemError)?;
            self.has_structured = Some(has);
        }
        if self.has_structured == Some(true) && self.has_residual.is_none() {
            self.qdd.fill(0.0);
            let has = self
                .sys
                .force_residual(t, q, qd, &self.qdd, &mut self.tmp)
                .map_err(|e| Box::new(e) as SystemError)?;
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
    /// one and `structured` allows it (nothing is evaluated now; the
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
            self.kind = JacKind::Structured;
            self.jac_t = t;
            self.jac_q.copy_from(q);
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

    /// Factors `I − β'·Jq − γ'·Jv` (the generalized-α iteration matrix), in
    /// mass-matrix form `M + β'K + γ'D` (dense, or the system's structured
    /// factorization at the configuration of the last update). `Ok(false)`:
    /// singular.
    pub(crate) fn factor_newmark(
        &mut self,
        beta_p: f64,
        gamma_p: f64,
    ) -> Result<bool, SystemError> {
        match self.kind {
            JacKind::Structured => {
                let q = std::mem::take(&mut self.jac_q);
                let r = self
                    .sys
                    .factor_shifted_mass(self.jac_t, &q, beta_p, gamma_p);
                self.jac_q = q;
                return r.map_err(|e| Box::new(e) as SystemError);
            }
            JacKind::MassForm => return Ok(self.factor_bracket(1.0, gamma_p, beta_p)),
            JacKind::None => return Ok(false),
            JacKind::Full => {}
        }
        let n = self.n;
        let a = self.lu.matrix_mut();
        for j in 0..n {
            for i in 0..n {
                a[(i, j)] = -beta_p * self.jq[(i, j)] - gamma_p * self.jv[(i, j)];
            }
            a[(j, j)] += 1.0;
        }
        Ok(self.lu.factor())
    }

    /// Solves `(I − β'·Jq − γ'·Jv) x = b` in place with the last
    /// [`factor_newmark`](Self::factor_newmark) (in mass-matrix form:
    /// `(M + β'K + γ'D) x = M b`).
    fn solve_n(&mut self, b: &mut DVector<f64>) {
        if self.kind == JacKind::MassForm {
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
    /// mass-matrix form (dense or structured) with a force residual
    /// `r = M x − f`: `Δ = −(M_J + β'K + γ'D)⁻¹ r` (see
    /// [`SecondOrderSystem::force_residual`]).
    pub(crate) fn newmark_correction(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        x: &DVector<f64>,
        out: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        if self.kind == JacKind::Structured {
            self.sys
                .force_residual(t, q, qd, x, out)
                .map_err(|e| Box::new(e) as SystemError)?;
            out.neg_mut();
            return self
                .sys
                .solve_shifted_mass(out)
                .map_err(|e| Box::new(e) as SystemError);
        }
        if self.kind == JacKind::MassForm && self.has_residual != Some(false) {
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

    /// Filters a local error estimate `e = (e_q, e_v)` of a first-order
    /// state through `(I − hγ J)⁻¹` (Shampine's filter, as in Hairer–Wanner's
    /// RADAU5, *ODEs II* §IV.8): stiff components of the estimate are divided
    /// by `|1 − hγλ|`, so an L-stable method is not made to resolve stiff
    /// modes it damps. With `J = [[0, I], [Jq, Jv]]` the second block of the
    /// solution is `ẽ_v = (I − hγJv − h²γ²Jq)⁻¹ (e_v + hγ Jq e_q)` — the
    /// last [`factor_newmark`](Self::factor_newmark) with `β' = h²γ²`,
    /// `γ' = hγ` — and `ẽ_q = e_q + hγ ẽ_v`. In mass-matrix and structured
    /// form the right-hand side is `M e_v − hγ K̃ e_q`; structured, `M e_v` and
    /// the static stiffness `K̃ e_q` (elastic plus geometric) are directional
    /// differences of the force residual at `(q_J, 0, ·)`: three residuals.
    pub(crate) fn filter_error(
        &mut self,
        t: f64,
        hg: f64,
        eq: &mut DVector<f64>,
        ev: &mut DVector<f64>,
    ) -> Result<(), SystemError> {
        let map = |e| Box::new(e) as SystemError;
        match self.kind {
            JacKind::None => return Ok(()),
            JacKind::Full => {
                self.tmp.copy_from(ev);
                self.tmp.gemv(hg, &self.jq, eq, 1.0);
                self.lu.solve_in_place(&mut self.tmp);
            }
            JacKind::MassForm => {
                self.tmp.gemv(1.0, &self.jq, ev, 0.0);
                self.tmp.gemv(-hg, &self.k, eq, 1.0);
                self.lu.solve_in_place(&mut self.tmp);
            }
            JacKind::Structured => {
                let q = std::mem::take(&mut self.jac_q);
                let out = self.structured_filter_rhs(t, hg, &q, eq, ev);
                self.jac_q = q;
                out?;
                self.sys.solve_shifted_mass(&mut self.tmp).map_err(map)?;
            }
        }
        ev.copy_from(&self.tmp);
        eq.axpy(hg, ev, 1.0);
        Ok(())
    }

    /// `tmp = M(q_J) e_v − hγ K̃ e_q` by three force residuals (see
    /// [`filter_error`](Self::filter_error)).
    fn structured_filter_rhs(
        &mut self,
        t: f64,
        hg: f64,
        qj: &DVector<f64>,
        eq: &DVector<f64>,
        ev: &DVector<f64>,
    ) -> Result<(), SystemError> {
        let map = |e| Box::new(e) as SystemError;
        let z = &self.zero;
        self.sys
            .force_residual(t, qj, z, z, &mut self.r0)
            .map_err(map)?;
        // M e_v = (r(q_J, 0, σ e_v) − r0) / σ: exactly linear in e_v.
        let sv = 1.0 / ev.amax().max(f64::MIN_POSITIVE);
        self.q.copy_from(ev);
        self.q *= sv;
        self.sys
            .force_residual(t, qj, z, &self.q, &mut self.tmp)
            .map_err(map)?;
        self.tmp -= &self.r0;
        self.tmp /= sv;
        // K̃ e_q = (r(q_J + σ e_q, 0, 0) − r0) / σ with a √ε-sized step.
        let sq = f64::EPSILON.sqrt() * qj.amax().max(1.0) / eq.amax().max(f64::MIN_POSITIVE);
        self.q.copy_from(qj);
        self.q.axpy(sq, eq, 1.0);
        self.sys
            .force_residual(t, &self.q, z, z, &mut self.r1)
            .map_err(map)?;
        self.r1 -= &self.r0;
        self.tmp.axpy(-hg / sq, &self.r1, 1.0);
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
        self.kind = JacKind::None;
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

/// Whether `a` is symmetric to rounding (`|aᵢⱼ − aⱼᵢ| ≤ 1e-12·max|a|`).
fn is_symmetric(a: &DMatrix<f64>) -> bool {
    let n = a.nrows();
    let tol = 1e-12 * a.amax();
    (0..n).all(|j| (0..j).all(|i| (a[(i, j)] - a[(j, i)]).abs() <= tol))
}
