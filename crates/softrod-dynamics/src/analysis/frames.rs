//! Where the model is: the world poses of every rod base and body frame
//! (D51), and the pose and spatial Jacobian of any rod section through
//! joints and parents (D11, D57, D62).

use crate::algorithms::check_vec;
use crate::algorithms::frames::{
    FrameState, RowBlock, add_frame_columns, frame_state, frames as frames_on_tree,
};
use crate::error::DynamicsError;
use crate::model::Model;
use crate::model::closure::{ResolvedFrame, Target};
use crate::model::data::Data;
use crate::model::tree::Tree;
use nalgebra::Matrix6xX;
use softrod_kinematics::{Frame, RodKinematics};
use softrod_lie::{Mat6, Pose};

/// World poses of every rod's base frame (`data.rod_bases`, one per rod)
/// and every rigid body's frame (`data.body_poses`) at `q` (dim n_dof).
/// A rod's shape in the world is `rod_bases[r] · Rod::base()⁻¹ · g_local(s)`
/// for the poses of `softrod_kinematics` (which start from `Rod::base()`);
/// for a model without joints or parents `rod_bases[r] = Rod::base()`.
/// Prescribed joints (D59) take their values of the last
/// [`Model::set_time`] or dynamics evaluation.
pub fn frames(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), DynamicsError> {
    check_vec(model, "q", q)?;
    if let Some(tree) = &model.tree {
        frames_on_tree(model, tree, data, q);
    }
    Ok(())
}

/// The world pose `g(s)` of the section at `s` \[m\] of rod `rod` (index in
/// [`Model::rods`]) and its spatial Jacobian `J` (6 × n_dof, angular rows
/// first): `J q̇` is the section's world twist `Ad_g η` (angular velocity in
/// world axes, velocity of the world point at the world origin; D11). Every
/// coordinate that moves the section has its column: the rod's pieces up to
/// `s`, and on an articulated model its joint's and every ancestor's, each
/// taken where the path leaves it (D57, D62). Prescribed joints (D59) stand
/// at their last [`Model::set_time`]. Allocates `J`.
pub fn section_jacobian(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    rod: usize,
    s: f64,
) -> Result<(Pose, Matrix6xX<f64>), DynamicsError> {
    check_vec(model, "q", q)?;
    let count = model.rods().len();
    let rm = model
        .rods()
        .get(rod)
        .ok_or(DynamicsError::RodIndex { index: rod, count })?;
    let kin_err = |source| DynamicsError::Kinematics { rod, source };
    let r = &rm.spec.geometry;
    let n = model.n_dof();
    let mut jac = Matrix6xX::zeros(n);
    let Some(tree) = &model.tree else {
        let mut kin = RodKinematics::new(r);
        kin.update(r, &q[rm.dofs()], None, None).map_err(kin_err)?;
        let g = kin.pose_at(r, s).map_err(kin_err)?;
        let mut local = Matrix6xX::zeros(rm.n_dof());
        kin.jacobian_at(r, s, Frame::Spatial, &mut local)
            .map_err(kin_err)?;
        jac.columns_mut(rm.dof_offset, rm.n_dof()).copy_from(&local);
        return Ok((g, jac));
    };
    let (piece, x) = r.locate(s).map_err(kin_err)?;
    frames_on_tree(model, tree, data, q);
    let frame = ResolvedFrame {
        target: Target::Rod {
            rod,
            piece,
            x,
            node: tree.rod_nodes[rod][piece],
        },
        offset: Pose::identity(),
    };
    let fs = frame_state(model, tree, data, &frame, q, None);
    jac.copy_from(&frame_columns(tree, data, &fs, n));
    Ok((fs.pose, jac))
}

/// The six rows of the frame `fs` as columns of every coordinate that
/// moves it (the closures' frame machinery, D63–D64), 6 × `n`.
fn frame_columns(tree: &Tree, data: &Data, fs: &FrameState, n: usize) -> nalgebra::DMatrix<f64> {
    let mut dense = nalgebra::DMatrix::zeros(6, n);
    let identity = Mat6::identity();
    let block = RowBlock {
        c: &identity,
        m: 6,
        row: 0,
        sign: 1.0,
    };
    add_frame_columns(tree, data, fs, block, &mut dense);
    dense
}

/// The world pose `g_b` of rigid body `body`'s frame (index in
/// [`Model::bodies`]; the frame of `data.body_poses`, whose origin is the
/// point of application of the body's loads, not its centre of mass) and
/// its spatial Jacobian `J` (6 × n_dof, angular rows first), as
/// [`section_jacobian`]: `J q̇ = (ω, v₀)` with `ω` the body's angular
/// velocity in world axes \[rad/s\] and `v₀` the velocity of the body-fixed
/// point at the world origin \[m/s\] (D11, D57), so the body frame's
/// origin `p` moves at `v₀ + ω × p = J_v q̇ − [p]× J_ω q̇`. The columns are
/// those of the body's joint and of every ancestor (the frame machinery
/// of the closures' rows, D63–D64); prescribed joints (D59) stand at
/// their last [`Model::set_time`]. Allocates `J`.
pub fn body_jacobian(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    body: usize,
) -> Result<(Pose, Matrix6xX<f64>), DynamicsError> {
    check_vec(model, "q", q)?;
    let count = model.bodies().len();
    // A model with bodies has a tree (a body always hangs from a parent).
    let (Some(tree), true) = (&model.tree, body < count) else {
        return Err(DynamicsError::BodyIndex { index: body, count });
    };
    frames_on_tree(model, tree, data, q);
    let frame = ResolvedFrame {
        target: Target::Body {
            node: tree.body_nodes[body],
        },
        offset: Pose::identity(),
    };
    let fs = frame_state(model, tree, data, &frame, q, None);
    let n = model.n_dof();
    let mut jac = Matrix6xX::zeros(n);
    jac.copy_from(&frame_columns(tree, data, &fs, n));
    Ok((fs.pose, jac))
}
