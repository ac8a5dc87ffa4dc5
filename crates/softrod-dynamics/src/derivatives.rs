//! Jacobians of the forward dynamics, for the stiff integrators.

use crate::algorithms::{check_vec, forward_dynamics, inverse_dynamics, mass_matrix};
use crate::data::Data;
use crate::error::DynamicsError;
use crate::matrices::{damping_matrix, stiffness_matrix};
use crate::model::Model;
use nalgebra::{DMatrix, DVector};

/// `∂q̈/∂q` and `∂q̈/∂q̇` (n_dof × n_dof each).
#[derive(Clone, Debug)]
pub struct DynamicsJacobians {
    /// `∂q̈/∂q`.
    pub dqdd_dq: DMatrix<f64>,
    /// `∂q̈/∂q̇`.
    pub dqdd_dqd: DMatrix<f64>,
    /// The `q̈` they were taken at.
    pub qdd: DVector<f64>,
}

/// Jacobians of the forward dynamics at `(q, q̇, t)` under `τ_act`.
///
/// From `ID(q, q̇, q̈(q, q̇)) = τ_act`: `∂q̈/∂q = −M⁻¹ ∂ID/∂q|_{q̈}` and
/// `∂q̈/∂q̇ = −M⁻¹ ∂ID/∂q̇|_{q̈}`. The stiff, constant parts are exact —
/// `∂ID/∂q = K + ∂(ID − Kq)/∂q`, `∂ID/∂q̇ = D + ∂(ID − Dq̇)/∂q̇` — and only the
/// soft remainder is taken by central differences (step `6e-6·max(1, |x|)`,
/// ~1e-10 relative), so the stiffness the integrator must see is never
/// blurred by differencing error. Cost: `4·n_dof` inverse dynamics (O(N)
/// each), one `M` and one Cholesky; allocates its outputs.
pub fn dynamics_jacobians(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<DynamicsJacobians, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    let n = model.n_dof();
    let qdd = forward_dynamics(model, data, t, q, qd, tau_act)?.clone();
    let k = stiffness_matrix(model);
    let d = damping_matrix(model);
    let mut dq = k.clone();
    let mut dqd = d.clone();
    let mut qp = q.to_vec();
    let mut qdp = qd.to_vec();
    for j in 0..n {
        let h = 6e-6 * q[j].abs().max(1.0);
        qp[j] = q[j] + h;
        let plus = inverse_dynamics(model, data, t, &qp, qd, qdd.as_slice())?.clone();
        qp[j] = q[j] - h;
        let minus = inverse_dynamics(model, data, t, &qp, qd, qdd.as_slice())?.clone();
        qp[j] = q[j];
        for i in 0..n {
            // Remove the linear elastic part K (exact above) from the difference.
            dq[(i, j)] += (plus[i] - minus[i]) / (2.0 * h) - k[(i, j)];
        }
        let h = 6e-6 * qd[j].abs().max(1.0);
        qdp[j] = qd[j] + h;
        let plus = inverse_dynamics(model, data, t, q, &qdp, qdd.as_slice())?.clone();
        qdp[j] = qd[j] - h;
        let minus = inverse_dynamics(model, data, t, q, &qdp, qdd.as_slice())?.clone();
        qdp[j] = qd[j];
        for i in 0..n {
            dqd[(i, j)] += (plus[i] - minus[i]) / (2.0 * h) - d[(i, j)];
        }
    }
    let m = mass_matrix(model, data, q)?.clone();
    let chol = m.cholesky().ok_or(DynamicsError::NotPositiveDefinite {
        what: "mass matrix",
    })?;
    Ok(DynamicsJacobians {
        dqdd_dq: -chol.solve(&dq),
        dqdd_dqd: -chol.solve(&dqd),
        qdd,
    })
}
