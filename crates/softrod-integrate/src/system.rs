//! The problem traits: a first-order system `y' = f(t, y)` and a second-order
//! system `q̈ = a(t, q, q̇)`.

use nalgebra::{DMatrix, DVector};

/// A first-order ODE `y' = f(t, y)`, `y ∈ Rⁿ`.
///
/// `&mut self` lets an implementor reuse internal buffers between calls. The
/// integrator never calls two methods concurrently.
pub trait OdeSystem {
    /// The error the system may return; it is wrapped in
    /// [`IntegrateError::System`](crate::IntegrateError::System).
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
    /// [`IntegrateError::System`](crate::IntegrateError::System).
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

    /// Optional: the Jacobian approximation in mass-matrix form,
    /// `∂a/∂q ≈ −M⁻¹K`, `∂a/∂q̇ ≈ −M⁻¹D`, for systems
    /// `M(q) q̈ = −K q − D q̇ + f(t, q, q̇)` whose stiff part is the constant
    /// `K`, `D`. Writes `M(q)` (symmetric positive definite) into `mass` and,
    /// when `constant` is `Some((stiffness, damping))`, `K` and `D`
    /// (symmetric; positive semi-definite for the stiff methods' stability),
    /// all n×n, and returns `Ok(true)`. `K`, `D` are asked for once per run
    /// and again after a callback returns
    /// [`Control::SystemChanged`](crate::Control); between these they must
    /// not change. The default returns `Ok(false)` and the methods call
    /// [`jacobians`](Self::jacobians) instead.
    ///
    /// With it the methods never form `M⁻¹K`: the generalized-α iteration
    /// matrix is `I − β'Jq − γ'Jv = M⁻¹(M + β'K + γ'D)` and the Rosenbrock
    /// Schur complement is `c²I − cJv − Jq = M⁻¹(c²M + cD + K)`, so each is
    /// solved as `(M + β'K + γ'D) x = M b` (resp. `(c²M + cD + K) x = …`)
    /// with a Cholesky factorization of the bracket (`n³/3` flops, only its
    /// lower triangle is read) and one product with `M` per solve — instead
    /// of `n` solves with `M` for `M⁻¹K` (`n³`) plus an LU (`2n³/3`). If `K`
    /// or `D` is not symmetric, or the bracket is not numerically positive
    /// definite, an LU is used.
    fn mass_form_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        constant: Option<(&mut DMatrix<f64>, &mut DMatrix<f64>)>,
    ) -> Result<bool, Self::Error> {
        let _ = (t, q, qd, mass, constant);
        Ok(false)
    }

    /// Whether [`mass_form_jacobians`](Self::mass_form_jacobians) is
    /// provided (asked without evaluating anything). Generalized-α then uses
    /// [`factor_shifted_mass`](Self::factor_shifted_mass), when provided, in
    /// place of the dense mass-matrix form (the same matrix `M + β'K + γ'D`,
    /// factored without an `n×n` buffer). Default `false`; a system that
    /// overrides `mass_form_jacobians` overrides this to return `true`.
    fn has_mass_form(&self) -> bool {
        false
    }

    /// Optional, with [`mass_form_jacobians`](Self::mass_form_jacobians):
    /// the residual of the equation of motion in force form,
    /// `r = M(q) q̈ − f(t, q, q̇)` for a given `q̈` (for a rod: inverse
    /// dynamics minus the actuator force), into `r`; returns `Ok(true)`.
    /// The default returns `Ok(false)`.
    ///
    /// Generalized-α then takes its Newton correction as
    /// `Δ = −(M_J + β'K + γ'D)⁻¹ r(qₙ₊₁, q̇ₙ₊₁, x)` (`M_J`: the mass matrix of
    /// the last Jacobian update) instead of `(M_J + β'K + γ'D)⁻¹ M_J (a − x)`:
    /// the same Newton iteration on the same equation, whose fixed point is
    /// `x = a`, but an inverse dynamics costs a fraction of a forward
    /// dynamics (no articulated inertias) and the product with `M_J` goes.
    /// With one iteration per step (the linearly implicit scheme) the two
    /// differ by `(M − M_J)(a − x)`: in the soft modes the acceleration form
    /// applies `≈ I` whatever `M_J`, the force form `M_J⁻¹M`, so the force
    /// form wants a fresh `M_J`. Measured on the soft cantilever with the
    /// default [`Options::jacobian_max_age`](crate::Options) = 20: the same
    /// tip accuracy at 5 pieces (dt 1.5e-3: 5.5e-5 m at t = 1, 1.65e-4 m
    /// max over the run, both forms), 10–30 % larger errors at 20 pieces
    /// for half the cost; with the Jacobian kept 100 steps it drifts
    /// (1e-2 m at 5 pieces, where the acceleration form stayed at 6e-5 m).
    fn force_residual(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        r: &mut DVector<f64>,
    ) -> Result<bool, Self::Error> {
        let _ = (t, q, qd, qdd, r);
        Ok(false)
    }

    /// Optional, for systems `M(q) q̈ = −K q − D q̇ + f(t, q, q̇)` with
    /// constant symmetric positive semi-definite `K`, `D`: factors the
    /// shifted mass matrix `S = M(q) + a·K + b·D` (`a, b ≥ 0`, real) for
    /// later [`solve_shifted_mass`](Self::solve_shifted_mass) calls, in
    /// whatever structured way the system knows (for a rod, the O(N)
    /// articulated recursion with `a K_n + b D_n` added to each piece's
    /// articulated inertia, instead of a dense `n×n` Cholesky). Returns
    /// `Ok(true)` if provided; the default returns `Ok(false)` and the
    /// methods use dense matrices ([`mass_form_jacobians`](Self::mass_form_jacobians)
    /// or [`jacobians`](Self::jacobians)).
    ///
    /// A system that provides it must also provide
    /// [`force_residual`](Self::force_residual): the implicit methods then
    /// take Newton corrections `Δ = −S⁻¹ r` on the force residual `r`, with
    /// no `n×n` matrix anywhere. `S` approximates the step's iteration matrix
    /// `M + a ∂r/∂q + b ∂r/∂q̇` by its elastic/viscous part (geometric,
    /// gyroscopic and load terms left out); methods that use it fall back to
    /// the exact [`jacobians`](Self::jacobians) when Newton converges badly.
    fn factor_shifted_mass(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        a: f64,
        b: f64,
    ) -> Result<bool, Self::Error> {
        let _ = (t, q, a, b);
        Ok(false)
    }

    /// Optional, with [`factor_shifted_mass`](Self::factor_shifted_mass):
    /// called at every Jacobian update of the structured path with the
    /// state `(t, q, q̇)` it is taken at, before the factorizations at `q`,
    /// so that a system whose shifted matrix has state-dependent parts
    /// beyond `M(q)` can linearize them there — for a rod in contact, the
    /// contact's stiffness and damping (`M + a(K + K_c) + b(D + D_c)`,
    /// docs/theory-contact.md CT17), or for a closed model on
    /// [`factor_shifted_constrained`](Self::factor_shifted_constrained) the
    /// multipliers whose closure forces its geometric terms hold
    /// (docs/theory-derivatives.md CD11). The default does nothing.
    fn linearize_shifted(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<(), Self::Error> {
        let _ = (t, q, qd);
        Ok(())
    }

    /// Optional, with [`linearize_shifted`](Self::linearize_shifted):
    /// whether the structured matrix should be re-linearized and refactored
    /// at every Newton iterate rather than once per step — for a system
    /// whose state-dependent part switches within a step (contacts that
    /// open, close, stick or slide: docs/theory-contact.md CT27). ESDIRK
    /// then runs an active-set Newton iteration on its structured matrix.
    /// The default is `false`.
    fn relinearize_in_newton(&self) -> bool {
        false
    }

    /// After a step from `(t0, q0, q̇0)` to `(t1, q1, q̇1)` of size `h` that
    /// passed its error test: `Some(θ)`, `0 < θ < 1`, if the system's
    /// internal state committed between steps (friction anchors) makes the
    /// step wrong by more than the system tolerates and it must be retried
    /// at `θ h` — where an event it cannot see inside a step happened (a
    /// sliding contact stopped: docs/theory-contact.md CT29). ESDIRK asks
    /// it; the default is `None`.
    #[allow(clippy::too_many_arguments)]
    fn step_event_fraction(
        &mut self,
        h: f64,
        t0: f64,
        q0: &DVector<f64>,
        qd0: &DVector<f64>,
        t1: f64,
        q1: &DVector<f64>,
        qd1: &DVector<f64>,
    ) -> Result<Option<f64>, Self::Error> {
        let _ = (h, t0, q0, qd0, t1, q1, qd1);
        Ok(None)
    }

    /// `x ← S⁻¹ x` with the `S` of the last successful
    /// [`factor_shifted_mass`](Self::factor_shifted_mass).
    ///
    /// # Panics
    ///
    /// The default panics: the methods call it only after
    /// `factor_shifted_mass` returned `Ok(true)`, so a system that overrides
    /// one must override both.
    fn solve_shifted_mass(&mut self, x: &mut DVector<f64>) -> Result<(), Self::Error> {
        let _ = x;
        unimplemented!("solve_shifted_mass: the system provides factor_shifted_mass but not this")
    }

    /// Optional, for systems whose accelerations are held by `m` algebraic
    /// constraints (closed chains, docs/theory.md D67–D68:
    /// `M q̈ = f + Jᵀλ`, `R = J q̈ + … = 0`): the number `m` of constraint
    /// rows the structured Newton solve of
    /// [`factor_shifted_constrained`](Self::factor_shifted_constrained)
    /// handles. Default 0 (no constraints, or none handled structurally:
    /// the methods then use [`factor_shifted_mass`](Self::factor_shifted_mass)
    /// or dense matrices).
    fn n_constraints(&self) -> usize {
        0
    }

    /// Optional: projects `(q, q̇)` at `t` onto the system's constraint
    /// manifold (a closed chain's loops, docs/theory.md D121), in place;
    /// `Ok(true)` if it changed them. Called after each accepted step when
    /// [`Options::project_state`](crate::Options::project_state) is on.
    /// Default: no constraints, nothing to do (`Ok(false)`).
    fn project(
        &mut self,
        t: f64,
        q: &mut DVector<f64>,
        qd: &mut DVector<f64>,
    ) -> Result<bool, Self::Error> {
        let _ = (t, q, qd);
        Ok(false)
    }

    /// Optional, with [`n_constraints`](Self::n_constraints) `= m > 0`:
    /// factors the KKT matrix `[S, −Jᵀ; s·J, 0]` of the constrained
    /// dynamics' implicit step at `(t, q)`, `S = M(q) + a·K + b·D` as in
    /// [`factor_shifted_mass`](Self::factor_shifted_mass), `J` the
    /// constraint rows and `s = ∂R/∂q̈` along the step (for Baumgarte-stabilized
    /// rows `s = 1 + 2α·b + α²·a`, docs/theory-derivatives.md CD6), for
    /// later [`solve_shifted_constrained`](Self::solve_shifted_constrained)
    /// calls. Returns `Ok(true)` if provided (default `Ok(false)`).
    ///
    /// A system that provides it must provide
    /// [`constrained_residual`](Self::constrained_residual): the implicit
    /// methods then take Newton corrections `Δ` from
    /// `[S, −Jᵀ; s·J, 0] [Δ; μ] = −[r; R]`, whose fixed point (`r = Jᵀμ`,
    /// `R = 0`) is the constrained `q̈`. Like the shifted mass matrix it
    /// approximates the exact iteration matrix; the methods fall back to the
    /// exact [`jacobians`](Self::jacobians) when Newton converges badly.
    fn factor_shifted_constrained(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        a: f64,
        b: f64,
    ) -> Result<bool, Self::Error> {
        let _ = (t, q, a, b);
        Ok(false)
    }

    /// `x ←` the first block of the solution of `[S, −Jᵀ; s·J, 0] [x; μ] =
    /// [x; d]` with the last successful
    /// [`factor_shifted_constrained`](Self::factor_shifted_constrained)
    /// (`x`: n, `d`: m).
    ///
    /// # Panics
    ///
    /// The default panics: the methods call it only after
    /// `factor_shifted_constrained` returned `Ok(true)`.
    fn solve_shifted_constrained(
        &mut self,
        x: &mut DVector<f64>,
        d: &DVector<f64>,
    ) -> Result<(), Self::Error> {
        let _ = (x, d);
        unimplemented!(
            "solve_shifted_constrained: the system provides factor_shifted_constrained but not this"
        )
    }

    /// Optional, with [`factor_shifted_constrained`](Self::factor_shifted_constrained):
    /// the residuals of the constrained equations of motion at a trial
    /// `q̈`: the force residual without the constraint forces,
    /// `r = M(q) q̈ − f(t, q, q̇)` (n), and the constraint rows `R` (m; for
    /// a closed chain the Baumgarte-stabilized `J q̈ + J̇q̇ + 2α J q̇ + α²φ`),
    /// both affine in `q̈`. Returns `Ok(true)` if provided (default
    /// `Ok(false)`).
    fn constrained_residual(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        r: &mut DVector<f64>,
        c: &mut DVector<f64>,
    ) -> Result<bool, Self::Error> {
        let _ = (t, q, qd, qdd, r, c);
        Ok(false)
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
