//! Gradients of whole trajectories by the discrete adjoint of the
//! integrator (docs/theory-control.md, "Gradients of whole trajectories",
//! G1–G8).
//!
//! A forward run records a [`Tape`]: the accepted step sequence `(tₙ, hₙ)`
//! and the states `yₙ = (qₙ, q̇ₙ)` at the step ends. The backward pass
//! ([`adjoint_second_order`]) runs the steps in reverse: it recomputes each
//! step's stages from `yₙ` (the explicit formulas of the method and a
//! Newton iteration converged to round-off), evaluates the exact Jacobians
//! at every stage and solves the transposed stage systems. The step
//! sequence is held fixed: the result is the exact gradient of the discrete
//! map the run computed, to round-off and the forward run's Newton
//! tolerance — not the gradient of the ODE's exact solution, and not the
//! derivative of the step-size controller's choices (which are piecewise
//! constant in the data; G1).
//!
//! Supported: [`Integrator::Esdirk`] (the default) and
//! [`Integrator::Esdirk5`], one code on their tableaux (both stiffly
//! accurate with an explicit first stage, G27), and
//! [`Integrator::Radau5`] (its fully implicit collocation system, solved
//! as one dense `3n×3n` system: `crate::radau_adjoint`, G25). Other
//! methods are refused with an error naming the ones that are supported.
//!
//! The system's parameters `p` enter through [`ParameterSystem`]: it gives
//! the vector–Jacobian product `wᵀ ∂a/∂p` at a state, so the backward pass
//! costs the same whatever the number of parameters (beyond those products).
//!
//! A system that offers the force form of its linearization
//! ([`ParameterSystem::force_jacobians`]: `M` and the derivatives of the
//! force residual, as a rod does) gets the transposed stage solves of G11:
//! `Sᵀν = Ã` with `S = M + hγ ∂r/∂q̇ + h²γ² ∂r/∂q`, by GMRES preconditioned
//! with its structured `M + h²γ²K + hγD`, no Jacobian of the acceleration
//! and no dense LU of a transposed stage matrix ([`AdjointSolver`]).
//! A system that also keeps the linearization as an O(N) operator
//! ([`ParameterSystem::force_linearization`] with its transposed products)
//! gets G12: the stages the reverse sweep solves with are linearized in
//! O(N) and used only through products, their GMRES preconditioned by the
//! dense LU the recomputation factored (G32).

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{DMatrix, DVector};

use crate::error::{IntegrateError, first_non_finite};
use crate::integrator::Integrator;
use crate::krylov::Gmres;
use crate::linalg::DenseLu;
use crate::methods::{
    Esdirk43, Esdirk54, EsdirkCoefficients as Coefficients, esdirk_explicit_part as explicit_part,
    esdirk_stage_values as stage_values,
};
use crate::system::SecondOrderSystem;

/// Newton iterations allowed when a stage is recomputed.
const MAX_NEWTON: usize = 50;

/// What switching the recomputation to a stage's own matrix costs, in
/// iterations of the force form's residual iteration (its dense derivatives
/// and LU ~30 iterations at 20 pieces, G11, less the few iterations the
/// switched iteration still takes): a slower predicted convergence
/// switches.
const SWITCH_ITERATIONS: f64 = 24.0;

/// The relative error of a recomputed stage's acceleration taken for its
/// round-off (G14): once converged, the changes of the iteration on the
/// gradient scenes' rods scatter 5e-14–2e-13 of the acceleration, the
/// noise of the inverse dynamics' force sums.
const RECOMPUTE_ROUNDOFF: f64 = 1e-13;

/// The integrators whose discrete adjoint [`adjoint_second_order`] has.
pub const ADJOINT_INTEGRATORS: [Integrator; 3] =
    [Integrator::Esdirk, Integrator::Esdirk5, Integrator::Radau5];

/// The tableau of an ESDIRK integrator in [`ADJOINT_INTEGRATORS`] (G27;
/// Radau IIA has its own pass, G25).
fn coefficients(integrator: Integrator) -> Option<Coefficients> {
    match integrator {
        Integrator::Esdirk => Some(Coefficients::of::<Esdirk43>()),
        Integrator::Esdirk5 => Some(Coefficients::of::<Esdirk54>()),
        _ => None,
    }
}

/// A [`SecondOrderSystem`] `q̈ = a(t, q, q̇; p)` with parameters `p`
/// (`n_params` of them) whose derivatives the backward pass needs.
pub trait ParameterSystem: SecondOrderSystem {
    /// Number of parameters `p`.
    fn n_params(&self) -> usize;

    /// Adds `wᵀ ∂a/∂pⱼ (t, q, q̇)` to `out[j]` for every parameter `j`
    /// (`out` has [`n_params`](Self::n_params) entries); `qdd` is
    /// `a(t, q, q̇)` (the backward pass has it). Must not allocate on every
    /// call: it runs at every stage of every step.
    fn accel_param_vjp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        w: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), Self::Error>;

    /// `∂a/∂p (t, q, q̇)` as an `n × n_params` matrix into `out`, for the
    /// forward sensitivities (G21; `qdd` is `a(t, q, q̇)`). The default
    /// forms it row by row from [`accel_param_vjp`](Self::accel_param_vjp)
    /// with the unit vectors (`n` products); a system that can apply
    /// `∂a/∂pⱼ` directly should.
    fn accel_param_jvp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), Self::Error> {
        let n = q.len();
        let np = self.n_params();
        let mut w = DVector::zeros(n);
        let mut row = vec![0.0; np];
        for r in 0..n {
            w[r] = 1.0;
            row.fill(0.0);
            self.accel_param_vjp(t, q, qd, qdd, &w, &mut row)?;
            for (c, v) in row.iter().enumerate() {
                out[(r, c)] = *v;
            }
            w[r] = 0.0;
        }
        Ok(())
    }

    /// Optional: the linearization in force form (docs/theory-control.md
    /// G11). For a system `M(q) q̈ = f(t, q, q̇)` with the force residual
    /// `r = M(q) q̈ − f`, writes `M(q)` (symmetric positive definite) into
    /// `mass`, `∂r/∂q` at fixed `q̇, q̈` into `dr_dq`, `∂r/∂q̇` into `dr_dqd`
    /// (all n×n) at the given `q̈`, and returns `Ok(true)`. Then
    /// `∂a/∂q = −M⁻¹ ∂r/∂q`, `∂a/∂q̇ = −M⁻¹ ∂r/∂q̇` at `q̈ = a`, and the
    /// backward pass never forms them. A system that provides it must also
    /// provide [`force_param_vjp`](Self::force_param_vjp). The default
    /// returns `Ok(false)`: the backward pass uses
    /// [`jacobians`](SecondOrderSystem::jacobians).
    #[allow(clippy::too_many_arguments)]
    fn force_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        dr_dq: &mut DMatrix<f64>,
        dr_dqd: &mut DMatrix<f64>,
    ) -> Result<bool, Self::Error> {
        let _ = (t, q, qd, qdd, mass, dr_dq, dr_dqd);
        Ok(false)
    }

    /// With [`force_jacobians`](Self::force_jacobians): adds
    /// `−zᵀ ∂r/∂pⱼ (t, q, q̇, q̈)` to `out[j]` — which is
    /// `wᵀ ∂a/∂pⱼ` for `w = M z` (`∂a/∂p = −M⁻¹ ∂r/∂p`, `M` symmetric), so
    /// [`accel_param_vjp`](Self::accel_param_vjp) is this after one solve
    /// with `M`, which the force form does not need.
    ///
    /// # Panics
    ///
    /// The default panics: the backward pass calls it only after
    /// `force_jacobians` returned `Ok(true)`.
    fn force_param_vjp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), Self::Error> {
        let _ = (t, q, qd, qdd, z, out);
        unimplemented!("force_param_vjp: the system provides force_jacobians but not this")
    }
    /// Optional, beside [`force_jacobians`](Self::force_jacobians)
    /// (docs/theory-control.md G12): writes `M(q)` into `mass` and keeps
    /// the force residual's `∂r/∂q`, `∂r/∂q̇` at `(t, q, q̇, q̈)` in `slot`
    /// (`slot` below the method's stage count, 7 at most; a later call on
    /// the same slot replaces it) as an operator for
    /// [`force_vjp`](Self::force_vjp), without forming them.
    /// Returns `Ok(true)`; the default `Ok(false)` (not offered: the
    /// backward pass forms the dense derivatives).
    #[allow(clippy::too_many_arguments)]
    fn force_linearization(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
    ) -> Result<bool, Self::Error> {
        let _ = (slot, t, q, qd, qdd, mass);
        Ok(false)
    }

    /// Optional, beside [`force_linearization`](Self::force_linearization)
    /// (docs/theory-control.md G15): the same operator kept in `slot`, and
    /// `M(q)` with it as the O(N) products of
    /// [`force_mass_product`](Self::force_mass_product) instead of a dense
    /// matrix. Returns `Ok(true)`; the default `Ok(false)` (not offered: the
    /// backward pass calls `force_linearization`).
    fn force_operators(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
    ) -> Result<bool, Self::Error> {
        let _ = (slot, t, q, qd, qdd);
        Ok(false)
    }

    /// With [`force_operators`](Self::force_operators): `M(q) v` into `out`
    /// at the linearization kept in `slot`. Runs at every GMRES iteration:
    /// must not allocate.
    ///
    /// # Panics
    ///
    /// The default panics: the backward pass calls it only after
    /// `force_operators` returned `Ok(true)`.
    fn force_mass_product(
        &mut self,
        slot: usize,
        v: &DVector<f64>,
        out: &mut DVector<f64>,
    ) -> Result<(), Self::Error> {
        let _ = (slot, v, out);
        unimplemented!("force_mass_product: the system provides force_operators but not this")
    }

    /// Optional, with [`force_linearization`](Self::force_linearization):
    /// [`force_param_vjp`](Self::force_param_vjp) at the point of the
    /// linearization kept in `slot` (its `t, q, q̇, q̈` are passed again),
    /// free to use what that linearization kept (docs/theory-control.md
    /// G13). Returns `Ok(true)` when it added the products; the default
    /// `Ok(false)` (nothing added: the backward pass calls
    /// `force_param_vjp`).
    #[allow(clippy::too_many_arguments)]
    fn force_param_vjp_kept(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<bool, Self::Error> {
        let _ = (slot, t, q, qd, qdd, z, out);
        Ok(false)
    }

    /// With [`force_linearization`](Self::force_linearization): `(∂r/∂q)ᵀu`
    /// into `out_q` and `(∂r/∂q̇)ᵀu` into `out_qd` at the linearization
    /// kept in `slot`. Runs at every GMRES iteration: must not allocate.
    ///
    /// # Panics
    ///
    /// The default panics: the backward pass calls it only after
    /// `force_linearization` returned `Ok(true)`.
    fn force_vjp(
        &mut self,
        slot: usize,
        u: &DVector<f64>,
        out_q: &mut DVector<f64>,
        out_qd: &mut DVector<f64>,
    ) -> Result<(), Self::Error> {
        let _ = (slot, u, out_q, out_qd);
        unimplemented!("force_vjp: the system provides force_linearization but not this")
    }
}

/// How [`adjoint_second_order_with`] solves the transposed stage systems.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AdjointSolver {
    /// The force form (G11) where the system provides
    /// [`ParameterSystem::force_jacobians`]: no Jacobian of the
    /// acceleration, the transposed stage system `Sᵀν = Ã` solved by GMRES
    /// preconditioned with the system's structured
    /// [`factor_shifted_mass`](SecondOrderSystem::factor_shifted_mass)
    /// (O(N) per iteration beside one dense product) — or, on a stage kept
    /// as an operator, with the recomputation's dense LU (G32) — a dense
    /// LU of `Sᵀ` where neither is offered or GMRES does not converge to
    /// round-off.
    /// Otherwise [`AdjointSolver::Dense`].
    #[default]
    Structured,
    /// The dense Jacobians of the acceleration and dense LUs of the
    /// transposed stage matrices (G5–G7): the reference.
    Dense,
}

/// The record of a forward run the backward pass needs: the times `tₙ`
/// (node 0 is the start), the accepted step sizes `hₙ` (`tₙ₊₁` is the end
/// of step `n`, exactly as the integrator landed on it) and the states
/// `(qₙ, q̇ₙ)` at every node, `16` bytes per coordinate and node. Optionally
/// ([`push_stages`](Self::push_stages)) the forward run's accelerations of
/// every implicit stage, `8·(s − 1)` bytes per coordinate and step more
/// (`s` stages: 40 for the ESDIRKs of six stages, 3.5× the tape): the
/// backward pass starts its recomputed stages from them (G34).
#[derive(Clone, Debug)]
pub struct Tape {
    n: usize,
    t: Vec<f64>,
    h: Vec<f64>,
    q: Vec<f64>,
    v: Vec<f64>,
    /// Implicit stages kept per step (`s − 1`; 0: none yet), and whether a
    /// step came without them (then none are kept).
    stage_count: usize,
    stages_dropped: bool,
    /// `A₁ … A_{s−1}` of every step, step by step.
    stage_acc: Vec<f64>,
}

impl Tape {
    /// A tape starting at `(t0, q0, q̇0)`.
    pub fn new(t0: f64, q0: &[f64], qd0: &[f64]) -> Self {
        assert_eq!(q0.len(), qd0.len(), "q0 and qdot0 differ in length");
        Self {
            n: q0.len(),
            t: vec![t0],
            h: Vec::new(),
            q: q0.to_vec(),
            v: qd0.to_vec(),
            stage_count: 0,
            stages_dropped: false,
            stage_acc: Vec::new(),
        }
    }

    /// Records the stage accelerations `A₀ … A_{s−1}` of the step just
    /// [`push`](Self::push)ed (a method's [`StepInfo::stages`](crate::StepInfo)),
    /// of which the tape keeps the implicit ones, `A₁ … A_{s−1}` (stage 0 is
    /// evaluated again by the backward pass). Every step must have them
    /// with the same stage count: a step recorded without them, or with
    /// another count, drops them all (the backward pass then starts its
    /// stages from its predictor, G3). They are starting points only: the
    /// gradient does not depend on them beyond round-off (G34).
    pub fn push_stages(&mut self, stages: &[DVector<f64>]) {
        let k = self.steps();
        if self.stages_dropped || k == 0 {
            return;
        }
        let count = stages.len().saturating_sub(1);
        if k == 1 && self.stage_count == 0 {
            self.stage_count = count;
        }
        let complete = self.stage_acc.len() == (k - 1) * self.stage_count * self.n;
        if count == 0
            || count != self.stage_count
            || !complete
            || stages.iter().any(|a| a.len() != self.n)
        {
            self.drop_stages();
            return;
        }
        for a in &stages[1..] {
            self.stage_acc.extend_from_slice(a.as_slice());
        }
    }

    fn drop_stages(&mut self) {
        self.stages_dropped = true;
        self.stage_count = 0;
        self.stage_acc = Vec::new();
    }

    /// The implicit stages kept per step (`s − 1` for a tableau of `s`
    /// stages), or 0 when the tape has none for every step.
    pub fn stage_count(&self) -> usize {
        if self.stages_dropped || self.stage_acc.len() != self.steps() * self.stage_count * self.n {
            0
        } else {
            self.stage_count
        }
    }

    /// The forward run's acceleration of implicit stage `i` (`1 ≤ i ≤`
    /// [`stage_count`](Self::stage_count)) of step `k`, if the tape has it.
    pub fn stage_acceleration(&self, k: usize, i: usize) -> Option<&[f64]> {
        let count = self.stage_count();
        if i == 0 || i > count || k >= self.steps() {
            return None;
        }
        let at = ((k * count) + i - 1) * self.n;
        Some(&self.stage_acc[at..at + self.n])
    }

    /// Bytes of the recorded data (times, step sizes, states and stages).
    pub fn bytes(&self) -> usize {
        8 * (self.t.len() + self.h.len() + self.q.len() + self.v.len() + self.stage_acc.len())
    }

    /// Records an accepted step of size `h` that ended at `(t, q, q̇)`.
    pub fn push(&mut self, t: f64, h: f64, q: &[f64], qd: &[f64]) {
        assert_eq!(q.len(), self.n, "q has the wrong length");
        assert_eq!(qd.len(), self.n, "qdot has the wrong length");
        self.t.push(t);
        self.h.push(h);
        self.q.extend_from_slice(q);
        self.v.extend_from_slice(qd);
        if self.stage_count > 0
            && self.stage_acc.len() != (self.steps() - 1) * self.stage_count * self.n
        {
            // The step before this one came without its stages.
            self.drop_stages();
        }
    }

    /// Number of nodes (accepted steps + 1).
    pub fn nodes(&self) -> usize {
        self.t.len()
    }

    /// Number of accepted steps.
    pub fn steps(&self) -> usize {
        self.h.len()
    }

    /// Dimension of `q`.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Time of node `k` \[s\].
    pub fn time(&self, k: usize) -> f64 {
        self.t[k]
    }

    /// The step size of step `k` (from node `k` to node `k + 1`) \[s\].
    pub fn step_size(&self, k: usize) -> f64 {
        self.h[k]
    }

    /// `q` at node `k`.
    pub fn q(&self, k: usize) -> &[f64] {
        &self.q[k * self.n..(k + 1) * self.n]
    }

    /// `q̇` at node `k`.
    pub fn qd(&self, k: usize) -> &[f64] {
        &self.v[k * self.n..(k + 1) * self.n]
    }
}

/// The gradient of a loss `L` through a whole run: `∂L/∂q₀`, `∂L/∂q̇₀` and
/// `∂L/∂p` (one per parameter of the [`ParameterSystem`]).
#[derive(Clone, Debug, PartialEq)]
pub struct AdjointGradient {
    /// `∂L/∂q(t₀)`.
    pub dq0: DVector<f64>,
    /// `∂L/∂q̇(t₀)`.
    pub dqd0: DVector<f64>,
    /// `∂L/∂pⱼ`.
    pub dp: Vec<f64>,
    /// Linearizations of the backward pass (one per stage and step, plus the
    /// recomputation's switches): the dense Jacobians of the acceleration
    /// ([`AdjointSolver::Dense`]) or of the force residual (the force form,
    /// G11), or the O(N) operators of a system that keeps them (G12).
    pub jacobian_evaluations: usize,
    /// Acceleration evaluations of the recomputed stages.
    pub accel_evaluations: usize,
    /// Dense LU factorizations (the recomputing Newton iteration's, and
    /// the transposed stage matrices solved directly).
    pub dense_factorizations: usize,
    /// GMRES iterations of the transposed stage solves (the force form).
    pub krylov_iterations: usize,
}

/// Adds the explicit loss derivatives `(∂ℓ/∂qₖ, ∂ℓ/∂q̇ₖ)` at node `k` to
/// its second and third arguments ([`adjoint_second_order`]).
pub type Seed<'a> = dyn FnMut(usize, &mut DVector<f64>, &mut DVector<f64>) + 'a;

/// The discrete adjoint of a run recorded on `tape` with `integrator`
/// (docs/theory-control.md G1–G8, G11): `L = Σₖ ℓₖ(qₖ, q̇ₖ)` over the
/// tape's nodes, with `seed(k, ∂L/∂qₖ, ∂L/∂q̇ₖ)` adding the explicit
/// derivatives of the loss at node `k` (called once per node, last node
/// first; leave them alone at a node without loss).
/// [`adjoint_second_order_with`] with [`AdjointSolver::Structured`].
///
/// Errors: an integrator without an adjoint ([`ADJOINT_INTEGRATORS`]), a
/// tape of another dimension than the system, a failing or non-finite
/// evaluation, a singular transposed stage matrix, a recomputed stage whose
/// Newton iteration does not converge.
pub fn adjoint_second_order<Sys: ParameterSystem>(
    sys: &mut Sys,
    integrator: Integrator,
    tape: &Tape,
    seed: &mut Seed<'_>,
) -> Result<AdjointGradient, IntegrateError> {
    adjoint_second_order_with(sys, integrator, tape, seed, AdjointSolver::Structured)
}

/// [`adjoint_second_order`] with the transposed stage systems solved as
/// `solver` says. The two solvers give the same gradient to round-off
/// (G11).
pub fn adjoint_second_order_with<Sys: ParameterSystem>(
    sys: &mut Sys,
    integrator: Integrator,
    tape: &Tape,
    seed: &mut Seed<'_>,
    solver: AdjointSolver,
) -> Result<AdjointGradient, IntegrateError> {
    if integrator == Integrator::Radau5 {
        // Radau IIA's collocation system is solved densely whatever
        // `solver` says (G25).
        return crate::radau_adjoint::adjoint(sys, tape, seed);
    }
    let (n, tab) = check_request(sys.dim(), integrator, tape)?;
    let mut w = EsdirkAdjoint::new(tab, n, sys.n_params(), solver == AdjointSolver::Structured);
    let mut lq = DVector::zeros(n);
    let mut lv = DVector::zeros(n);
    let last = tape.nodes() - 1;
    seed(last, &mut lq, &mut lv);
    for k in (0..tape.steps()).rev() {
        w.step(sys, tape, k, &mut lq, &mut lv)?;
        seed(k, &mut lq, &mut lv);
    }
    if let Some(index) = first_non_finite(lq.as_slice())
        .or_else(|| first_non_finite(lv.as_slice()))
        .or_else(|| first_non_finite(&w.dp))
    {
        return Err(IntegrateError::NonFinite {
            t: tape.time(0),
            h: 0.0,
            what: "gradient",
            index,
        });
    }
    Ok(AdjointGradient {
        dq0: lq,
        dqd0: lv,
        dp: w.dp,
        jacobian_evaluations: w.jacobians,
        accel_evaluations: w.accels,
        dense_factorizations: w.factorizations,
        krylov_iterations: w.krylov,
    })
}

/// The checks a gradient request passes before either pass (the adjoint,
/// the forward sensitivities): an integrator with the discrete derivatives
/// ([`ADJOINT_INTEGRATORS`]) and a tape of the system's dimension `n`;
/// returns `n` and the integrator's tableau.
pub(crate) fn check_request(
    n: usize,
    integrator: Integrator,
    tape: &Tape,
) -> Result<(usize, Coefficients), IntegrateError> {
    let Some(tab) = coefficients(integrator) else {
        let names: Vec<&str> = ADJOINT_INTEGRATORS.iter().map(|i| i.name()).collect();
        return Err(IntegrateError::InvalidInput {
            what: format!(
                "gradients need the discrete adjoint of the integrator; {} has none \
                 (supported: {})",
                integrator.name(),
                names.join(", ")
            ),
        });
    };
    if tape.dim() != n {
        return Err(IntegrateError::InvalidInput {
            what: format!("the tape has {} coordinates, the system {n}", tape.dim()),
        });
    }
    Ok((n, tab))
}

/// Up to this many coordinates the step start's `M₀⁻¹` (G6, G11) is a
/// dense Cholesky of the `M₀` stage 0 formed anyway (`n³/3` flops: ~22 k
/// instructions at 24 coordinates) instead of the structured O(N)
/// factorization (~62 k at 24 coordinates of a planar rod): the two cost
/// about the same near 40 coordinates (G33).
const DENSE_MASS_MAX: usize = 40;

/// The stages whose `cᵢ` lies strictly inside this band iterate with the
/// mean of the step start's and the step end's matrices; those before it
/// with the start's, those after it with the end's (G35).
const MID_BAND: (f64, f64) = (0.2, 0.8);

/// GMRES iterations per cycle and cycles of a transposed stage solve
/// before it falls back to the dense LU (G11).
const KRYLOV_ITERATIONS: usize = 40;
const KRYLOV_CYCLES: usize = 3;

/// The buffers of the ESDIRK backward pass (allocated once per pass).
struct EsdirkAdjoint {
    /// The tableau (G27): `s` stages, every per-stage buffer below has `s`.
    tab: Coefficients,
    n: usize,
    /// The force form (G11): `jq`, `jv` hold `∂r/∂q`, `∂r/∂q̇` and `mass`
    /// `M`; otherwise (or once the system declined it) `∂a/∂q`, `∂a/∂q̇`.
    force: bool,
    q: DVector<f64>,
    v: DVector<f64>,
    qs: Vec<DVector<f64>>,
    vs: Vec<DVector<f64>>,
    accs: Vec<DVector<f64>>,
    /// The node whose step-start acceleration `accs[0]` holds (the pass
    /// runs backwards, so at step `k` it is node `k + 1`'s, the end of the
    /// step: the recomputation's predictor), and a copy of it.
    a0_node: Option<usize>,
    a_end: DVector<f64>,
    /// Whether stage 0's matrices were in the force form (`force` then).
    a0_force: bool,
    /// `∂r/∂q` (or `∂a/∂q`), `∂r/∂q̇` (or `∂a/∂q̇`), `M` of each stage, and
    /// in the extra slot [`END`](Self::end) those of the step end: the
    /// stage 0 of the step the pass did before (G35).
    jq: Vec<DMatrix<f64>>,
    jv: Vec<DMatrix<f64>>,
    /// `M` at each stage (force form).
    mass: Vec<DMatrix<f64>>,
    /// `S = M + hγ ∂r/∂q̇ + h²γ² ∂r/∂q` of each implicit stage (force form,
    /// formed only where the system keeps no operator).
    shifted: Vec<DMatrix<f64>>,
    /// Stage `i`'s `∂r/∂q`, `∂r/∂q̇` are kept by the system in slot `i`
    /// (G12): products by [`ParameterSystem::force_vjp`], `jq`, `jv`,
    /// `shifted` not formed.
    ops: Vec<bool>,
    /// Stage `i`'s `M` is kept with its operator too (G15): `M v` by
    /// [`ParameterSystem::force_mass_product`], `mass[i]` not formed.
    mass_ops: Vec<bool>,
    /// The products' outputs `(∂r/∂q)ᵀu`, `(∂r/∂q̇)ᵀu`.
    pq: DVector<f64>,
    pv: DVector<f64>,
    /// `(I − hγJ)ᵀ` (force form: `Sᵀ`) of each implicit stage, factored;
    /// slot 0: the (untransposed) step-start matrix of the recomputing
    /// Newton iteration; slot [`END`](Self::end): the step end's (G35).
    lus: Vec<DenseLu>,
    /// The step start's `M₀` factored by Cholesky (G33).
    chol: DenseLu,
    /// Force form: `M` of the matrix in slot [`mid`](Self::mid) of `lus`,
    /// the mean of the step start's and the step end's (G35).
    mid_mass: DMatrix<f64>,
    /// Force form: `‖Sᵀ‖∞` of the matrix factored (untransposed) in each
    /// slot of `lus`, for GMRES's stopping test (G32).
    lu_norms: Vec<f64>,
    /// Force form: the slot of `lus` whose `S` the recomputation of stage
    /// `i` last iterated with (the step start's, or the stage's own after
    /// a switch): its transposed solves precondition stage `i`'s GMRES
    /// (G32).
    lu_slot: Vec<usize>,
    gmres: Gmres,
    qhat: DVector<f64>,
    vhat: DVector<f64>,
    f: DVector<f64>,
    g: DVector<f64>,
    qbar: Vec<DVector<f64>>,
    vbar: Vec<DVector<f64>>,
    abar: Vec<DVector<f64>>,
    mu: DVector<f64>,
    rhs: DVector<f64>,
    qhat_bar: DVector<f64>,
    vhat_bar: DVector<f64>,
    dp: Vec<f64>,
    jacobians: usize,
    accels: usize,
    factorizations: usize,
    krylov: usize,
}

impl EsdirkAdjoint {
    /// The slot of the step end's matrices in `jq`, `jv`, `mass`, `lus`
    /// (G35): the one after the stages'.
    fn end(&self) -> usize {
        self.tab.stages()
    }

    /// The slot in `lus` of the mean of the step start's and the step
    /// end's matrices (G35).
    fn mid(&self) -> usize {
        self.tab.stages() + 1
    }

    fn new(tab: Coefficients, n: usize, np: usize, force: bool) -> Self {
        let s = tab.stages();
        let z = DVector::zeros(n);
        let m = DMatrix::zeros(n, n);
        // The force form's matrices are allocated only when it is asked for.
        let fm = if force {
            m.clone()
        } else {
            DMatrix::zeros(0, 0)
        };
        Self {
            tab,
            n,
            force,
            q: z.clone(),
            v: z.clone(),
            qs: (0..s).map(|_| z.clone()).collect(),
            vs: (0..s).map(|_| z.clone()).collect(),
            accs: (0..s).map(|_| z.clone()).collect(),
            a0_node: None,
            a_end: z.clone(),
            a0_force: force,
            mid_mass: fm.clone(),
            jq: (0..=s).map(|_| m.clone()).collect(),
            jv: (0..=s).map(|_| m.clone()).collect(),
            mass: (0..=s).map(|_| fm.clone()).collect(),
            shifted: (0..s).map(|_| fm.clone()).collect(),
            ops: vec![false; s],
            mass_ops: vec![false; s],
            pq: z.clone(),
            pv: z.clone(),
            lus: (0..s + 2).map(|_| DenseLu::new(n)).collect(),
            chol: DenseLu::new(n),
            lu_norms: vec![0.0; s + 2],
            lu_slot: vec![0; s],
            gmres: Gmres::new(if force { n } else { 0 }, KRYLOV_ITERATIONS.min(n)),
            qhat: z.clone(),
            vhat: z.clone(),
            f: z.clone(),
            g: z.clone(),
            qbar: (0..s).map(|_| z.clone()).collect(),
            vbar: (0..s).map(|_| z.clone()).collect(),
            abar: (0..s).map(|_| z.clone()).collect(),
            mu: z.clone(),
            rhs: z.clone(),
            qhat_bar: z.clone(),
            vhat_bar: z,
            dp: vec![0.0; np],
            jacobians: 0,
            accels: 0,
            factorizations: 0,
            krylov: 0,
        }
    }

    /// The linearization at stage `i`, `(tᵢ, qs[i], vs[i])` with the
    /// acceleration `accs[qdd]`: the force form's `M`, `∂r/∂q`, `∂r/∂q̇` (and
    /// `S` into `shifted[i]` when `keep`), or the acceleration's Jacobians
    /// (the dense form, or a system without the force form: then the pass
    /// continues in the dense form).
    #[allow(clippy::too_many_arguments)]
    fn linearize<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        i: usize,
        ti: f64,
        qdd: usize,
        h: f64,
        keep: bool,
    ) -> Result<(), Sys::Error> {
        self.jacobians += 1;
        self.ops[i] = false;
        self.mass_ops[i] = false;
        // The stages the reverse sweep solves with: the O(N) operator
        // where the system keeps one (G12), with `M` as products where it
        // keeps that too (G15).
        if self.force
            && keep
            && sys.force_operators(i, ti, &self.qs[i], &self.vs[i], &self.accs[qdd])?
        {
            self.ops[i] = true;
            self.mass_ops[i] = true;
            return Ok(());
        }
        if self.force
            && keep
            && sys.force_linearization(
                i,
                ti,
                &self.qs[i],
                &self.vs[i],
                &self.accs[qdd],
                &mut self.mass[i],
            )?
        {
            self.ops[i] = true;
            return Ok(());
        }
        if self.force {
            if sys.force_jacobians(
                ti,
                &self.qs[i],
                &self.vs[i],
                &self.accs[qdd],
                &mut self.mass[i],
                &mut self.jq[i],
                &mut self.jv[i],
            )? {
                if keep {
                    let gamma = self.tab.gamma;
                    let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
                    let s = self.shifted[i].as_mut_slice();
                    let (m, jv, jq) = (&self.mass[i], &self.jv[i], &self.jq[i]);
                    for (k, x) in s.iter_mut().enumerate() {
                        *x = m.as_slice()[k] + hg * jv.as_slice()[k] + hg2 * jq.as_slice()[k];
                    }
                }
                return Ok(());
            }
            // Declined (a model the force form does not cover): the dense
            // form from here on (this step's stage 0 comes first).
            debug_assert_eq!(i, 0, "the force form declined after its first stage");
            self.force = false;
        }
        sys.jacobians(
            ti,
            &self.qs[i],
            &self.vs[i],
            &mut self.jq[i],
            &mut self.jv[i],
        )
    }

    /// Fills `lus[slot]` with the stage matrix of stage `j` — `I − hγJv −
    /// h²γ²Jq` of the acceleration's Jacobians, or the force form's
    /// `M + hγ ∂r/∂q̇ + h²γ² ∂r/∂q` — transposed when `transpose`, and
    /// factors it.
    fn factor(&mut self, slot: usize, j: usize, h: f64, transpose: bool) -> bool {
        self.factorizations += 1;
        if self.force {
            let gamma = self.tab.gamma;
            let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
            let m = self.lus[slot].matrix_mut();
            let (mass, jq, jv) = (&self.mass[j], &self.jq[j], &self.jv[j]);
            // ‖Sᵀ‖∞ of the untransposed `S`: its largest column sum.
            let mut norm: f64 = 0.0;
            for c in 0..self.n {
                let mut sum = 0.0;
                for r in 0..self.n {
                    let (a, b) = if transpose { (c, r) } else { (r, c) };
                    let x = mass[(a, b)] + hg * jv[(a, b)] + hg2 * jq[(a, b)];
                    m[(r, c)] = x;
                    sum += x.abs();
                }
                norm = norm.max(sum);
            }
            self.lu_norms[slot] = norm;
            return self.lus[slot].factor();
        }
        stage_matrix(
            &mut self.lus[slot],
            &self.jq[j],
            &self.jv[j],
            self.tab.gamma,
            h,
            transpose,
        )
    }

    /// Fills `lus[mid]` with the mean of the stage matrices of the step
    /// start (slot 0) and the step end ([`end`](Self::end)), both at this
    /// step's `h`, and factors it (G35); force form: their `M`s' mean into
    /// `mid_mass` too.
    fn factor_mid(&mut self, h: f64) -> bool {
        self.factorizations += 1;
        let (mid, end) = (self.mid(), self.end());
        let gamma = self.tab.gamma;
        let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
        let m = self.lus[mid].matrix_mut();
        let n = self.n;
        let (jq0, jq1) = (self.jq[0].as_slice(), self.jq[end].as_slice());
        let (jv0, jv1) = (self.jv[0].as_slice(), self.jv[end].as_slice());
        if self.force {
            let (m0, m1) = (self.mass[0].as_slice(), self.mass[end].as_slice());
            let mm = self.mid_mass.as_mut_slice();
            let mut norm: f64 = 0.0;
            for (c, col) in m.as_mut_slice().chunks_exact_mut(n).enumerate() {
                let mut sum = 0.0;
                for (r, x) in col.iter_mut().enumerate() {
                    let k = c * n + r;
                    let mass = 0.5 * (m0[k] + m1[k]);
                    mm[k] = mass;
                    *x = mass + hg * (0.5 * (jv0[k] + jv1[k])) + hg2 * (0.5 * (jq0[k] + jq1[k]));
                    sum += x.abs();
                }
                norm = norm.max(sum);
            }
            self.lu_norms[mid] = norm;
        } else {
            for (c, col) in m.as_mut_slice().chunks_exact_mut(n).enumerate() {
                for (r, x) in col.iter_mut().enumerate() {
                    let k = c * n + r;
                    let d = if r == c { 1.0 } else { 0.0 };
                    *x = d - hg * (0.5 * (jv0[k] + jv1[k])) - hg2 * (0.5 * (jq0[k] + jq1[k]));
                }
            }
        }
        self.lus[mid].factor()
    }

    /// The Newton correction of a recomputed stage, `W⁻¹ g` with the matrix
    /// of `slot` (force form: `S⁻¹ M g`, `W = M⁻¹S`), in place in `g`.
    fn newton_correction(&mut self, slot: usize) {
        if self.force {
            let mass = if slot == self.mid() {
                &self.mid_mass
            } else {
                &self.mass[slot]
            };
            self.mu.gemv(1.0, mass, &self.g, 0.0);
            self.g.copy_from(&self.mu);
        }
        self.lus[slot].solve_in_place(&mut self.g);
    }

    /// One step backwards: `(λq, λv)` at node `k + 1` in, at node `k` out
    /// (G4–G7, G11); adds the step's `∂L/∂p` to `dp`.
    fn step<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        tape: &Tape,
        k: usize,
        lq: &mut DVector<f64>,
        lv: &mut DVector<f64>,
    ) -> Result<(), IntegrateError> {
        let n = self.n;
        let t = tape.time(k);
        let t_new = tape.time(k + 1);
        let h = tape.step_size(k);
        let (s, c, a) = (self.tab.stages(), self.tab.c, self.tab.a);
        let gamma = self.tab.gamma;
        let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
        let err = |what: &'static str| {
            move |e: Sys::Error| IntegrateError::System {
                t,
                h,
                what,
                source: Box::new(e),
            }
        };
        self.q.copy_from_slice(tape.q(k));
        self.v.copy_from_slice(tape.qd(k));
        // The step end's acceleration a(tₙ₊₁, yₙ₊₁), from the step done
        // before (the next one in time), for the predictor (G3).
        let end = self.a0_node == Some(k + 1);
        if end {
            self.a_end.copy_from(&self.accs[0]);
        }
        // Its matrices too, `M`, `∂r/∂q`, `∂r/∂q̇` at (tₙ₊₁, yₙ₊₁): the
        // later stages iterate with them (G35). The same `h` finds their
        // LU done; another factors them again.
        let end_slot = self.end();
        let use_end = end && self.a0_force == self.force;
        if use_end {
            self.jq.swap(0, end_slot);
            self.jv.swap(0, end_slot);
            self.mass.swap(0, end_slot);
            if h == tape.step_size(k + 1) {
                self.lus.swap(0, end_slot);
                self.lu_norms.swap(0, end_slot);
            } else if !self.factor(end_slot, end_slot, h, false) {
                return Err(singular(t_new, h));
            }
        }
        self.a0_node = None;
        // Stage 0: the step start (G2).
        self.qs[0].copy_from(&self.q);
        self.vs[0].copy_from(&self.v);
        sys.accel(t, &self.q, &self.v, &mut self.accs[0])
            .map_err(err("accel"))?;
        self.accels += 1;
        self.a0_node = Some(k);
        self.linearize(sys, 0, t, 0, h, false)
            .map_err(err("jacobian"))?;
        self.a0_force = self.force;
        // Stages in the middle of the step iterate with the mean of the
        // start's and the end's matrices (G35).
        let mid_slot = self.mid();
        let use_mid = use_end && (1..s).any(|i| c[i] > MID_BAND.0 && c[i] < MID_BAND.1);
        if use_mid && !self.factor_mid(h) {
            return Err(singular(t, h));
        }
        if !self.factor(0, 0, h, false) {
            return Err(singular(t, h));
        }
        // Stages 1..s−1, recomputed (G3): simplified Newton on the
        // step-start matrix, to round-off.
        for i in 1..s {
            let ti = if i == s - 1 { t_new } else { t + c[i] * h };
            explicit_part(
                &a[i][..i],
                h,
                &self.q,
                &self.v,
                &self.vs,
                &self.accs,
                &mut self.qhat,
                &mut self.vhat,
            );
            // The starting guess: the forward run's own stage where the
            // tape kept it (G34); else the cubic Hermite interpolant of the
            // velocity through (q̇ₙ, aₙ) and (q̇ₙ₊₁, aₙ₊₁), differentiated at
            // cᵢ (G3); without the step end, the previous stage's.
            {
                let (done, rest) = self.accs.split_at_mut(i);
                let stored = if tape.stage_count() == s - 1 {
                    tape.stage_acceleration(k, i)
                } else {
                    None
                };
                if let Some(x) = stored {
                    rest[0].copy_from_slice(x);
                } else if end {
                    let th = c[i];
                    let wd = (6.0 * th - 6.0 * th * th) / h;
                    let w0 = 3.0 * th * th - 4.0 * th + 1.0;
                    let w1 = 3.0 * th * th - 2.0 * th;
                    let (v0, v1) = (tape.qd(k), tape.qd(k + 1));
                    for r in 0..n {
                        rest[0][r] = wd * (v1[r] - v0[r]) + w0 * done[0][r] + w1 * self.a_end[r];
                    }
                } else {
                    rest[0].copy_from(&done[i - 1]);
                }
            }
            let mut prev = f64::INFINITY;
            let mut prev2 = f64::INFINITY;
            let mut converged = false;
            // The LU the iteration solves with: the step-start matrix, or
            // the step end's for a stage nearer the end (G35), or (after a
            // slow iteration) the stage's own at its iterate.
            let start = if !use_end || c[i] <= MID_BAND.0 {
                0
            } else if c[i] < MID_BAND.1 {
                mid_slot
            } else {
                end_slot
            };
            let mut slot = start;
            // Iterations done with the present `slot` (the contraction rate
            // is measured on one matrix only).
            let mut on_slot = 0;
            for iteration in 0..MAX_NEWTON {
                stage_values(
                    hg,
                    &self.qhat,
                    &self.vhat,
                    &self.accs[i],
                    &mut self.vs[i],
                    &mut self.qs[i],
                );
                // The force form iterates on the force residual
                // r = ID(Qᵢ, Vᵢ, x) − τ = M(Qᵢ)(x − a): an inverse dynamics
                // instead of a forward one, and `S⁻¹r` for `W⁻¹(x − a)`.
                let forced = self.force
                    && sys
                        .force_residual(ti, &self.qs[i], &self.vs[i], &self.accs[i], &mut self.g)
                        .map_err(err("force residual"))?;
                self.accels += 1;
                if forced {
                    self.lus[slot].solve_in_place(&mut self.g);
                } else {
                    sys.accel(ti, &self.qs[i], &self.vs[i], &mut self.f)
                        .map_err(err("accel"))?;
                    for r in 0..n {
                        self.g[r] = self.accs[i][r] - self.f[r];
                    }
                    self.newton_correction(slot);
                }
                let x = &mut self.accs[i];
                *x -= &self.g;
                let dx = self.g.amax();
                let size = x.amax();
                if !(dx.is_finite() && size.is_finite()) {
                    return Err(IntegrateError::NonFinite {
                        t: ti,
                        h,
                        what: "recomputed stage",
                        index: first_non_finite(x.as_slice()).unwrap_or(0),
                    });
                }
                // Converged to round-off, or stalled there: the change no
                // longer shrinks and is already tiny, relative to the
                // acceleration or (a stage near rest, whose acceleration is
                // a small difference of large forces and carries their
                // round-off) by what it moves the stage's position,
                // `h²γ² δA`, relative to that position.
                let moved = hg2 * dx <= 1e-13 * self.qs[i].amax().max(hg * self.vs[i].amax());
                // Or the error left after this change, `ρ/(1 − ρ)·|δA|` by
                // the contraction rate `ρ` of the last two iterations on
                // this matrix (the larger, for the alternating iteration
                // below), is below the acceleration's round-off (G14).
                on_slot += 1;
                let rate = match on_slot {
                    0 | 1 => f64::INFINITY,
                    2 => dx / prev,
                    _ => (dx / prev).max(prev / prev2),
                };
                let left = rate < 1.0 && rate / (1.0 - rate) * dx <= RECOMPUTE_ROUNDOFF * size;
                if dx <= 4.0 * f64::EPSILON * size
                    || left
                    || (dx >= 0.5 * prev && (dx <= 1e-10 * size || moved))
                {
                    converged = true;
                    break;
                }
                // A long stiff step can leave the step-start matrix a poor
                // model of the stage's (the forward run stopped at its
                // tolerance; this iteration must reach round-off): a slow
                // contraction switches to the stage's own Jacobian at the
                // current iterate (once: the rest is at round-off).
                // In the force form an iteration (one inverse dynamics and a
                // solve) costs ~1/30 of a linearization (the inverse
                // dynamics' dense derivatives and an LU): only a contraction
                // expected to need more iterations to round-off than a
                // switch costs, or a long one, switches. The rate is
                // measured over the last two iterations: the step-start
                // matrix's iteration often alternates a fast and a slow
                // iteration (0.01, then 0.5–1.9 on a six-strain chain, 4×
                // per two iterations or better), which one slow iteration
                // alone took for a stall.
                let slow = if self.force {
                    let rate = (dx / prev2).sqrt();
                    let left = if rate < 1.0 {
                        (1e-13 * size / dx).ln() / rate.ln()
                    } else {
                        f64::INFINITY
                    };
                    left > SWITCH_ITERATIONS || iteration >= 16
                } else {
                    dx > 0.25 * prev
                };
                if slot == start && iteration >= 2 && slow {
                    stage_values(
                        hg,
                        &self.qhat,
                        &self.vhat,
                        &self.accs[i],
                        &mut self.vs[i],
                        &mut self.qs[i],
                    );
                    self.linearize(sys, i, ti, i, h, false)
                        .map_err(err("jacobian"))?;
                    if !self.factor(i, i, h, false) {
                        return Err(singular(ti, h));
                    }
                    slot = i;
                    on_slot = 0;
                }
                prev2 = prev;
                prev = dx;
            }
            self.lu_slot[i] = slot;
            if !converged {
                return Err(IntegrateError::NewtonNonConvergence {
                    t,
                    h,
                    iterations: MAX_NEWTON,
                    what: "recomputed stage of the adjoint",
                });
            }
            stage_values(
                hg,
                &self.qhat,
                &self.vhat,
                &self.accs[i],
                &mut self.vs[i],
                &mut self.qs[i],
            );
            self.linearize(sys, i, ti, i, h, true)
                .map_err(err("jacobian"))?;
            // The dense form factors Wᵢᵀ now; the force form solves with
            // Sᵢᵀ in the sweep (G11).
            if !self.force && !self.factor(i, i, h, true) {
                return Err(singular(ti, h));
            }
        }
        // The reverse sweep (G5–G7).
        for i in 0..s {
            self.qbar[i].fill(0.0);
            self.vbar[i].fill(0.0);
            self.abar[i].fill(0.0);
        }
        self.qbar[s - 1].copy_from(lq);
        self.vbar[s - 1].copy_from(lv);
        lq.fill(0.0);
        lv.fill(0.0);
        for i in (1..s).rev() {
            let ti = if i == s - 1 { t_new } else { t + c[i] * h };
            // Ã = Ā + hγ V̄ + h²γ² Q̄.
            for r in 0..n {
                self.rhs[r] = self.abar[i][r] + hg * self.vbar[i][r] + hg2 * self.qbar[i][r];
            }
            if self.force {
                // Sᵀν = Ã (G11): μ = Mν, Jqᵀμ = −(∂r/∂q)ᵀν.
                if !self
                    .solve_transposed(sys, i, ti, h)
                    .map_err(err("transposed stage solve"))?
                {
                    return Err(singular(ti, h));
                }
                let nu = &self.mu;
                self.qhat_bar.copy_from(&self.qbar[i]);
                self.vhat_bar.copy_from(&self.vbar[i]);
                self.vhat_bar.axpy(hg, &self.qbar[i], 1.0);
                if self.ops[i] {
                    sys.force_vjp(i, nu, &mut self.pq, &mut self.pv)
                        .map_err(err("transposed products"))?;
                    self.qhat_bar.axpy(-1.0, &self.pq, 1.0);
                    self.vhat_bar.axpy(-hg, &self.pq, 1.0);
                    self.vhat_bar.axpy(-1.0, &self.pv, 1.0);
                } else {
                    self.qhat_bar.gemv_tr(-1.0, &self.jq[i], nu, 1.0);
                    self.vhat_bar.gemv_tr(-hg, &self.jq[i], nu, 1.0);
                    self.vhat_bar.gemv_tr(-1.0, &self.jv[i], nu, 1.0);
                }
                // The parameter products on the kept linearization where
                // the system has them (G13), else by themselves.
                let kept = self.ops[i]
                    && sys
                        .force_param_vjp_kept(
                            i,
                            ti,
                            &self.qs[i],
                            &self.vs[i],
                            &self.accs[i],
                            nu,
                            &mut self.dp,
                        )
                        .map_err(err("parameter derivatives"))?;
                if !kept {
                    sys.force_param_vjp(
                        ti,
                        &self.qs[i],
                        &self.vs[i],
                        &self.accs[i],
                        nu,
                        &mut self.dp,
                    )
                    .map_err(err("parameter derivatives"))?;
                }
            } else {
                // μ = W⁻ᵀ Ã; q̂̄ = Q̄ + Jqᵀμ; v̂̄ = V̄ + hγ Q̄ + hγ Jqᵀμ + Jvᵀμ.
                self.mu.copy_from(&self.rhs);
                self.lus[i].solve_in_place(&mut self.mu);
                self.qhat_bar.copy_from(&self.qbar[i]);
                self.qhat_bar.gemv_tr(1.0, &self.jq[i], &self.mu, 1.0);
                self.vhat_bar.copy_from(&self.vbar[i]);
                self.vhat_bar.axpy(hg, &self.qbar[i], 1.0);
                self.vhat_bar.gemv_tr(hg, &self.jq[i], &self.mu, 1.0);
                self.vhat_bar.gemv_tr(1.0, &self.jv[i], &self.mu, 1.0);
                sys.accel_param_vjp(
                    ti,
                    &self.qs[i],
                    &self.vs[i],
                    &self.accs[i],
                    &self.mu,
                    &mut self.dp,
                )
                .map_err(err("parameter derivatives"))?;
            }
            *lq += &self.qhat_bar;
            *lv += &self.vhat_bar;
            for (j, &aij) in a[i][..i].iter().enumerate() {
                if aij != 0.0 {
                    self.vbar[j].axpy(h * aij, &self.qhat_bar, 1.0);
                    self.abar[j].axpy(h * aij, &self.vhat_bar, 1.0);
                }
            }
        }
        // Stage 0: Q₀ = qₙ, V₀ = q̇ₙ, A₀ = a(tₙ, qₙ, q̇ₙ; p).
        *lq += &self.qbar[0];
        *lv += &self.vbar[0];
        if self.force {
            // Jᵀ Ā₀ = −(∂r)ᵀ M⁻¹ Ā₀.
            self.mu.copy_from(&self.abar[0]);
            self.solve_mass(sys, t).map_err(err("mass solve"))?;
            lq.gemv_tr(-1.0, &self.jq[0], &self.mu, 1.0);
            lv.gemv_tr(-1.0, &self.jv[0], &self.mu, 1.0);
            sys.force_param_vjp(
                t,
                &self.qs[0],
                &self.vs[0],
                &self.accs[0],
                &self.mu,
                &mut self.dp,
            )
            .map_err(err("parameter derivatives"))?;
        } else {
            lq.gemv_tr(1.0, &self.jq[0], &self.abar[0], 1.0);
            lv.gemv_tr(1.0, &self.jv[0], &self.abar[0], 1.0);
            sys.accel_param_vjp(
                t,
                &self.qs[0],
                &self.vs[0],
                &self.accs[0],
                &self.abar[0],
                &mut self.dp,
            )
            .map_err(err("parameter derivatives"))?;
        }
        Ok(())
    }

    /// `ν = Sᵢ⁻ᵀ rhs` into `mu` (G11): on a kept operator GMRES
    /// preconditioned by the recomputation's dense LU (G32); on a formed
    /// `Sᵢ` GMRES preconditioned by the system's structured
    /// `M + h²γ²K + hγD` at the stage; or a dense LU of `Sᵢᵀ` (neither
    /// offered, or GMRES not at round-off). False when `Sᵢ` is singular.
    fn solve_transposed<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        i: usize,
        ti: f64,
        h: f64,
    ) -> Result<bool, Sys::Error> {
        let gamma = self.tab.gamma;
        let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
        let rtol = 16.0 * f64::EPSILON * (self.n as f64).sqrt();
        // The kept operator: GMRES preconditioned by the transposed solves
        // of the dense LU the recomputation iterated with (G32), no
        // structured factorization.
        let solved = if self.ops[i] {
            self.gmres_products(sys, i, h, rtol)?
        } else {
            None
        };
        if let Some(iterations) = solved {
            self.krylov += iterations;
            return Ok(true);
        }
        if self.ops[i] {
            self.krylov += KRYLOV_ITERATIONS.min(self.n) * KRYLOV_CYCLES;
        } else if sys.factor_shifted_mass(ti, &self.qs[i], hg2, hg)? {
            let solved = {
                let s = &self.shifted[i];
                // ‖Sᵀ‖∞: the largest column sum of |S|.
                let anorm = s
                    .column_iter()
                    .map(|c| c.iter().map(|v| v.abs()).sum::<f64>())
                    .fold(0.0, f64::max);
                self.gmres.solve(
                    &self.rhs,
                    &mut self.mu,
                    anorm,
                    rtol,
                    KRYLOV_CYCLES,
                    |v, out| out.gemv_tr(1.0, s, v, 0.0),
                    |v| sys.solve_shifted_mass(v),
                )?
            };
            match solved {
                Some(iterations) => {
                    self.krylov += iterations;
                    return Ok(true);
                }
                None => self.krylov += KRYLOV_ITERATIONS.min(self.n) * KRYLOV_CYCLES,
            }
        }
        if self.ops[i] {
            // The dense fallback needs the dense derivatives of the stage.
            let ti_acc = &self.accs[i];
            if !sys.force_jacobians(
                ti,
                &self.qs[i],
                &self.vs[i],
                ti_acc,
                &mut self.mass[i],
                &mut self.jq[i],
                &mut self.jv[i],
            )? {
                unreachable!("a system that keeps the operator gives the dense derivatives")
            }
            self.jacobians += 1;
            self.ops[i] = false;
            self.mass_ops[i] = false;
            let s = self.shifted[i].as_mut_slice();
            let (m, jv, jq) = (&self.mass[i], &self.jv[i], &self.jq[i]);
            for (k, x) in s.iter_mut().enumerate() {
                *x = m.as_slice()[k] + hg * jv.as_slice()[k] + hg2 * jq.as_slice()[k];
            }
        }
        self.factorizations += 1;
        let m = self.lus[i].matrix_mut();
        m.tr_copy_from(&self.shifted[i]);
        if !self.lus[i].factor() {
            return Ok(false);
        }
        self.mu.copy_from(&self.rhs);
        self.lus[i].solve_in_place(&mut self.mu);
        Ok(true)
    }

    /// GMRES on `Sᵢᵀν = rhs` with `Sᵢᵀv = Mv + hγ(∂r/∂q̇)ᵀv + h²γ²(∂r/∂q)ᵀv`
    /// by the system's O(N) products (G12), preconditioned by the
    /// transposed solves of the dense LU of `S` the recomputation of stage
    /// `i` iterated with (the step start's `S₀`, or the stage's own after a
    /// switch), and with that matrix's `‖Sᵀ‖∞` in the stopping test (G32).
    fn gmres_products<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        i: usize,
        h: f64,
        rtol: f64,
    ) -> Result<Option<usize>, Sys::Error> {
        let gamma = self.tab.gamma;
        let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
        let kept_mass = self.mass_ops[i];
        let slot = self.lu_slot[i];
        let anorm = self.lu_norms[slot];
        let lu = &self.lus[slot];
        let mut failure = None;
        let (mass, pq, pv) = (&self.mass[i], &mut self.pq, &mut self.pv);
        let solved = self.gmres.solve(
            &self.rhs,
            &mut self.mu,
            anorm,
            rtol,
            KRYLOV_CYCLES,
            |v, out| {
                if failure.is_none() {
                    let s = &mut *sys;
                    let done = s.force_vjp(i, v, pq, pv).and_then(|()| {
                        if kept_mass {
                            s.force_mass_product(i, v, out)
                        } else {
                            out.gemv_tr(1.0, mass, v, 0.0);
                            Ok(())
                        }
                    });
                    match done {
                        Ok(()) => {
                            out.axpy(hg, pv, 1.0);
                            out.axpy(hg2, pq, 1.0);
                            return;
                        }
                        Err(e) => failure = Some(e),
                    }
                }
                out.fill(0.0);
            },
            |v| {
                lu.solve_transposed_in_place(v);
                Ok::<(), Sys::Error>(())
            },
        )?;
        match failure {
            Some(e) => Err(e),
            None => Ok(solved),
        }
    }

    /// `mu ← M₀⁻¹ mu` at the step start: a dense Cholesky of the `M₀` stage
    /// 0's linearization formed, up to [`DENSE_MASS_MAX`] coordinates
    /// (G33), else the system's structured solve with no shift (or the
    /// Cholesky where it has none).
    fn solve_mass<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        t: f64,
    ) -> Result<(), Sys::Error> {
        if self.n > DENSE_MASS_MAX {
            if sys.factor_shifted_mass(t, &self.qs[0], 0.0, 0.0)? {
                return sys.solve_shifted_mass(&mut self.mu);
            }
            // A large dense Cholesky is counted with the LUs; the small one
            // of G33 is not (it costs less than the structured one).
            self.factorizations += 1;
        }
        self.chol.matrix_mut().copy_from(&self.mass[0]);
        if !self.chol.factor_cholesky() {
            // Not positive definite: left to the final non-finite check.
            self.mu.fill(f64::NAN);
            return Ok(());
        }
        self.chol.solve_in_place(&mut self.mu);
        Ok(())
    }
}

/// Fills `lu` with `I − hγ Jv − h²γ² Jq`, transposed when `transpose`, and
/// factors it; false when singular.
fn stage_matrix(
    lu: &mut DenseLu,
    jq: &DMatrix<f64>,
    jv: &DMatrix<f64>,
    gamma: f64,
    h: f64,
    transpose: bool,
) -> bool {
    let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
    let n = jq.nrows();
    let m = lu.matrix_mut();
    for c in 0..n {
        for r in 0..n {
            let (a, b) = if transpose { (c, r) } else { (r, c) };
            let d = if r == c { 1.0 } else { 0.0 };
            m[(r, c)] = d - hg * jv[(a, b)] - hg2 * jq[(a, b)];
        }
    }
    lu.factor()
}

fn singular(t: f64, h: f64) -> IntegrateError {
    IntegrateError::SingularMatrix {
        t,
        h,
        what: "transposed stage matrix of the adjoint",
    }
}
