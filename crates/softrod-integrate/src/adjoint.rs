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
//! Supported: [`Integrator::Esdirk`] (the default). Other methods are
//! refused with an error naming the ones that are supported.
//!
//! The system's parameters `p` enter through [`ParameterSystem`]: it gives
//! the vector–Jacobian product `wᵀ ∂a/∂p` at a state, so the backward pass
//! costs the same whatever the number of parameters (beyond those products).

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{DMatrix, DVector};

use crate::error::{IntegrateError, first_non_finite};
use crate::integrator::Integrator;
use crate::linalg::DenseLu;
use crate::methods::{
    ESDIRK_A as A, ESDIRK_C as C, ESDIRK_GAMMA as GAMMA, esdirk_explicit_part as explicit_part,
    esdirk_stage_values as stage_values,
};
use crate::system::SecondOrderSystem;

const S: usize = 6;
/// Newton iterations allowed when a stage is recomputed.
const MAX_NEWTON: usize = 50;

/// The integrators whose discrete adjoint [`adjoint_second_order`] has.
pub const ADJOINT_INTEGRATORS: [Integrator; 1] = [Integrator::Esdirk];

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
}

/// The record of a forward run the backward pass needs: the times `tₙ`
/// (node 0 is the start), the accepted step sizes `hₙ` (`tₙ₊₁` is the end
/// of step `n`, exactly as the integrator landed on it) and the states
/// `(qₙ, q̇ₙ)` at every node. `8·n` bytes per coordinate and node.
#[derive(Clone, Debug)]
pub struct Tape {
    n: usize,
    t: Vec<f64>,
    h: Vec<f64>,
    q: Vec<f64>,
    v: Vec<f64>,
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
        }
    }

    /// Records an accepted step of size `h` that ended at `(t, q, q̇)`.
    pub fn push(&mut self, t: f64, h: f64, q: &[f64], qd: &[f64]) {
        assert_eq!(q.len(), self.n, "q has the wrong length");
        assert_eq!(qd.len(), self.n, "qdot has the wrong length");
        self.t.push(t);
        self.h.push(h);
        self.q.extend_from_slice(q);
        self.v.extend_from_slice(qd);
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
    /// Dense Jacobian evaluations of the backward pass (6 per step).
    pub jacobian_evaluations: usize,
    /// Acceleration evaluations of the recomputed stages.
    pub accel_evaluations: usize,
}

/// Adds the explicit loss derivatives `(∂ℓ/∂qₖ, ∂ℓ/∂q̇ₖ)` at node `k` to
/// its second and third arguments ([`adjoint_second_order`]).
pub type Seed<'a> = dyn FnMut(usize, &mut DVector<f64>, &mut DVector<f64>) + 'a;

/// The discrete adjoint of a run recorded on `tape` with `integrator`
/// (docs/theory-control.md G1–G8): `L = Σₖ ℓₖ(qₖ, q̇ₖ)` over the tape's
/// nodes, with `seed(k, ∂L/∂qₖ, ∂L/∂q̇ₖ)` adding the explicit derivatives
/// of the loss at node `k` (called once per node, last node first; leave
/// them alone at a node without loss).
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
    if !ADJOINT_INTEGRATORS.contains(&integrator) {
        let names: Vec<&str> = ADJOINT_INTEGRATORS.iter().map(|i| i.name()).collect();
        return Err(IntegrateError::InvalidInput {
            what: format!(
                "gradients need the discrete adjoint of the integrator; {} has none \
                 (supported: {})",
                integrator.name(),
                names.join(", ")
            ),
        });
    }
    let n = sys.dim();
    if tape.dim() != n {
        return Err(IntegrateError::InvalidInput {
            what: format!("the tape has {} coordinates, the system {n}", tape.dim()),
        });
    }
    let mut w = EsdirkAdjoint::new(n, sys.n_params());
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
    })
}

/// The buffers of the ESDIRK backward pass (allocated once per pass).
struct EsdirkAdjoint {
    n: usize,
    q: DVector<f64>,
    v: DVector<f64>,
    qs: [DVector<f64>; S],
    vs: [DVector<f64>; S],
    accs: [DVector<f64>; S],
    jq: [DMatrix<f64>; S],
    jv: [DMatrix<f64>; S],
    /// `(I − hγJ)ᵀ` of each implicit stage, factored; slot 0: the
    /// (untransposed) step-start matrix of the recomputing Newton iteration.
    lus: [DenseLu; S],
    qhat: DVector<f64>,
    vhat: DVector<f64>,
    f: DVector<f64>,
    g: DVector<f64>,
    qbar: [DVector<f64>; S],
    vbar: [DVector<f64>; S],
    abar: [DVector<f64>; S],
    mu: DVector<f64>,
    qhat_bar: DVector<f64>,
    vhat_bar: DVector<f64>,
    dp: Vec<f64>,
    jacobians: usize,
    accels: usize,
}

impl EsdirkAdjoint {
    fn new(n: usize, np: usize) -> Self {
        let z = DVector::zeros(n);
        let m = DMatrix::zeros(n, n);
        Self {
            n,
            q: z.clone(),
            v: z.clone(),
            qs: std::array::from_fn(|_| z.clone()),
            vs: std::array::from_fn(|_| z.clone()),
            accs: std::array::from_fn(|_| z.clone()),
            jq: std::array::from_fn(|_| m.clone()),
            jv: std::array::from_fn(|_| m.clone()),
            lus: std::array::from_fn(|_| DenseLu::new(n)),
            qhat: z.clone(),
            vhat: z.clone(),
            f: z.clone(),
            g: z.clone(),
            qbar: std::array::from_fn(|_| z.clone()),
            vbar: std::array::from_fn(|_| z.clone()),
            abar: std::array::from_fn(|_| z.clone()),
            mu: z.clone(),
            qhat_bar: z.clone(),
            vhat_bar: z,
            dp: vec![0.0; np],
            jacobians: 0,
            accels: 0,
        }
    }

    /// Fills slot `i` of `lus` with `I − hγ Jv − h²γ² Jq` of stage `j`,
    /// transposed when `transpose`, and factors it.
    fn factor(&mut self, i: usize, j: usize, h: f64, transpose: bool) -> bool {
        stage_matrix(&mut self.lus[i], &self.jq[j], &self.jv[j], h, transpose)
    }

    /// One step backwards: `(λq, λv)` at node `k + 1` in, at node `k` out
    /// (G4–G7); adds the step's `∂L/∂p` to `dp`.
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
        let (hg, hg2) = (h * GAMMA, h * h * GAMMA * GAMMA);
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
        // Stage 0: the step start (G2).
        self.qs[0].copy_from(&self.q);
        self.vs[0].copy_from(&self.v);
        sys.accel(t, &self.q, &self.v, &mut self.accs[0])
            .map_err(err("accel"))?;
        self.accels += 1;
        sys.jacobians(t, &self.q, &self.v, &mut self.jq[0], &mut self.jv[0])
            .map_err(err("jacobian"))?;
        self.jacobians += 1;
        if !self.factor(0, 0, h, false) {
            return Err(singular(t, h));
        }
        // Stages 1..5, recomputed (G3): simplified Newton on the step-start
        // matrix, to round-off.
        for i in 1..S {
            let ti = if i == S - 1 { t_new } else { t + C[i] * h };
            explicit_part(
                i,
                h,
                &self.q,
                &self.v,
                &self.vs,
                &self.accs,
                &mut self.qhat,
                &mut self.vhat,
            );
            let (done, rest) = self.accs.split_at_mut(i);
            let x = &mut rest[0];
            x.copy_from(&done[i - 1]);
            let mut prev = f64::INFINITY;
            let mut converged = false;
            // The LU the iteration solves with: the step-start matrix, or
            // (after a slow iteration) the stage's own at its iterate.
            let mut slot = 0;
            for iteration in 0..MAX_NEWTON {
                stage_values(
                    hg,
                    &self.qhat,
                    &self.vhat,
                    x,
                    &mut self.vs[i],
                    &mut self.qs[i],
                );
                sys.accel(ti, &self.qs[i], &self.vs[i], &mut self.f)
                    .map_err(err("accel"))?;
                self.accels += 1;
                for r in 0..n {
                    self.g[r] = x[r] - self.f[r];
                }
                self.lus[slot].solve_in_place(&mut self.g);
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
                if dx <= 4.0 * f64::EPSILON * size
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
                if slot == 0 && iteration >= 2 && dx > 0.25 * prev {
                    stage_values(
                        hg,
                        &self.qhat,
                        &self.vhat,
                        x,
                        &mut self.vs[i],
                        &mut self.qs[i],
                    );
                    let (jq, jv) = (&mut self.jq[i], &mut self.jv[i]);
                    sys.jacobians(ti, &self.qs[i], &self.vs[i], jq, jv)
                        .map_err(err("jacobian"))?;
                    self.jacobians += 1;
                    if !stage_matrix(&mut self.lus[i], jq, jv, h, false) {
                        return Err(singular(ti, h));
                    }
                    slot = i;
                }
                prev = dx;
            }
            if !converged {
                return Err(IntegrateError::NewtonNonConvergence {
                    t,
                    h,
                    iterations: MAX_NEWTON,
                    what: "recomputed stage of the adjoint",
                });
            }
            let x = &self.accs[i];
            stage_values(
                hg,
                &self.qhat,
                &self.vhat,
                x,
                &mut self.vs[i],
                &mut self.qs[i],
            );
            let (jq, jv) = (&mut self.jq[i], &mut self.jv[i]);
            sys.jacobians(ti, &self.qs[i], &self.vs[i], jq, jv)
                .map_err(err("jacobian"))?;
            self.jacobians += 1;
            if !self.factor(i, i, h, true) {
                return Err(singular(ti, h));
            }
        }
        // The reverse sweep (G5–G7).
        for i in 0..S {
            self.qbar[i].fill(0.0);
            self.vbar[i].fill(0.0);
            self.abar[i].fill(0.0);
        }
        self.qbar[S - 1].copy_from(lq);
        self.vbar[S - 1].copy_from(lv);
        lq.fill(0.0);
        lv.fill(0.0);
        for i in (1..S).rev() {
            let ti = if i == S - 1 { t_new } else { t + C[i] * h };
            // Ã = Ā + hγ V̄ + h²γ² Q̄, μ = W⁻ᵀ Ã.
            for r in 0..n {
                self.mu[r] = self.abar[i][r] + hg * self.vbar[i][r] + hg2 * self.qbar[i][r];
            }
            self.lus[i].solve_in_place(&mut self.mu);
            // q̂̄ = Q̄ + Jqᵀμ; v̂̄ = V̄ + hγ Q̄ + hγ Jqᵀμ + Jvᵀμ.
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
            *lq += &self.qhat_bar;
            *lv += &self.vhat_bar;
            for (j, &a) in A[i][..i].iter().enumerate() {
                if a != 0.0 {
                    self.vbar[j].axpy(h * a, &self.qhat_bar, 1.0);
                    self.abar[j].axpy(h * a, &self.vhat_bar, 1.0);
                }
            }
        }
        // Stage 0: Q₀ = qₙ, V₀ = q̇ₙ, A₀ = a(tₙ, qₙ, q̇ₙ; p).
        *lq += &self.qbar[0];
        *lv += &self.vbar[0];
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
        Ok(())
    }
}

/// Fills `lu` with `I − hγ Jv − h²γ² Jq`, transposed when `transpose`, and
/// factors it; false when singular.
fn stage_matrix(
    lu: &mut DenseLu,
    jq: &DMatrix<f64>,
    jv: &DMatrix<f64>,
    h: f64,
    transpose: bool,
) -> bool {
    let (hg, hg2) = (h * GAMMA, h * h * GAMMA * GAMMA);
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
