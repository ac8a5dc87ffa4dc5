//! The discrete adjoint and the forward sensitivities of Radau IIA
//! ([`Integrator::Radau5`](crate::Integrator::Radau5);
//! docs/theory-control.md G25, G26).
//!
//! A step of the second-order problem `q̈ = a(t, q, q̇; p)` solves the
//! collocation equations for the stage accelerations `X = (A₁, A₂, A₃)`:
//!
//! `Vᵢ = q̇ₙ + h Σⱼ aᵢⱼ Aⱼ`, `Qᵢ = qₙ + cᵢ h q̇ₙ + h² Σⱼ (A²)ᵢⱼ Aⱼ`,
//! `Rᵢ(X) = Aᵢ − a(tₙ + cᵢh, Qᵢ, Vᵢ) = 0`,
//!
//! and ends at `(qₙ₊₁, q̇ₙ₊₁) = (Q₃, V₃)` (stiffly accurate, `c₃ = 1`) —
//! the first-order view's `Z = h(A ⊗ I) F(yₙ + Z)` with the velocity
//! stages eliminated. Its derivative is the `3n×3n` matrix
//! `K = I − [h aᵢⱼ ∂a/∂q̇ᵢ + h² (A²)ᵢⱼ ∂a/∂qᵢ]ᵢⱼ` with the exact Jacobians
//! at the three stage points. Both passes recompute every step's stages
//! from the tape to round-off by Newton's method on `K`, factor `K` at the
//! converged stages (a dense LU), and solve with it: `Kᵀw = g` backwards
//! (the adjoint, G25), `K dX = ·` with one column per parameter forwards
//! (G26). The factorization of one step is the next step's Newton matrix.

// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// The stage index runs over several arrays at once.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector};

use crate::adjoint::{AdjointGradient, ParameterSystem, Seed, Tape};
use crate::error::{IntegrateError, first_non_finite};
use crate::linalg::DenseLu;
use crate::methods::{RADAU_A, RADAU_C};

/// Newton iterations allowed when a step's stages are recomputed.
const MAX_NEWTON: usize = 50;

/// New linearizations a recomputation may take after slow contraction.
const MAX_RELINEARIZATIONS: usize = 4;

/// The relative error of a recomputed stage's acceleration taken for its
/// round-off (as the ESDIRK recomputation's, G14).
const RECOMPUTE_ROUNDOFF: f64 = 1e-13;

/// What a new linearization costs in iterations of the simplified Newton
/// iteration (three Jacobians and a `3n×3n` LU against three
/// accelerations and one pair of triangular solves: ~10 on the planar
/// release, n = 24): a contraction predicted to need more iterations than
/// this to reach round-off linearizes again at the iterate.
const SWITCH_ITERATIONS: f64 = 10.0;

/// A held factorization is the next step's Newton matrix when the step
/// sizes differ by at most this factor (`K` depends on `h`).
const REUSE_RATIO: f64 = 2.0;

/// The stages of one Radau IIA step recomputed from the tape, their
/// Jacobians and the factored `K` (allocated once per pass).
struct Stages {
    n: usize,
    /// `A²`.
    a2: [[f64; 3]; 3],
    q: DVector<f64>,
    v: DVector<f64>,
    qs: [DVector<f64>; 3],
    vs: [DVector<f64>; 3],
    accs: [DVector<f64>; 3],
    /// `∂a/∂q`, `∂a/∂q̇` at each stage.
    jq: [DMatrix<f64>; 3],
    jv: [DMatrix<f64>; 3],
    /// `K` factored, and the step size it was formed with (NaN: none).
    lu: DenseLu,
    lu_h: f64,
    f: DVector<f64>,
    r: DVector<f64>,
    /// The accelerations `a(tₖ, qₖ, q̇ₖ)` at two nodes (the step's ends,
    /// for the starting guess; the pass moves one node a step).
    ends: [(Option<usize>, DVector<f64>); 2],
    jacobians: usize,
    accels: usize,
    factorizations: usize,
}

impl Stages {
    fn new(n: usize) -> Self {
        let z = DVector::zeros(n);
        let m = DMatrix::zeros(n, n);
        let mut a2 = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                a2[i][j] = (0..3).map(|k| RADAU_A[i][k] * RADAU_A[k][j]).sum();
            }
        }
        Self {
            n,
            a2,
            q: z.clone(),
            v: z.clone(),
            qs: std::array::from_fn(|_| z.clone()),
            vs: std::array::from_fn(|_| z.clone()),
            accs: std::array::from_fn(|_| z.clone()),
            jq: std::array::from_fn(|_| m.clone()),
            jv: std::array::from_fn(|_| m.clone()),
            lu: DenseLu::new(3 * n),
            lu_h: f64::NAN,
            f: z.clone(),
            r: DVector::zeros(3 * n),
            ends: [(None, z.clone()), (None, z)],
            jacobians: 0,
            accels: 0,
            factorizations: 0,
        }
    }

    /// The time of stage `i` of a step of size `h` from `t`: the forward
    /// step's own (`t + h` for the last, where the step's end may have
    /// been clipped to a breakpoint a rounding away).
    fn stage_time(t: f64, h: f64, i: usize) -> f64 {
        if i == 2 { t + h } else { t + RADAU_C[i] * h }
    }

    /// `Qᵢ`, `Vᵢ` from the stage accelerations (G25).
    fn stage_values(&mut self, h: f64) {
        for i in 0..3 {
            self.vs[i].copy_from(&self.v);
            self.qs[i].copy_from(&self.q);
            self.qs[i].axpy(RADAU_C[i] * h, &self.v, 1.0);
            for j in 0..3 {
                self.vs[i].axpy(h * RADAU_A[i][j], &self.accs[j], 1.0);
                self.qs[i].axpy(h * h * self.a2[i][j], &self.accs[j], 1.0);
            }
        }
    }

    /// The Jacobians at the current stage values, `K` formed and factored.
    fn linearize<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        t: f64,
        h: f64,
    ) -> Result<(), IntegrateError> {
        let n = self.n;
        for i in 0..3 {
            let ti = Self::stage_time(t, h, i);
            sys.jacobians(
                ti,
                &self.qs[i],
                &self.vs[i],
                &mut self.jq[i],
                &mut self.jv[i],
            )
            .map_err(system(ti, h, "jacobian"))?;
            self.jacobians += 1;
            if let Some(index) = first_non_finite(self.jq[i].as_slice())
                .or_else(|| first_non_finite(self.jv[i].as_slice()))
            {
                return Err(IntegrateError::NonFinite {
                    t: ti,
                    h,
                    what: "Jacobian of a recomputed stage",
                    index,
                });
            }
        }
        let k = self.lu.matrix_mut();
        for i in 0..3 {
            for j in 0..3 {
                let (cv, cq) = (h * RADAU_A[i][j], h * h * self.a2[i][j]);
                for c in 0..n {
                    for r in 0..n {
                        let d = if i == j && r == c { 1.0 } else { 0.0 };
                        k[(i * n + r, j * n + c)] =
                            d - cv * self.jv[i][(r, c)] - cq * self.jq[i][(r, c)];
                    }
                }
            }
        }
        self.factorizations += 1;
        if !self.lu.factor() {
            self.lu_h = f64::NAN;
            return Err(IntegrateError::SingularMatrix {
                t,
                h,
                what: "collocation matrix of the recomputed Radau IIA step",
            });
        }
        self.lu_h = h;
        Ok(())
    }

    /// `a(tₖ, qₖ, q̇ₖ)` at tape node `k`: the slot that holds it.
    fn end_accel<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        tape: &Tape,
        k: usize,
        keep: usize,
    ) -> Result<usize, IntegrateError> {
        if let Some(slot) = self.ends.iter().position(|(node, _)| *node == Some(k)) {
            return Ok(slot);
        }
        // The slot not holding the other end of the step.
        let slot = usize::from(self.ends[0].0 == Some(keep));
        let t = tape.time(k);
        self.q.copy_from_slice(tape.q(k));
        self.v.copy_from_slice(tape.qd(k));
        let out = &mut self.ends[slot].1;
        sys.accel(t, &self.q, &self.v, out)
            .map_err(system(t, 0.0, "accel"))?;
        self.accels += 1;
        self.ends[slot].0 = Some(k);
        Ok(slot)
    }

    /// Recomputes the stages of tape step `k` to round-off and leaves `K`
    /// factored at them; returns `(tₖ, hₖ)`.
    fn recompute<Sys: ParameterSystem>(
        &mut self,
        sys: &mut Sys,
        tape: &Tape,
        k: usize,
    ) -> Result<(f64, f64), IntegrateError> {
        let n = self.n;
        let t = tape.time(k);
        let h = tape.step_size(k);
        // The starting guess: the cubic Hermite interpolant of the
        // velocity through (q̇ₖ, aₖ) and (q̇ₖ₊₁, aₖ₊₁), differentiated at
        // the nodes (as the ESDIRK recomputation's, G3).
        let s0 = self.end_accel(sys, tape, k, k + 1)?;
        let s1 = self.end_accel(sys, tape, k + 1, k)?;
        {
            let (v0, v1) = (tape.qd(k), tape.qd(k + 1));
            let (a0, a1) = (&self.ends[s0].1, &self.ends[s1].1);
            for i in 0..3 {
                let th = RADAU_C[i];
                let wd = (6.0 * th - 6.0 * th * th) / h;
                let w0 = 3.0 * th * th - 4.0 * th + 1.0;
                let w1 = 3.0 * th * th - 2.0 * th;
                for r in 0..n {
                    self.accs[i][r] = wd * (v1[r] - v0[r]) + w0 * a0[r] + w1 * a1[r];
                }
            }
        }
        self.q.copy_from_slice(tape.q(k));
        self.v.copy_from_slice(tape.qd(k));
        self.stage_values(h);
        // The Newton matrix: the last step's `K` where its step size is
        // close, else `K` at the guess.
        let held =
            self.lu_h.is_finite() && self.lu_h <= REUSE_RATIO * h && h <= REUSE_RATIO * self.lu_h;
        if !held {
            self.linearize(sys, t, h)?;
        }
        let mut relinearized = 0;
        let mut on_matrix = 0;
        let (mut prev, mut prev2) = (f64::INFINITY, f64::INFINITY);
        let mut converged = false;
        for _ in 0..MAX_NEWTON {
            for i in 0..3 {
                let ti = Self::stage_time(t, h, i);
                sys.accel(ti, &self.qs[i], &self.vs[i], &mut self.f)
                    .map_err(system(ti, h, "accel"))?;
                self.accels += 1;
                for r in 0..n {
                    self.r[i * n + r] = self.accs[i][r] - self.f[r];
                }
            }
            self.lu.solve_in_place(&mut self.r);
            for i in 0..3 {
                for r in 0..n {
                    self.accs[i][r] -= self.r[i * n + r];
                }
            }
            self.stage_values(h);
            let dx = self.r.amax();
            let size = self.accs.iter().map(|x| x.amax()).fold(0.0, f64::max);
            if !(dx.is_finite() && size.is_finite()) {
                return Err(IntegrateError::NonFinite {
                    t,
                    h,
                    what: "recomputed Radau IIA stage",
                    index: first_non_finite(self.r.as_slice()).unwrap_or(0),
                });
            }
            on_matrix += 1;
            let rate = match on_matrix {
                0 | 1 => f64::INFINITY,
                2 => dx / prev,
                _ => (dx / prev).max(prev / prev2),
            };
            // Converged to round-off, or stalled there (G14): the tests of
            // the ESDIRK recomputation, on all three stages at once.
            let reach = self
                .qs
                .iter()
                .zip(&self.vs)
                .map(|(q, v)| q.amax().max(h * v.amax()))
                .fold(0.0, f64::max);
            let moved = h * h * dx <= 1e-13 * reach;
            let left = rate < 1.0 && rate / (1.0 - rate) * dx <= RECOMPUTE_ROUNDOFF * size;
            if dx <= 4.0 * f64::EPSILON * size
                || left
                || (dx >= 0.5 * prev && (dx <= 1e-10 * size || moved))
            {
                converged = true;
                break;
            }
            let slow = if rate < 1.0 {
                (RECOMPUTE_ROUNDOFF * size / dx).ln() / rate.ln() > SWITCH_ITERATIONS
            } else {
                true
            };
            if on_matrix >= 2 && slow && relinearized < MAX_RELINEARIZATIONS {
                // Newton's method proper from here: `K` at the iterate.
                self.linearize(sys, t, h)?;
                relinearized += 1;
                on_matrix = 0;
            }
            prev2 = prev;
            prev = dx;
        }
        if !converged {
            return Err(IntegrateError::NewtonNonConvergence {
                t,
                h,
                iterations: MAX_NEWTON,
                what: "recomputed Radau IIA step of the gradient",
            });
        }
        // The exact linearization at the converged stages.
        self.linearize(sys, t, h)?;
        Ok((t, h))
    }
}

fn system<E: std::error::Error + Send + Sync + 'static>(
    t: f64,
    h: f64,
    what: &'static str,
) -> impl FnOnce(E) -> IntegrateError {
    move |e| IntegrateError::System {
        t,
        h,
        what,
        source: Box::new(e),
    }
}

fn check_dim(n: usize, tape: &Tape) -> Result<(), IntegrateError> {
    if tape.dim() != n {
        return Err(IntegrateError::InvalidInput {
            what: format!("the tape has {} coordinates, the system {n}", tape.dim()),
        });
    }
    Ok(())
}

/// The discrete adjoint of a Radau IIA run (G25): per step, backwards,
/// `Kᵀw = g` with `gⱼ = h²(A²)₃ⱼ λq + h a₃ⱼ λv`, then
/// `λq ← λq + Σⱼ (∂a/∂q)ⱼᵀ wⱼ`,
/// `λv ← λv + h λq + Σⱼ (cⱼh (∂a/∂q)ⱼ + (∂a/∂q̇)ⱼ)ᵀ wⱼ`,
/// `∂L/∂p += Σⱼ (∂a/∂p)ⱼᵀ wⱼ`.
pub(crate) fn adjoint<Sys: ParameterSystem>(
    sys: &mut Sys,
    tape: &Tape,
    seed: &mut Seed<'_>,
) -> Result<AdjointGradient, IntegrateError> {
    let n = sys.dim();
    check_dim(n, tape)?;
    let mut st = Stages::new(n);
    let mut dp = vec![0.0; sys.n_params()];
    let mut lq = DVector::zeros(n);
    let mut lv = DVector::zeros(n);
    let mut g = DVector::zeros(3 * n);
    let mut w = DVector::zeros(n);
    seed(tape.nodes() - 1, &mut lq, &mut lv);
    for k in (0..tape.steps()).rev() {
        let (t, h) = st.recompute(sys, tape, k)?;
        for j in 0..3 {
            let (cq, cv) = (h * h * st.a2[2][j], h * RADAU_A[2][j]);
            for r in 0..n {
                g[j * n + r] = cq * lq[r] + cv * lv[r];
            }
        }
        st.lu.solve_transposed_in_place(&mut g);
        lv.axpy(h, &lq, 1.0);
        for j in 0..3 {
            w.copy_from(&g.rows(j * n, n));
            lq.gemv_tr(1.0, &st.jq[j], &w, 1.0);
            lv.gemv_tr(RADAU_C[j] * h, &st.jq[j], &w, 1.0);
            lv.gemv_tr(1.0, &st.jv[j], &w, 1.0);
            let tj = Stages::stage_time(t, h, j);
            sys.accel_param_vjp(tj, &st.qs[j], &st.vs[j], &st.accs[j], &w, &mut dp)
                .map_err(system(tj, h, "parameter derivatives"))?;
        }
        seed(k, &mut lq, &mut lv);
    }
    if let Some(index) = first_non_finite(lq.as_slice())
        .or_else(|| first_non_finite(lv.as_slice()))
        .or_else(|| first_non_finite(&dp))
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
        dp,
        jacobian_evaluations: st.jacobians,
        accel_evaluations: st.accels,
        dense_factorizations: st.factorizations,
        krylov_iterations: 0,
    })
}

/// The forward sensitivities of a Radau IIA run (G26): per step, with
/// `S = ∂(qₙ, q̇ₙ)/∂(p, q₀, q̇₀)`, `K dX = [(∂a/∂q)ⱼ Sq + (cⱼh (∂a/∂q)ⱼ +
/// (∂a/∂q̇)ⱼ) Sv + (∂a/∂p)ⱼ]ⱼ`, then `Sq ← Sq + h Sv + h² Σⱼ (A²)₃ⱼ dAⱼ`,
/// `Sv ← Sv + h Σⱼ a₃ⱼ dAⱼ`; contracted with the loss at the nodes.
pub(crate) fn forward<Sys: ParameterSystem>(
    sys: &mut Sys,
    tape: &Tape,
    seed: &mut Seed<'_>,
    initial: bool,
) -> Result<AdjointGradient, IntegrateError> {
    let n = sys.dim();
    check_dim(n, tape)?;
    let np = sys.n_params();
    let m = np + if initial { 2 * n } else { 0 };
    let mut st = Stages::new(n);
    let mut sq = DMatrix::zeros(n, m);
    let mut sv = DMatrix::zeros(n, m);
    if initial {
        for r in 0..n {
            sq[(r, np + r)] = 1.0;
            sv[(r, np + n + r)] = 1.0;
        }
    }
    let mut rhs = DMatrix::zeros(3 * n, m);
    let mut block = DMatrix::zeros(n, m);
    let mut ap = DMatrix::zeros(n, np);
    let mut col = DVector::zeros(3 * n);
    let mut grad = DVector::zeros(m);
    let mut lq = DVector::zeros(n);
    let mut lv = DVector::zeros(n);
    let mut contract = |k: usize, sq: &DMatrix<f64>, sv: &DMatrix<f64>, grad: &mut DVector<f64>| {
        lq.fill(0.0);
        lv.fill(0.0);
        seed(k, &mut lq, &mut lv);
        grad.gemv_tr(1.0, sq, &lq, 1.0);
        grad.gemv_tr(1.0, sv, &lv, 1.0);
    };
    contract(0, &sq, &sv, &mut grad);
    for k in 0..tape.steps() {
        let (t, h) = st.recompute(sys, tape, k)?;
        for j in 0..3 {
            block.gemm(1.0, &st.jq[j], &sq, 0.0);
            // (cⱼh Jq + Jv) Sv = Jq (cⱼh Sv) + Jv Sv.
            block.gemm(RADAU_C[j] * h, &st.jq[j], &sv, 1.0);
            block.gemm(1.0, &st.jv[j], &sv, 1.0);
            if np > 0 {
                let tj = Stages::stage_time(t, h, j);
                sys.accel_param_jvp(tj, &st.qs[j], &st.vs[j], &st.accs[j], &mut ap)
                    .map_err(system(tj, h, "parameter derivatives"))?;
                for c in 0..np {
                    for r in 0..n {
                        block[(r, c)] += ap[(r, c)];
                    }
                }
            }
            rhs.rows_mut(j * n, n).copy_from(&block);
        }
        for c in 0..m {
            col.copy_from(&rhs.column(c));
            st.lu.solve_in_place(&mut col);
            rhs.set_column(c, &col);
        }
        // Sq first: it takes the step-start Sv.
        let sv_old = &sv;
        sq.zip_apply(sv_old, |x, y| *x += h * y);
        for j in 0..3 {
            let (cq, cv) = (h * h * st.a2[2][j], h * RADAU_A[2][j]);
            let da = rhs.rows(j * n, n);
            sq.zip_apply(&da, |x, y| *x += cq * y);
            sv.zip_apply(&da, |x, y| *x += cv * y);
        }
        contract(k + 1, &sq, &sv, &mut grad);
    }
    crate::sensitivity::gradient_of_sensitivities(
        &grad,
        np,
        n,
        initial,
        tape,
        [st.jacobians, st.accels, st.factorizations],
    )
}
