//! Linearized natural modes about an equilibrium.

use super::matrices::stiffness_matrix;
use crate::algorithms::{check_vec, inverse_dynamics_with, mass_matrix};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector};

/// Natural frequencies and mode shapes, lowest first.
#[derive(Clone, Debug)]
pub struct Modes {
    /// Angular frequencies `ω_i` [rad/s]: `√ω²` for a stable mode, `−√|ω²|`
    /// for an unstable one (`ω² < −rigid_tolerance`), exactly `0` for a
    /// rigid (zero) mode, `|ω²| ≤ rigid_tolerance` (docs/theory.md E7).
    pub omega: DVector<f64>,
    /// Mode shapes in `q`, one per column, `M`-orthonormal (`VᵀMV = I`).
    pub shapes: DMatrix<f64>,
    /// Relative asymmetry `‖K_eff − K_effᵀ‖/‖K_eff‖` of the tangent
    /// stiffness: non-zero with follower loads or cables, which are not
    /// conservative; the symmetric part is used.
    pub asymmetry: f64,
    /// The `|ω²|` [rad²/s²] at or below which a mode is rigid (zero):
    /// the round-off of the eigenvalues, `n ε max|ω²|`, plus the bound
    /// `‖ |L⁻¹| |δK| |L⁻¹|ᵀ ‖_F` of the round-off `δK` of the differenced
    /// geometric stiffness mapped through `M = LLᵀ` (docs/theory.md E7).
    pub rigid_tolerance: f64,
}

/// What a linearized mode says of the equilibrium (docs/theory.md E7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeKind {
    /// `ω² > rigid_tolerance`: the mode oscillates.
    Stable,
    /// `|ω²| ≤ rigid_tolerance`: a rigid (zero) mode — a free body or
    /// joint that nothing holds; neutral, neither restored nor repelled.
    Rigid,
    /// `ω² < −rigid_tolerance`: the mode grows like `exp(|ω| t)`.
    Unstable,
}

impl Modes {
    /// The kind of mode `i` (by the sign of [`Modes::omega`], which is `0`
    /// exactly for a rigid mode).
    pub fn kind(&self, i: usize) -> ModeKind {
        let w = self.omega[i];
        if w > 0.0 {
            ModeKind::Stable
        } else if w < 0.0 {
            ModeKind::Unstable
        } else {
            ModeKind::Rigid
        }
    }

    /// Number of rigid (zero) modes.
    pub fn n_rigid(&self) -> usize {
        self.omega.iter().filter(|w| **w == 0.0).count()
    }

    /// Number of unstable modes (`ω² < −rigid_tolerance`).
    pub fn n_unstable(&self) -> usize {
        self.omega.iter().filter(|w| **w < 0.0).count()
    }

    /// Frequencies in Hz, `ω/2π`.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.omega
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect()
    }
}

/// Undamped modes of the model linearized about `q_eq` (which should be an
/// equilibrium, e.g. from [`crate::statics`]): the generalized symmetric
/// eigenproblem `K_eff v = ω² M v` with `K_eff = ∂ID(q, 0, 0)/∂q` (elastic
/// `K` exact, geometric stiffness of gravity/loads/cables by central
/// differences) and `M = M(q_eq)`, solved as `L⁻¹K_effL⁻ᵀ` with `M = LLᵀ`.
///
/// Prescribed joints (D59) hold their values at `time`, at rest.
pub fn modes(
    model: &Model,
    data: &mut Data,
    q_eq: &[f64],
    time: f64,
) -> Result<Modes, DynamicsError> {
    check_vec(model, "q", q_eq)?;
    if let (true, Some(tree)) = (model.has_closures(), &model.tree) {
        // Closed chains: K and M on the null space of J (docs/theory.md D69).
        crate::constraints::queries::check_workspace(model, data)?;
        return super::closed::modes(model, tree, data, q_eq, time);
    }
    let n = model.n_dof();
    let k = stiffness_matrix(model);
    let zero = vec![0.0; n];
    let at_rest = Forces::at_rest(1.0);
    let mut keff = k.clone();
    let mut qp = q_eq.to_vec();
    // |δK_ij|, the round-off of the differences (for the rigid tolerance).
    let mut noise = DMatrix::zeros(n, n);
    for j in 0..n {
        let h = 6e-6 * q_eq[j].abs().max(1.0);
        qp[j] = q_eq[j] + h;
        let plus = inverse_dynamics_with(model, data, at_rest, time, &qp, &zero, &zero)?.clone();
        qp[j] = q_eq[j] - h;
        let minus = inverse_dynamics_with(model, data, at_rest, time, &qp, &zero, &zero)?.clone();
        qp[j] = q_eq[j];
        for i in 0..n {
            keff[(i, j)] += (plus[i] - minus[i]) / (2.0 * h) - k[(i, j)];
            noise[(i, j)] = difference_noise(plus[i], minus[i], h);
        }
    }
    let asym = (&keff - keff.transpose()).norm() / keff.norm().max(f64::MIN_POSITIVE);
    let ksym = (&keff + keff.transpose()) * 0.5;
    let m = mass_matrix(model, data, q_eq)?.clone();
    let l = m
        .cholesky()
        .ok_or(DynamicsError::NotPositiveDefinite {
            what: "mass matrix",
        })?
        .l();
    let linv = l
        .clone()
        .try_inverse()
        .ok_or(DynamicsError::NotPositiveDefinite {
            what: "mass matrix (singular Cholesky factor)",
        })?;
    let c = &linv * ksym * linv.transpose();
    let c = (&c + c.transpose()) * 0.5;
    let eig = c.symmetric_eigen();
    let mapped_noise = mapped_noise(&linv, &noise);
    let (omega, rigid_tolerance) = frequencies(&eig.eigenvalues, mapped_noise, "mode")?;
    let mut shapes = DMatrix::zeros(n, n);
    let lt_inv = linv.transpose();
    for (i, o) in ascending(&eig.eigenvalues).into_iter().enumerate() {
        let v = &lt_inv * eig.eigenvectors.column(o);
        shapes.set_column(i, &v);
    }
    Ok(Modes {
        omega,
        shapes,
        asymmetry: asym,
        rigid_tolerance,
    })
}

/// Bound of the round-off of the central difference `(plus − minus)/2h`
/// of two evaluations of the static force: each carries a relative error
/// of a few `ε` (taken as 4ε, the sums of the recursions), so the
/// difference carries `4ε (|plus| + |minus|) / 2h`.
pub(crate) fn difference_noise(plus: f64, minus: f64, h: f64) -> f64 {
    4.0 * f64::EPSILON * (plus.abs() + minus.abs()) / (2.0 * h)
}

/// Bound of the perturbation of `C = B K Bᵀ` by a perturbation of `K`
/// with entries `|δK_ij| ≤ noise_ij`: `‖ |B| noise |B|ᵀ ‖_F`, elementwise
/// (tighter than `‖B‖² ‖δK‖`, which pairs the stiffest coordinates'
/// noise with the lightest coordinates' inverse mass), and a bound of
/// `‖δC‖₂`, hence of the eigenvalues' shift (Weyl).
pub(crate) fn mapped_noise(b: &DMatrix<f64>, noise: &DMatrix<f64>) -> f64 {
    let abs = b.abs();
    (&abs * noise * abs.transpose()).norm()
}

/// The indices of `values` in ascending order.
pub(crate) fn ascending(values: &DVector<f64>) -> Vec<usize> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    order
}

/// The angular frequencies of the eigenvalues `omega2` [rad²/s²], in
/// ascending order, and the rigid tolerance (docs/theory.md E7): `ω² =
/// 0` exactly when `|ω²| ≤ n ε max|ω²| + mapped_noise` (the eigensolver's
/// round-off, Weyl's bound `ε‖C‖₂` with a factor `n` for the reduction to
/// tridiagonal form, plus the differencing noise of `K_eff` mapped into
/// `C = L⁻¹K L⁻ᵀ`), else `sign(ω²)√|ω²|`. `what` names a mode in the error
/// of a non-finite frequency.
pub(crate) fn frequencies(
    omega2: &DVector<f64>,
    mapped_noise: f64,
    what: &str,
) -> Result<(DVector<f64>, f64), DynamicsError> {
    let n = omega2.len();
    let scale = omega2.amax();
    let tol = n as f64 * f64::EPSILON * scale + mapped_noise;
    let mut omega = DVector::zeros(n);
    for (i, o) in ascending(omega2).into_iter().enumerate() {
        let w2 = omega2[o];
        if !w2.is_finite() {
            return Err(DynamicsError::NotFinite {
                what: format!("angular frequency of {what} {i} [rad/s]"),
                value: w2,
            });
        }
        omega[i] = if w2.abs() <= tol {
            0.0
        } else {
            w2.signum() * w2.abs().sqrt()
        };
    }
    Ok((omega, tol))
}
