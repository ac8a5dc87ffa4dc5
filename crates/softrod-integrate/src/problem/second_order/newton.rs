//! Newton on the acceleration, for the methods that solve for `q̈`
//! (generalized-α, ESDIRK): the iteration matrix `I − β'Jq − γ'Jv` (in
//! mass-matrix form `M + β'K + γ'D`, dense or the system's structured
//! factorization), the Newton correction, and the filter of a local error
//! estimate through it.

use nalgebra::DVector;

use super::{JacKind, SecondOrderProblem};
use crate::error::SystemError;
use crate::system::SecondOrderSystem;

impl<S: SecondOrderSystem> SecondOrderProblem<'_, S> {
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
                let r = if self.m > 0 {
                    self.sys
                        .factor_shifted_constrained(self.jac_t, &q, beta_p, gamma_p)
                } else {
                    self.sys
                        .factor_shifted_mass(self.jac_t, &q, beta_p, gamma_p)
                };
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
        if self.kind == JacKind::Structured && self.m > 0 {
            // The KKT step (docs/theory-derivatives.md CD5–CD7):
            // [S, −Jᵀ; s·J, 0] [Δ; μ] = −[r; R].
            let map = |e| Box::new(e) as SystemError;
            self.sys
                .constrained_residual(t, q, qd, x, out, &mut self.cres)
                .map_err(map)?;
            out.neg_mut();
            self.cres.neg_mut();
            return self
                .sys
                .solve_shifted_constrained(out, &self.cres)
                .map_err(map);
        }
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
    /// differences of the force residual at `(q_J, 0, ·)`: three residuals,
    /// two once the one at `(q_J, 0, 0)` is held for the update.
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
            JacKind::Structured if self.m > 0 => {
                let q = std::mem::take(&mut self.jac_q);
                let out = self.constrained_filter_rhs(t, hg, &q, eq, ev);
                self.jac_q = q;
                out?;
                self.sys
                    .solve_shifted_constrained(&mut self.tmp, &self.cres)
                    .map_err(map)?;
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

    /// Whether `r0` (and `cres0`) hold the residual at `(t, q_J, 0, 0)` of
    /// the current structured update: evaluated at this `t`, or at another
    /// time of the same update when the system does not depend on `t`
    /// (then the same numbers).
    fn r0_held(&self, t: f64) -> bool {
        self.r0_t == t || (self.r0_t.is_finite() && self.sys.is_autonomous())
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
        if !self.r0_held(t) {
            self.r0_t = f64::NAN;
            self.sys
                .force_residual(t, qj, z, z, &mut self.r0)
                .map_err(map)?;
            self.r0_t = t;
        }
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

    /// The constrained filter's right-hand side (docs/theory-derivatives.md
    /// CD8): `tmp = M e_v − hγ K̃ e_q` as in
    /// [`structured_filter_rhs`](Self::structured_filter_rhs) and
    /// `cres = J e_v − hγ ∂R/∂q e_q` (`∂R/∂q = α²J` at rest), each a
    /// directional difference of [`SecondOrderSystem::constrained_residual`]
    /// at `(q_J, 0, ·)`: three residuals (two when the one at `(q_J, 0, 0)`
    /// is held).
    fn constrained_filter_rhs(
        &mut self,
        t: f64,
        hg: f64,
        qj: &DVector<f64>,
        eq: &DVector<f64>,
        ev: &DVector<f64>,
    ) -> Result<(), SystemError> {
        let map = |e| Box::new(e) as SystemError;
        let z = &self.zero;
        if !self.r0_held(t) {
            self.r0_t = f64::NAN;
            self.sys
                .constrained_residual(t, qj, z, z, &mut self.r0, &mut self.cres0)
                .map_err(map)?;
            self.r0_t = t;
        }
        // Exactly linear in q̈: M e_v and J e_v.
        let sv = 1.0 / ev.amax().max(f64::MIN_POSITIVE);
        self.q.copy_from(ev);
        self.q *= sv;
        self.sys
            .constrained_residual(t, qj, z, &self.q, &mut self.tmp, &mut self.cres)
            .map_err(map)?;
        self.tmp -= &self.r0;
        self.tmp /= sv;
        self.cres -= &self.cres0;
        self.cres /= sv;
        // K̃ e_q and ∂R/∂q e_q with a √ε-sized step.
        let sq = f64::EPSILON.sqrt() * qj.amax().max(1.0) / eq.amax().max(f64::MIN_POSITIVE);
        self.q.copy_from(qj);
        self.q.axpy(sq, eq, 1.0);
        self.sys
            .constrained_residual(t, &self.q, z, z, &mut self.r1, &mut self.cres1)
            .map_err(map)?;
        self.r1 -= &self.r0;
        self.tmp.axpy(-hg / sq, &self.r1, 1.0);
        self.cres1 -= &self.cres0;
        self.cres.axpy(-hg / sq, &self.cres1, 1.0);
        Ok(())
    }
}
