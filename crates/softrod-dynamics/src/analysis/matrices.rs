//! The matrices of the Lagrangian form, (C10) and (D19)–(D22), on request.

use crate::algorithms::{Motion, chain, check_vec, tree};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector, Matrix6xX};
use softrod_kinematics::{Frame, RodKinematics};
use softrod_lie::coad_vec;

/// Generalized gravity `G(q) = −∫ Jᵀ 𝓜 Ad⁻¹_{g(s)} 𝒢 ds = ∂V_g/∂q` (D22), on
/// the left-hand side of the equations of motion; zero without gravity.
/// Equals `ID(q, 0, 0)` with only gravity on.
pub fn generalized_gravity(
    model: &Model,
    data: &mut Data,
    q: &[f64],
) -> Result<DVector<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    let zero = vec![0.0; model.n_dof()];
    // At rest, gravity alone; prescribed joints where the last evaluation
    // left them (no time is set).
    let motion = Motion::new(q, None, Some(&zero));
    match &model.tree {
        Some(tr) => tree::inverse_dynamics(model, tr, data, Forces::GRAVITY, 0.0, motion),
        None => chain::inverse_dynamics_general(model, data, Forces::GRAVITY, 0.0, motion),
    }
    Ok(data.tau.clone())
}

/// Block-diagonal generalized stiffness `K = diag(K_n)`, `K_n = ∫B_nᵀΓB_n ds`
/// (D13), with the joints' spring constants on their coordinates (D53).
pub fn stiffness_matrix(model: &Model) -> DMatrix<f64> {
    let mut m = block_diag(model, |pd| &pd.stiffness);
    joint_diag(model, &mut m, 0);
    m
}

/// Block-diagonal generalized damping `D = diag(D_n)`, `D_n = ∫B_nᵀγB_n ds`
/// (D13), with the joints' damping constants on their coordinates (D53).
pub fn damping_matrix(model: &Model) -> DMatrix<f64> {
    let mut m = block_diag(model, |pd| &pd.damping);
    joint_diag(model, &mut m, 1);
    m
}

/// Joint spring (`which = 0`) or damper (`1`) constants on the diagonal.
fn joint_diag(model: &Model, m: &mut DMatrix<f64>, which: usize) {
    for e in model.elements() {
        for (i, o) in e.joint_dofs.clone().enumerate() {
            let (k, d, _) = e.attachment.joint.coefficients(i);
            m[(o, o)] = if which == 0 { k } else { d };
        }
    }
}

fn block_diag(
    model: &Model,
    f: impl Fn(&crate::model::rod::PieceData) -> &DMatrix<f64>,
) -> DMatrix<f64> {
    let n = model.n_dof();
    let mut m = DMatrix::zeros(n, n);
    for rm in model.rods() {
        for (piece, pd) in rm.spec.geometry.pieces().iter().zip(&rm.pieces) {
            let o = rm.dof_offset + piece.dof_offset;
            let k = piece.basis.dof();
            m.view_mut((o, o), (k, k)).copy_from(f(pd));
        }
    }
    m
}

/// Actuation matrix (n_dof × n_cables): column `c` is the generalized force
/// of cable `c` per unit tension, `−∂ℓ_c/∂q` (D15). Cables are numbered rod
/// by rod in the order given.
pub fn actuation_matrix(model: &Model, q: &[f64]) -> Result<DMatrix<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    let mut a = DMatrix::zeros(model.n_dof(), model.n_cables());
    let mut col = 0;
    for rm in model.rods() {
        let range = rm.dofs();
        for cable in &rm.spec.cables {
            let mut v = vec![0.0; rm.n_dof()];
            cable.add_force_per_tension(
                &rm.spec.geometry,
                &q[range.clone()],
                &model.quadrature,
                &mut v,
            );
            for (i, x) in v.iter().enumerate() {
                a[(range.start + i, col)] = *x;
            }
            col += 1;
        }
    }
    Ok(a)
}

/// Coriolis/centrifugal matrix `C(q, q̇)` with `C q̇ = ∫Jᵀ(ad*_η𝓜η + 𝓜J̇q̇) ds`
/// (D21) and `Ṁ − 2C` skew-symmetric.
///
/// Only `C q̇` is unique. The seed's (12), `∫Jᵀ(ad*_{Jq̇}𝓜J + 𝓜J̇)`, gives the
/// right product but `ad*_η𝓜` is not skew, so `Ṁ − 2C` is not skew with it.
/// We use `C = ∫Jᵀ(Λ(𝓜η) J + 𝓜J̇) ds` with `Λ(F)ζ := ad*_ζ F`: `Λ(F) =
/// [[−m̃, −f̃], [−f̃, 0]]` for `F = (m, f)` is skew, `Λ(𝓜η)η = ad*_η𝓜η`, and
/// `C + Cᵀ = ∫(Jᵀ𝓜J̇ + J̇ᵀ𝓜J) = Ṁ` because `𝓜` is constant in the body frame.
/// Built from explicit Jacobians (true `J̇` of (D12)) at the Gauss points:
/// O(N·n_dof²), for analysis and control, not for simulation (use
/// [`crate::bias_force`]).
pub fn coriolis_matrix(
    model: &Model,
    q: &[f64],
    qd: &[f64],
) -> Result<DMatrix<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    model.require_chain("coriolis_matrix")?;
    let n = model.n_dof();
    let mut c = DMatrix::zeros(n, n);
    for (r, rm) in model.rods().iter().enumerate() {
        let kinematics = |source| DynamicsError::Kinematics { rod: r, source };
        let rod = &rm.spec.geometry;
        let range = rm.dofs();
        let k = rod.n_dof();
        let mut kin = RodKinematics::new(rod);
        kin.update(rod, &q[range.clone()], Some(&qd[range.clone()]), None)
            .map_err(kinematics)?;
        let mut j = Matrix6xX::zeros(k);
        let mut jd = Matrix6xX::zeros(k);
        let qdr = DVector::from_column_slice(&qd[range.clone()]);
        for (piece, pd) in rod.pieces().iter().zip(&rm.pieces) {
            for qp in &pd.points {
                let s = piece.start + qp.x;
                kin.jacobian_at(rod, s, Frame::Body, &mut j)
                    .map_err(kinematics)?;
                kin.jacobian_dot_at(rod, s, Frame::Body, &mut jd)
                    .map_err(kinematics)?;
                let eta: softrod_lie::Vec6 = (&j * &qdr).fixed_rows::<6>(0).into_owned();
                // inner = Λ(𝓜η) J + 𝓜 J̇ (6×k), Λ(F) jc = ad*_{jc} F.
                let m_eta = qp.inertia.component_mul(&eta);
                let mut inner = Matrix6xX::zeros(k);
                for col in 0..k {
                    let jc: softrod_lie::Vec6 = j.fixed_view::<6, 1>(0, col).into_owned();
                    let jdc: softrod_lie::Vec6 = jd.fixed_view::<6, 1>(0, col).into_owned();
                    let v = coad_vec(&jc, &m_eta) + qp.inertia.component_mul(&jdc);
                    inner.set_column(col, &v);
                }
                let blk = j.transpose() * inner * qp.w;
                let mut view = c.view_mut((range.start, range.start), (k, k));
                view += blk;
            }
        }
    }
    Ok(c)
}
