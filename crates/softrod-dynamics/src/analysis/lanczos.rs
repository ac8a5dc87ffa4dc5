//! The lowest modes without a dense eigensolve (docs/theory.md E11):
//! shift-invert Lanczos on `K_eff⁻¹ M` in the `M` inner product, with
//! `K_eff` solves by the Krylov iterations of the structured statics and
//! `M` products by one inverse dynamics. O(N) per Lanczos step.

use super::krylov::{BlockStiffness, Tangent, dot, gmres};
use super::modes::Modes;
use crate::algorithms::{check_vec, inverse_dynamics_with};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector};

/// Relative asymmetry of `K_eff` above which [`lowest_modes`] refuses
/// ([`DynamicsError::NotSymmetric`]). Conservative loads (gravity, dead
/// point forces) leave round-off (~3·10⁻¹⁴); world-frame moments, follower
/// loads and cables are not conservative (2.5·10⁻⁶ on the test models).
/// A skew part `E` moves the eigenvalues of the symmetric part only at
/// second order, but Lanczos assumes `K⁻¹M` self-adjoint and `K⁻¹`
/// amplifies `E` by the condition number of `K` (soft bending against
/// stiff stretch, 10³–10⁶): at 2.5·10⁻⁶ the Ritz values left the spectrum
/// by 0.8 %. Below `10⁻⁹` that amplified error stays under the solves'
/// tolerance; the probes' estimate resolves ~10⁻¹¹.
const MAX_ASYMMETRY: f64 = 1e-9;

/// The `count` lowest undamped modes of the model linearized about `q_eq`
/// (an equilibrium, e.g. from [`crate::statics`]) at `time`: the same
/// problem `K_eff v = ω² M v` and the same [`Modes`] as [`crate::modes`]
/// (`count` columns of `shapes`, `M`-orthonormal), without any `n × n`
/// matrix — O(N) memory and per step (docs/theory.md E11):
///
/// - shift-invert Lanczos: `K_eff⁻¹ M` is self-adjoint in `⟨x, y⟩_M =
///   xᵀMy` and its largest eigenvalues `θ = 1/ω²` are the lowest modes,
///   separated as `1/ω²` (a beam's `θ₁/θ₂ ≈ 39`), so a few Lanczos steps
///   per mode converge them; full reorthogonalization;
/// - `K_eff x = b` by right-preconditioned GMRES with products `K_eff v`
///   by a central difference of two O(N) inverse dynamics and the
///   block-diagonal `K` as preconditioner (E9, E10);
/// - `M x = ID(q, 0, x)` with every force off (one O(N) inverse dynamics).
///
/// A Ritz pair `(θ, x)` is converged when its residual `|β_m s_m| ≤ 10⁻⁹
/// |θ|` (the Lanczos estimate of `‖K_eff⁻¹Mx − θx‖_M`).
/// [`Modes::asymmetry`] is estimated from bilinear forms `uᵀK_eff v −
/// vᵀK_eff u` of six random probes (±30 %), and
/// [`Modes::rigid_tolerance`] is the differencing noise of the products
/// mapped onto the returned modes, `max_i ‖v_i‖ ‖δ(K_eff v_i)‖` (E7's
/// noise term; shift-invert resolves the lowest `ω²` to relative accuracy,
/// so E7's eigensolver term `n ε ω²_max` has no counterpart).
///
/// Needs an open model whose `K` is positive definite (rods; joints with
/// springs) — [`DynamicsError::UnsupportedClosed`],
/// [`DynamicsError::NotPositiveDefinite`] otherwise — and a symmetric
/// `K_eff` ([`DynamicsError::NotSymmetric`] with follower loads or
/// cables: use [`crate::modes`], which takes the symmetric part). An
/// equilibrium whose `K_eff` is singular (a buckling load) makes the
/// solves fail ([`DynamicsError::NotFinite`]).
pub fn lowest_modes(
    model: &Model,
    data: &mut Data,
    q_eq: &[f64],
    time: f64,
    count: usize,
) -> Result<Modes, DynamicsError> {
    check_vec(model, "q", q_eq)?;
    if model.has_closures() {
        return Err(DynamicsError::UnsupportedClosed {
            what: "lowest_modes",
        });
    }
    let n = model.n_dof();
    let count = count.min(n);
    let stiffness = BlockStiffness::new(model);
    if !stiffness.is_definite() {
        return Err(DynamicsError::NotPositiveDefinite {
            what: "generalized stiffness K, the preconditioner of lowest_modes (a joint without a spring?)",
        });
    }
    let zero = vec![0.0; n];
    let mut tangent = Tangent::new(model, Forces::at_rest(1.0), time, q_eq, &zero);
    let mut ops = Operators {
        model,
        time,
        q: q_eq,
        zero: &zero,
        stiffness: &stiffness,
    };
    let asymmetry = estimate_asymmetry(&mut tangent, data, n)?;
    if asymmetry > MAX_ASYMMETRY {
        return Err(DynamicsError::NotSymmetric {
            what: "lowest_modes",
            asymmetry,
        });
    }
    if count == 0 {
        return Ok(Modes {
            omega: DVector::zeros(0),
            shapes: DMatrix::zeros(n, 0),
            asymmetry,
            rigid_tolerance: 0.0,
        });
    }
    // Lanczos basis V (columns v_j) and the products M v_j.
    let mut v: Vec<Vec<f64>> = Vec::new();
    let mut mv: Vec<Vec<f64>> = Vec::new();
    let (mut alpha, mut beta) = (Vec::<f64>::new(), Vec::<f64>::new());
    // Start: a smooth vector with every coordinate present.
    let mut w: Vec<f64> = (0..n)
        .map(|i| 1.0 + 0.5 * (0.37 * i as f64).sin())
        .collect();
    let mut mw = vec![0.0; n];
    ops.mass(data, &w, &mut mw)?;
    let scale = dot(&w, &mw).sqrt();
    w.iter_mut().for_each(|x| *x /= scale);
    mw.iter_mut().for_each(|x| *x /= scale);
    v.push(w.clone());
    mv.push(mw.clone());
    // Beyond this the lowest modes are not separated enough for Lanczos to
    // matter: the Ritz values at the cap are returned.
    let max_steps = n.min(20 * count + 100);
    let mut result = None;
    loop {
        let j = v.len() - 1;
        // w = K_eff⁻¹ M v_j.
        ops.solve(&mut tangent, data, &mv[j], &mut w)?;
        let a = dot(&w, &mv[j]);
        alpha.push(a);
        // Full reorthogonalization, twice (Kahan: twice is enough).
        for _ in 0..2 {
            for (vi, mvi) in v.iter().zip(&mv) {
                let c = dot(&w, mvi);
                w.iter_mut().zip(vi).for_each(|(x, y)| *x -= c * y);
            }
        }
        ops.mass(data, &w, &mut mw)?;
        let b = dot(&w, &mw).max(0.0).sqrt();
        let steps = alpha.len();
        // An exhausted Krylov space (b = 0) holds fewer modes than asked.
        if steps >= count || b == 0.0 {
            let take = count.min(steps);
            let (theta, s) = tridiagonal_eigen(&alpha, &beta);
            // The `count` largest θ (lowest positive ω²) …; negative θ
            // (unstable modes) have the largest |θ| when they are lowest in ω².
            let order = by_magnitude(&theta);
            let wanted = &order[..take];
            let converged = wanted
                .iter()
                .all(|&i| (b * s[(steps - 1, i)]).abs() <= 1e-9 * theta[i].abs());
            if converged || steps >= max_steps || b == 0.0 {
                result = Some((theta, s, order, take));
            }
        }
        if let Some((theta, s, order, take)) = result {
            return finish(&v, &theta, &s, &order[..take], asymmetry, |shape| {
                tangent.noise(data, shape)
            });
        }
        beta.push(b);
        w.iter_mut().for_each(|x| *x /= b);
        mw.iter_mut().for_each(|x| *x /= b);
        v.push(w.clone());
        mv.push(mw.clone());
    }
}

/// The products and solves of [`lowest_modes`] at `q`.
struct Operators<'a> {
    model: &'a Model,
    time: f64,
    q: &'a [f64],
    zero: &'a [f64],
    stiffness: &'a BlockStiffness,
}

/// Every force off: `ID(q, 0, q̈) = M(q) q̈` exactly (no gravity — its
/// scale is 0 —, no elasticity, loads, cables or springs, drives at rest).
const INERTIA_ONLY: Forces = Forces::GRAVITY.with_load_scale(0.0);

impl Operators<'_> {
    /// `out ← M(q) x`.
    fn mass(&mut self, data: &mut Data, x: &[f64], out: &mut [f64]) -> Result<(), DynamicsError> {
        let tau = inverse_dynamics_with(
            self.model,
            data,
            INERTIA_ONLY,
            self.time,
            self.q,
            self.zero,
            x,
        )?;
        out.copy_from_slice(tau.as_slice());
        Ok(())
    }

    /// `x ← K_eff⁻¹ b` to a relative residual `10⁻¹¹`.
    fn solve(
        &mut self,
        tangent: &mut Tangent,
        data: &mut Data,
        b: &[f64],
        x: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let k = self.stiffness;
        let outcome = gmres(
            |v, out| tangent.apply(data, v, out),
            |y| k.solve(y),
            b,
            x,
            1e-11,
            80,
            800,
        )?;
        if outcome.relative_residual.is_nan() || outcome.relative_residual > 1e-8 {
            return Err(DynamicsError::NotFinite {
                what: format!(
                    "relative residual of the K_eff solve of lowest_modes (singular K_eff, a buckling load?): {:e}",
                    outcome.relative_residual
                ),
                value: outcome.relative_residual,
            });
        }
        Ok(())
    }
}

/// `‖K − Kᵀ‖_F / ‖K‖_F` estimated from six random probes `u_i`: for
/// Gaussian `u, v`, `E[(uᵀAv)²] = ‖A‖²_F`, so the mean of
/// `(u_iᵀKu_j − u_jᵀKu_i)²` over pairs over the mean of `(u_iᵀKu_j)²`
/// estimates the square of the ratio.
fn estimate_asymmetry(
    tangent: &mut Tangent,
    data: &mut Data,
    n: usize,
) -> Result<f64, DynamicsError> {
    const PROBES: usize = 6;
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut gauss = || {
        // Box–Muller on a small LCG: reproducible, no dependency.
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (uniform(), uniform());
        (-2.0 * a.ln()).sqrt() * (2.0 * std::f64::consts::PI * b).cos()
    };
    let probes: Vec<Vec<f64>> = (0..PROBES)
        .map(|_| (0..n).map(|_| gauss()).collect())
        .collect();
    let mut products = vec![vec![0.0; n]; PROBES];
    for (u, ku) in probes.iter().zip(&mut products) {
        tangent.apply(data, u, ku)?;
    }
    let (mut skew, mut full) = (0.0, 0.0);
    for i in 0..PROBES {
        for j in 0..PROBES {
            if i == j {
                continue;
            }
            let kij = dot(&probes[i], &products[j]);
            full += kij * kij;
            if i < j {
                let kji = dot(&probes[j], &products[i]);
                skew += (kij - kji).powi(2);
            }
        }
    }
    let pairs = (PROBES * (PROBES - 1)) as f64;
    Ok(((skew / (pairs / 2.0)) / (full / pairs).max(f64::MIN_POSITIVE)).sqrt())
}

/// Eigenvalues and eigenvectors (columns) of the symmetric tridiagonal
/// matrix with diagonal `alpha` and off-diagonal `beta`.
fn tridiagonal_eigen(alpha: &[f64], beta: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
    let m = alpha.len();
    let t = DMatrix::from_fn(m, m, |i, j| {
        if i == j {
            alpha[i]
        } else if i + 1 == j {
            beta[i]
        } else if j + 1 == i {
            beta[j]
        } else {
            0.0
        }
    });
    let e = t.symmetric_eigen();
    (e.eigenvalues, e.eigenvectors)
}

/// Indices of `theta` by decreasing `|θ|` (increasing `|ω²|`).
fn by_magnitude(theta: &DVector<f64>) -> Vec<usize> {
    let mut order: Vec<usize> = (0..theta.len()).collect();
    order.sort_by(|&a, &b| theta[b].abs().total_cmp(&theta[a].abs()));
    order
}

/// The [`Modes`] of the Ritz pairs `wanted` (by increasing `|ω²|`), sorted
/// by `ω` as [`crate::modes`] sorts them.
fn finish(
    v: &[Vec<f64>],
    theta: &DVector<f64>,
    s: &DMatrix<f64>,
    wanted: &[usize],
    asymmetry: f64,
    mut noise: impl FnMut(&[f64]) -> Result<f64, DynamicsError>,
) -> Result<Modes, DynamicsError> {
    let n = v[0].len();
    let mut pairs: Vec<(f64, usize)> = wanted.iter().map(|&i| (1.0 / theta[i], i)).collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut omega2 = DVector::zeros(pairs.len());
    let mut shapes = DMatrix::zeros(n, pairs.len());
    let mut rigid_tolerance: f64 = 0.0;
    for (c, (w2, i)) in pairs.into_iter().enumerate() {
        if !w2.is_finite() {
            return Err(DynamicsError::NotFinite {
                what: format!("angular frequency of mode {c} [rad/s]"),
                value: w2,
            });
        }
        omega2[c] = w2;
        for (j, vj) in v.iter().enumerate().take(s.nrows()) {
            let sj = s[(j, i)];
            for (x, y) in shapes.column_mut(c).iter_mut().zip(vj) {
                *x += sj * y;
            }
        }
        let shape = shapes.column(c).clone_owned();
        rigid_tolerance = rigid_tolerance.max(shape.norm() * noise(shape.as_slice())?);
    }
    let omega = omega2.map(|w2: f64| {
        if w2.abs() <= rigid_tolerance {
            0.0
        } else {
            w2.signum() * w2.abs().sqrt()
        }
    });
    Ok(Modes {
        omega,
        shapes,
        asymmetry,
        rigid_tolerance,
    })
}
