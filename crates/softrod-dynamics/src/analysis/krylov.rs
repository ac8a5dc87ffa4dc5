//! Matrix-free linear algebra of the structured statics and modes
//! (docs/theory.md E8–E10): the block-diagonal generalized stiffness `K`
//! and its Cholesky factors, the tangent-stiffness product `K_t v` by a
//! central difference of the static force along `v`, and restarted GMRES.
//! Everything is O(n_dof) in memory and per product; no `n × n` matrix.

use crate::algorithms::inverse_dynamics_with;
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::DMatrix;

/// `K = diag(K_n)` (D13) with the joints' spring constants (D53), one
/// dense block per piece or joint coordinate, and their Cholesky factors
/// when every block is positive definite (rod pieces always are; a joint
/// without a spring is not).
pub(crate) struct BlockStiffness {
    /// `(offset, block)`, blocks in ascending offset, covering `0..n_dof`.
    blocks: Vec<(usize, DMatrix<f64>)>,
    /// Lower Cholesky factors of the blocks, `None` if one is singular.
    factors: Option<Vec<DMatrix<f64>>>,
}

impl BlockStiffness {
    pub(crate) fn new(model: &Model) -> Self {
        let mut blocks = Vec::new();
        for rm in model.rods() {
            for (piece, pd) in rm.spec.geometry.pieces().iter().zip(&rm.pieces) {
                blocks.push((rm.dof_offset + piece.dof_offset, pd.stiffness.clone()));
            }
        }
        for e in model.elements() {
            for (i, o) in e.joint_dofs.clone().enumerate() {
                let (k, _, _) = e.attachment.joint.coefficients(i);
                blocks.push((o, DMatrix::from_element(1, 1, k)));
            }
        }
        blocks.sort_by_key(|(o, _)| *o);
        let factors = blocks
            .iter()
            .map(|(_, b)| b.clone().cholesky().map(|c| c.l()))
            .collect::<Option<Vec<_>>>()
            .filter(|_| blocks.iter().map(|(_, b)| b.nrows()).sum::<usize>() == model.n_dof());
        Self { blocks, factors }
    }

    /// Whether every block is positive definite (the preconditioner exists).
    pub(crate) fn is_definite(&self) -> bool {
        self.factors.is_some()
    }

    /// `‖K q‖∞`.
    pub(crate) fn mul_amax(&self, q: &[f64]) -> f64 {
        let mut m: f64 = 0.0;
        for (o, b) in &self.blocks {
            let k = b.nrows();
            for i in 0..k {
                let v: f64 = (0..k).map(|j| b[(i, j)] * q[o + j]).sum();
                m = m.max(v.abs());
            }
        }
        m
    }

    /// `x ← K⁻¹ x` by the blocks' Cholesky factors (needs [`Self::is_definite`]).
    pub(crate) fn solve(&self, x: &mut [f64]) {
        let Some(factors) = &self.factors else {
            return;
        };
        for ((o, _), l) in self.blocks.iter().zip(factors) {
            let k = l.nrows();
            let y = &mut x[*o..o + k];
            for i in 0..k {
                let s: f64 = (0..i).map(|j| l[(i, j)] * y[j]).sum();
                y[i] = (y[i] - s) / l[(i, i)];
            }
            for i in (0..k).rev() {
                let s: f64 = (i + 1..k).map(|j| l[(j, i)] * y[j]).sum();
                y[i] = (y[i] - s) / l[(i, i)];
            }
        }
    }
}

/// The tangent stiffness `K_t = ∂τ_s/∂q` of the static force `τ_s(q) =
/// ID(q, 0, 0)` under `forces` at `q`, applied to vectors by the central
/// difference `K_t v ≈ (τ_s(q + hv) − τ_s(q − hv)) / 2h` (E9): two O(N)
/// inverse dynamics per product, truncation `O(h²)`, round-off
/// `ε‖τ_s‖/h`; `h‖v‖∞ = 6·10⁻⁶ max(1, ‖q‖∞)` balances the two near
/// `10⁻¹¹` of `‖τ_s‖`.
pub(crate) struct Tangent<'a> {
    pub(crate) model: &'a Model,
    pub(crate) forces: Forces,
    pub(crate) time: f64,
    pub(crate) q: &'a [f64],
    pub(crate) zero: &'a [f64],
    trial: Vec<f64>,
    plus: Vec<f64>,
}

impl<'a> Tangent<'a> {
    pub(crate) fn new(
        model: &'a Model,
        forces: Forces,
        time: f64,
        q: &'a [f64],
        zero: &'a [f64],
    ) -> Self {
        Self {
            model,
            forces,
            time,
            q,
            zero,
            trial: q.to_vec(),
            plus: vec![0.0; q.len()],
        }
    }

    /// `out ← K_t v`.
    pub(crate) fn apply(
        &mut self,
        data: &mut Data,
        v: &[f64],
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        out.fill(0.0);
        self.difference(data, v, |plus, minus, h| {
            for ((o, p), m) in out.iter_mut().zip(plus).zip(minus) {
                *o = (p - m) / (2.0 * h);
            }
        })
    }

    /// `‖δ(K_t v)‖₂`, the round-off bound of the difference
    /// [`Tangent::apply`] forms, entry by entry
    /// [`super::modes::difference_noise`] (E7).
    pub(crate) fn noise(&mut self, data: &mut Data, v: &[f64]) -> Result<f64, DynamicsError> {
        let mut sum = 0.0;
        self.difference(data, v, |plus, minus, h| {
            for (p, m) in plus.iter().zip(minus) {
                sum += super::modes::difference_noise(*p, *m, h).powi(2);
            }
        })?;
        Ok(sum.sqrt())
    }

    /// The inverse dynamics at `q ± h v` (the step `h` scaled to `v`)
    /// handed to `pair(plus, minus, h)`; nothing for `v = 0`.
    fn difference(
        &mut self,
        data: &mut Data,
        v: &[f64],
        pair: impl FnOnce(&[f64], &[f64], f64),
    ) -> Result<(), DynamicsError> {
        let vmax = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        if vmax == 0.0 {
            return Ok(());
        }
        let qmax = self.q.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let h = 6e-6 * qmax / vmax;
        for sign in [1.0, -1.0] {
            for ((t, q), d) in self.trial.iter_mut().zip(self.q).zip(v) {
                *t = q + sign * h * d;
            }
            let tau = inverse_dynamics_with(
                self.model,
                data,
                self.forces,
                self.time,
                &self.trial,
                self.zero,
                self.zero,
            )?;
            if sign > 0.0 {
                self.plus.copy_from_slice(tau.as_slice());
            } else {
                pair(&self.plus, tau.as_slice(), h);
                return Ok(());
            }
        }
        Ok(())
    }
}

/// What [`gmres`] reached.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GmresOutcome {
    /// `‖b − A x‖₂ / ‖b‖₂` of the returned `x` (the recurrence's estimate).
    pub(crate) relative_residual: f64,
}

/// Restarted GMRES(`restart`) for `A x = b` from `x = 0`, right
/// preconditioned (`A P⁻¹ y = b`, `x = P⁻¹ y`, so the residual it
/// minimizes is the true one; E10): stops at `‖b − Ax‖ ≤ rtol ‖b‖` or
/// after `max_products` products. Modified Gram–Schmidt, Givens rotations.
pub(crate) fn gmres<E>(
    mut apply: impl FnMut(&[f64], &mut [f64]) -> Result<(), E>,
    mut precondition: impl FnMut(&mut [f64]),
    b: &[f64],
    x: &mut [f64],
    rtol: f64,
    restart: usize,
    max_products: usize,
) -> Result<GmresOutcome, E> {
    let n = b.len();
    x.fill(0.0);
    let bnorm = norm(b);
    if bnorm == 0.0 {
        return Ok(GmresOutcome {
            relative_residual: 0.0,
        });
    }
    let mut r = b.to_vec();
    let mut w = vec![0.0; n];
    let mut z = vec![0.0; n];
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(restart + 1);
    let mut h = vec![vec![0.0; restart]; restart + 1];
    let (mut cs, mut sn, mut g) = (
        vec![0.0; restart],
        vec![0.0; restart],
        vec![0.0; restart + 1],
    );
    let mut products = 0;
    let mut rel: f64;
    loop {
        // r = b − A x (x = 0 at the first cycle: r = b).
        let beta = norm(&r);
        rel = beta / bnorm;
        if rel <= rtol || products >= max_products {
            break;
        }
        basis.clear();
        basis.push(r.iter().map(|v| v / beta).collect());
        g.fill(0.0);
        g[0] = beta;
        let mut m = 0;
        while m < restart && products < max_products {
            z.copy_from_slice(&basis[m]);
            precondition(&mut z);
            apply(&z, &mut w)?;
            products += 1;
            for (i, v) in basis.iter().enumerate() {
                let hij = dot(&w, v);
                h[i][m] = hij;
                for (wk, vk) in w.iter_mut().zip(v) {
                    *wk -= hij * vk;
                }
            }
            let wn = norm(&w);
            h[m + 1][m] = wn;
            for i in 0..m {
                let t = cs[i] * h[i][m] + sn[i] * h[i + 1][m];
                h[i + 1][m] = -sn[i] * h[i][m] + cs[i] * h[i + 1][m];
                h[i][m] = t;
            }
            let d = h[m][m].hypot(h[m + 1][m]);
            (cs[m], sn[m]) = if d == 0.0 {
                (1.0, 0.0)
            } else {
                (h[m][m] / d, h[m + 1][m] / d)
            };
            h[m][m] = d;
            h[m + 1][m] = 0.0;
            g[m + 1] = -sn[m] * g[m];
            g[m] *= cs[m];
            m += 1;
            rel = g[m].abs() / bnorm;
            if rel <= rtol || wn == 0.0 || !rel.is_finite() {
                break;
            }
            basis.push(w.iter().map(|v| v / wn).collect());
        }
        // y = H⁻¹ g (upper triangular m × m), x += P⁻¹ V y.
        let mut y = vec![0.0; m];
        for i in (0..m).rev() {
            let s: f64 = (i + 1..m).map(|j| h[i][j] * y[j]).sum();
            y[i] = if h[i][i] == 0.0 {
                0.0
            } else {
                (g[i] - s) / h[i][i]
            };
        }
        z.fill(0.0);
        for (yi, v) in y.iter().zip(&basis) {
            for (zk, vk) in z.iter_mut().zip(v) {
                *zk += yi * vk;
            }
        }
        precondition(&mut z);
        for (xk, zk) in x.iter_mut().zip(&z) {
            *xk += zk;
        }
        if rel <= rtol || products >= max_products || !rel.is_finite() {
            break;
        }
        // Restart from the true residual.
        apply(x, &mut w)?;
        products += 1;
        for ((rk, bk), wk) in r.iter_mut().zip(b).zip(&w) {
            *rk = bk - wk;
        }
    }
    Ok(GmresOutcome {
        relative_residual: rel,
    })
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(crate) fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}
