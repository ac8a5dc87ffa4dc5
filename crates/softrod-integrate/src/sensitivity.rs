//! Forward sensitivities of a recorded run (docs/theory-control.md G21):
//! the derivatives `S = ∂yₙ/∂(p, q₀, q̇₀)` carried forward through the same
//! discrete map the adjoint ([`crate::adjoint_second_order`]) runs
//! backwards — the recorded step sequence held fixed, every stage
//! recomputed to round-off — and contracted with the loss's derivatives at
//! the nodes.
//!
//! Its cost grows with the number of columns (one per parameter, plus `n`
//! for `q₀` and `n` for `q̇₀` when asked for) where the adjoint's does not;
//! it pays where the parameters are few and the model small (dense stage
//! Jacobians and LUs), and it is a second, independent algorithm for the
//! same numbers: the two agree to round-off (tests/gradients.rs).

#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{DMatrix, DVector};

use crate::adjoint::{AdjointGradient, ParameterSystem, Seed, Tape, check_request};
use crate::error::{IntegrateError, first_non_finite};
use crate::integrator::Integrator;
use crate::linalg::DenseLu;
use crate::methods::{
    EsdirkCoefficients as Coefficients, esdirk_explicit_part as explicit_part,
    esdirk_stage_values as stage_values,
};

/// Newton iterations allowed when a stage is recomputed.
const MAX_NEWTON: usize = 60;

/// `∂L/∂p` (and `∂L/∂q₀`, `∂L/∂q̇₀` when `initial`) of a run recorded on
/// `tape` with `integrator`, by forward sensitivities (G21): the same
/// numbers as [`adjoint_second_order`](crate::adjoint_second_order) to
/// round-off, in the same [`AdjointGradient`] (with `initial` false its
/// `dq0`, `dqd0` are zero). `seed(k, ∂L/∂qₖ, ∂L/∂q̇ₖ)` adds the loss's
/// explicit derivatives at node `k`, called once per node, first node
/// first.
///
/// Errors: an integrator without these sensitivities (as the adjoint: the
/// ESDIRK methods and Radau IIA, G26), a tape of another dimension, a failing or non-finite
/// evaluation, a singular stage matrix, a stage whose Newton iteration
/// does not converge.
pub fn forward_sensitivity_second_order<Sys: ParameterSystem>(
    sys: &mut Sys,
    integrator: Integrator,
    tape: &Tape,
    seed: &mut Seed<'_>,
    initial: bool,
) -> Result<AdjointGradient, IntegrateError> {
    if integrator == Integrator::Radau5 {
        return crate::radau_adjoint::forward(sys, tape, seed, initial);
    }
    let (n, tab) = check_request(sys.dim(), integrator, tape)?;
    let np = sys.n_params();
    let m = np + if initial { 2 * n } else { 0 };
    let mut w = Forward::new(tab, n, np, m);
    if initial {
        for r in 0..n {
            w.sq[(r, np + r)] = 1.0;
            w.sv[(r, np + n + r)] = 1.0;
        }
    }
    let mut grad = DVector::zeros(m);
    let mut lq = DVector::zeros(n);
    let mut lv = DVector::zeros(n);
    w.contract(0, seed, &mut lq, &mut lv, &mut grad);
    for k in 0..tape.steps() {
        w.step(sys, tape, k)?;
        w.contract(k + 1, seed, &mut lq, &mut lv, &mut grad);
    }
    gradient_of_sensitivities(
        &grad,
        np,
        n,
        initial,
        tape,
        [w.jacobians, w.accels, w.factorizations],
    )
}

/// The gradient from the contracted sensitivities `grad` = `(dL/dp (np),
/// dL/dq₀ (n), dL/dq̇₀ (n))` (the last two only when `initial`), checked
/// finite; `counts` = Jacobian evaluations, acceleration evaluations,
/// dense factorizations of the pass. Shared by the ESDIRK and the Radau IIA
/// forward sensitivities.
pub(crate) fn gradient_of_sensitivities(
    grad: &DVector<f64>,
    np: usize,
    n: usize,
    initial: bool,
    tape: &Tape,
    counts: [usize; 3],
) -> Result<AdjointGradient, IntegrateError> {
    if let Some(index) = first_non_finite(grad.as_slice()) {
        return Err(IntegrateError::NonFinite {
            t: tape.time(tape.steps()),
            h: 0.0,
            what: "sensitivity",
            index,
        });
    }
    let (dq0, dqd0) = if initial {
        (
            grad.rows(np, n).into_owned(),
            grad.rows(np + n, n).into_owned(),
        )
    } else {
        (DVector::zeros(n), DVector::zeros(n))
    };
    Ok(AdjointGradient {
        dq0,
        dqd0,
        dp: grad.rows(0, np).iter().copied().collect(),
        jacobian_evaluations: counts[0],
        accel_evaluations: counts[1],
        dense_factorizations: counts[2],
        krylov_iterations: 0,
    })
}

/// The buffers of the forward pass (allocated once per pass).
struct Forward {
    /// The tableau (G27): the per-stage buffers have one entry per stage.
    tab: Coefficients,
    n: usize,
    np: usize,
    /// `∂qₙ/∂·`, `∂q̇ₙ/∂·` at the current node (n × m).
    sq: DMatrix<f64>,
    sv: DMatrix<f64>,
    /// Per stage: `∂Vᵢ/∂·`, `∂Aᵢ/∂·` (n × m).
    dv: Vec<DMatrix<f64>>,
    da: Vec<DMatrix<f64>>,
    dqh: DMatrix<f64>,
    dvh: DMatrix<f64>,
    rhs: DMatrix<f64>,
    /// `∂a/∂p` at a stage (n × np).
    ap: DMatrix<f64>,
    jq: DMatrix<f64>,
    jv: DMatrix<f64>,
    lu: DenseLu,
    q: DVector<f64>,
    v: DVector<f64>,
    qs: Vec<DVector<f64>>,
    vs: Vec<DVector<f64>>,
    accs: Vec<DVector<f64>>,
    qhat: DVector<f64>,
    vhat: DVector<f64>,
    f: DVector<f64>,
    g: DVector<f64>,
    jacobians: usize,
    accels: usize,
    factorizations: usize,
}

impl Forward {
    fn new(tab: Coefficients, n: usize, np: usize, m: usize) -> Self {
        let s = tab.stages();
        let z = || DMatrix::zeros(n, m);
        Self {
            tab,
            n,
            np,
            sq: z(),
            sv: z(),
            dv: (0..s).map(|_| z()).collect(),
            da: (0..s).map(|_| z()).collect(),
            dqh: z(),
            dvh: z(),
            rhs: z(),
            ap: DMatrix::zeros(n, np),
            jq: DMatrix::zeros(n, n),
            jv: DMatrix::zeros(n, n),
            lu: DenseLu::new(n),
            q: DVector::zeros(n),
            v: DVector::zeros(n),
            qs: (0..s).map(|_| DVector::zeros(n)).collect(),
            vs: (0..s).map(|_| DVector::zeros(n)).collect(),
            accs: (0..s).map(|_| DVector::zeros(n)).collect(),
            qhat: DVector::zeros(n),
            vhat: DVector::zeros(n),
            f: DVector::zeros(n),
            g: DVector::zeros(n),
            jacobians: 0,
            accels: 0,
            factorizations: 0,
        }
    }

    /// Adds `Sqᵀ ∂ℓ/∂qₖ + Svᵀ ∂ℓ/∂q̇ₖ` of node `k` to `grad`.
    fn contract(
        &self,
        k: usize,
        seed: &mut Seed<'_>,
        lq: &mut DVector<f64>,
        lv: &mut DVector<f64>,
        grad: &mut DVector<f64>,
    ) {
        lq.fill(0.0);
        lv.fill(0.0);
        seed(k, lq, lv);
        grad.gemv_tr(1.0, &self.sq, lq, 1.0);
        grad.gemv_tr(1.0, &self.sv, lv, 1.0);
    }

    /// The exact Jacobians `∂a/∂q`, `∂a/∂q̇` and `∂a/∂p` at stage `i`'s
    /// values (its acceleration in `accs[i]`).
    fn linearize<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        i: usize,
        t: f64,
    ) -> Result<(), Sys::Error> {
        sys.jacobians(t, &self.qs[i], &self.vs[i], &mut self.jq, &mut self.jv)?;
        self.jacobians += 1;
        if self.np > 0 {
            sys.accel_param_jvp(t, &self.qs[i], &self.vs[i], &self.accs[i], &mut self.ap)?;
        }
        Ok(())
    }

    /// Factors `W = I − hγ J_v − h²γ² J_q` (G2) of the Jacobians held.
    fn factor(&mut self, h: f64) -> bool {
        let gamma = self.tab.gamma;
        let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
        let w = self.lu.matrix_mut();
        for c in 0..self.n {
            for r in 0..self.n {
                w[(r, c)] = -hg * self.jv[(r, c)] - hg2 * self.jq[(r, c)];
            }
            w[(c, c)] += 1.0;
        }
        self.factorizations += 1;
        self.lu.factor()
    }

    /// One step: the stages recomputed from the tape's node `k`, the
    /// sensitivities carried from node `k` to `k + 1`.
    fn step<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        tape: &Tape,
        k: usize,
    ) -> Result<(), IntegrateError> {
        let t = tape.time(k);
        let t_new = tape.time(k + 1);
        let h = tape.step_size(k);
        let (s, c, a) = (self.tab.stages(), self.tab.c, self.tab.a);
        let hg = h * self.tab.gamma;
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
        // Stage 0, the step start: dA₀ = J_q Sq + J_v Sv + ∂a/∂p.
        self.qs[0].copy_from(&self.q);
        self.vs[0].copy_from(&self.v);
        sys.accel(t, &self.q, &self.v, &mut self.accs[0])
            .map_err(err("accel"))?;
        self.accels += 1;
        self.linearize(sys, 0, t).map_err(err("jacobian"))?;
        self.dv[0].copy_from(&self.sv);
        self.da[0].gemm(1.0, &self.jq, &self.sq, 0.0);
        self.da[0].gemm(1.0, &self.jv, &self.sv, 1.0);
        add_params(&mut self.da[0], &self.ap);
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
            let stored = if tape.stage_count() == s - 1 {
                tape.stage_acceleration(k, i)
            } else {
                None
            };
            self.solve_stage(sys, i, ti, h, stored)?;
            // The stage's sensitivity: W dAᵢ = J_q (dq̂ + hγ dv̂) + J_v dv̂ + ∂a/∂p,
            // dVᵢ = dv̂ + hγ dAᵢ (G2 differentiated).
            self.dqh.copy_from(&self.sq);
            self.dvh.copy_from(&self.sv);
            for (j, &aij) in a[i][..i].iter().enumerate() {
                if aij != 0.0 {
                    axpy(&mut self.dqh, h * aij, &self.dv[j]);
                    axpy(&mut self.dvh, h * aij, &self.da[j]);
                }
            }
            self.rhs.copy_from(&self.dqh);
            axpy(&mut self.rhs, hg, &self.dvh);
            let (jq, jv) = (&self.jq, &self.jv);
            self.da[i].gemm(1.0, jq, &self.rhs, 0.0);
            self.da[i].gemm(1.0, jv, &self.dvh, 1.0);
            add_params(&mut self.da[i], &self.ap);
            if !self.factor(h) {
                return Err(singular(ti, h));
            }
            for c in 0..self.da[i].ncols() {
                self.g.copy_from(&self.da[i].column(c));
                self.lu.solve_in_place(&mut self.g);
                self.da[i].set_column(c, &self.g);
            }
            self.dv[i].copy_from(&self.dvh);
            axpy(&mut self.dv[i], hg, &self.da[i]);
            if i == s - 1 {
                // Stiffly accurate: yₙ₊₁ = (Q_{s−1}, V_{s−1}),
                // dQ_{s−1} = dq̂ + hγ dV_{s−1}.
                self.sq.copy_from(&self.dqh);
                axpy(&mut self.sq, hg, &self.dv[i]);
                self.sv.copy_from(&self.dv[i]);
            }
        }
        Ok(())
    }

    /// Stage `i`'s acceleration `x = a(tᵢ, Qᵢ(x), Vᵢ(x))` by Newton's
    /// method with `W` at each iterate, to round-off (the adjoint's test,
    /// G3), from the forward run's stage where the tape kept it (G34), else
    /// from the previous stage's; leaves the Jacobians and `∂a/∂p` at the
    /// converged values.
    fn solve_stage<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        i: usize,
        ti: f64,
        h: f64,
        stored: Option<&[f64]>,
    ) -> Result<(), IntegrateError> {
        let n = self.n;
        let gamma = self.tab.gamma;
        let (hg, hg2) = (h * gamma, h * h * gamma * gamma);
        let err = |what: &'static str| {
            move |e: Sys::Error| IntegrateError::System {
                t: ti,
                h,
                what,
                source: Box::new(e),
            }
        };
        let (done, rest) = self.accs.split_at_mut(i);
        match stored {
            Some(x) => rest[0].copy_from_slice(x),
            None => rest[0].copy_from(&done[i - 1]),
        }
        let mut prev = f64::INFINITY;
        for _ in 0..MAX_NEWTON {
            stage_values(
                hg,
                &self.qhat,
                &self.vhat,
                &self.accs[i],
                &mut self.vs[i],
                &mut self.qs[i],
            );
            sys.accel(ti, &self.qs[i], &self.vs[i], &mut self.f)
                .map_err(err("accel"))?;
            self.accels += 1;
            self.linearize(sys, i, ti).map_err(err("jacobian"))?;
            if !self.factor(h) {
                return Err(singular(ti, h));
            }
            // W dx = a(x) − x.
            for r in 0..n {
                self.g[r] = self.f[r] - self.accs[i][r];
            }
            self.lu.solve_in_place(&mut self.g);
            self.accs[i] += &self.g;
            let dx = self.g.amax();
            let size = self.accs[i].amax();
            if !(dx.is_finite() && size.is_finite()) {
                return Err(IntegrateError::NonFinite {
                    t: ti,
                    h,
                    what: "recomputed stage",
                    index: first_non_finite(self.accs[i].as_slice()).unwrap_or(0),
                });
            }
            let moved = hg2 * dx <= 1e-13 * self.qs[i].amax().max(hg * self.vs[i].amax());
            if dx <= 4.0 * f64::EPSILON * size
                || (dx >= 0.5 * prev && (dx <= 1e-10 * size || moved))
            {
                // The converged stage's values and their Jacobians.
                stage_values(
                    hg,
                    &self.qhat,
                    &self.vhat,
                    &self.accs[i],
                    &mut self.vs[i],
                    &mut self.qs[i],
                );
                self.linearize(sys, i, ti).map_err(err("jacobian"))?;
                return Ok(());
            }
            prev = dx;
        }
        Err(IntegrateError::NewtonNonConvergence {
            t: ti,
            h,
            iterations: MAX_NEWTON,
            what: "recomputed stage of the forward sensitivities",
        })
    }
}

/// `y += a x` on matrices.
fn axpy(y: &mut DMatrix<f64>, a: f64, x: &DMatrix<f64>) {
    y.zip_apply(x, |yi, xi| *yi += a * xi);
}

/// Adds `∂a/∂p` to the parameter columns (the first) of a stage's `dA`.
fn add_params(da: &mut DMatrix<f64>, ap: &DMatrix<f64>) {
    for c in 0..ap.ncols() {
        for r in 0..ap.nrows() {
            da[(r, c)] += ap[(r, c)];
        }
    }
}

fn singular(t: f64, h: f64) -> IntegrateError {
    IntegrateError::InvalidInput {
        what: format!("a singular stage matrix at t = {t}, h = {h} (forward sensitivities)"),
    }
}
