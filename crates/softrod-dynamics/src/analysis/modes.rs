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
    /// Angular frequencies `ω_i` [rad/s] (negative `ω²` — an unstable
    /// equilibrium — are reported as `−√|ω²|`).
    pub omega: DVector<f64>,
    /// Mode shapes in `q`, one per column, `M`-orthonormal (`VᵀMV = I`).
    pub shapes: DMatrix<f64>,
    /// Relative asymmetry `‖K_eff − K_effᵀ‖/‖K_eff‖` of the tangent
    /// stiffness: non-zero with follower loads or cables, which are not
    /// conservative; the symmetric part is used.
    pub asymmetry: f64,
}

impl Modes {
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
    for j in 0..n {
        let h = 6e-6 * q_eq[j].abs().max(1.0);
        qp[j] = q_eq[j] + h;
        let plus = inverse_dynamics_with(model, data, at_rest, time, &qp, &zero, &zero)?.clone();
        qp[j] = q_eq[j] - h;
        let minus = inverse_dynamics_with(model, data, at_rest, time, &qp, &zero, &zero)?.clone();
        qp[j] = q_eq[j];
        for i in 0..n {
            keff[(i, j)] += (plus[i] - minus[i]) / (2.0 * h) - k[(i, j)];
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
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let mut omega = DVector::zeros(n);
    let mut shapes = DMatrix::zeros(n, n);
    let lt_inv = linv.transpose();
    for (i, &o) in order.iter().enumerate() {
        let w2 = eig.eigenvalues[o];
        omega[i] = w2.signum() * w2.abs().sqrt();
        let v = &lt_inv * eig.eigenvectors.column(o);
        shapes.set_column(i, &v);
    }
    if let Some((i, &value)) = omega.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!("angular frequency of mode {i} [rad/s]"),
            value,
        });
    }
    Ok(Modes {
        omega,
        shapes,
        asymmetry: asym,
    })
}
