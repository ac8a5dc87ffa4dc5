//! What a caller asks of the closures at a state: the residual and its
//! norms (D66), the Jacobian and its rank, whether the closures hold, the
//! multipliers of the last constrained forward dynamics.

use super::rows::assemble;
use crate::algorithms::tree::outward;
use crate::algorithms::{Motion, Pass, check_vec};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::closure::{ClosureKind, ResolvedClosure};
use crate::model::data::{ConstraintRows, Data};
use nalgebra::{DMatrix, DVector};

/// The model's length scale for residual norms: its longest rod \[m\].
pub(crate) fn length_scale(model: &Model) -> f64 {
    model
        .rods
        .iter()
        .map(|r| r.spec.geometry.length())
        .fold(0.0, f64::max)
}

/// One number per closure from its rows of `φ`: `max(‖d‖, ℓ‖r‖)` \[m\]
/// with `ℓ` the model's length scale (D66) — a rotation misfit counted by
/// the displacement it causes one model length away.
pub(crate) fn closure_norm(model: &Model, rc: &ResolvedClosure, phi: &DVector<f64>) -> f64 {
    let v = |i: usize| phi[rc.row + i];
    let norm3 = |o: usize| (v(o).powi(2) + v(o + 1).powi(2) + v(o + 2).powi(2)).sqrt();
    match rc.spec.kind {
        ClosureKind::Weld => norm3(3).max(length_scale(model) * norm3(0)),
        ClosureKind::Ball => norm3(0),
        ClosureKind::Slider { .. } => v(0).hypot(v(1)),
    }
}

/// The stacked closure residual `φ(q)` (D63; weld rows `(r, d)`, ball `d`,
/// slider the two components of `d` normal to the axis; radians and
/// metres, b's axes). Allocates; for checks and tests.
pub fn constraint_residual(
    model: &Model,
    data: &mut Data,
    q: &[f64],
) -> Result<DVector<f64>, DynamicsError> {
    let (phi, _) = residual_and_jacobian(model, data, q, true)?;
    Ok(phi)
}

/// The constraint Jacobian `J = ∂φ/∂q` (m×n_dof, D64) at `q`. Allocates.
pub fn constraint_jacobian(
    model: &Model,
    data: &mut Data,
    q: &[f64],
) -> Result<DMatrix<f64>, DynamicsError> {
    let (_, j) = residual_and_jacobian(model, data, q, true)?;
    Ok(j)
}

/// Per closure, in model order, the norm of its residual
/// `max(‖d‖, ℓ‖r‖)` \[m\] (D66; ℓ the longest rod's length).
pub fn closure_residuals(
    model: &Model,
    data: &mut Data,
    q: &[f64],
) -> Result<Vec<f64>, DynamicsError> {
    let phi = constraint_residual(model, data, q)?;
    Ok(model
        .closures
        .iter()
        .map(|rc| closure_norm(model, rc, &phi))
        .collect())
}

/// [`DynamicsError::ClosureNotHeld`] for the first closure whose residual
/// norm ([`closure_residuals`]) exceeds `1e-9 ℓ` at `q` (the initial-state
/// policy of D66: a closure must hold at the start; nothing assembles it).
pub fn check_closures(model: &Model, data: &mut Data, q: &[f64]) -> Result<(), DynamicsError> {
    let tol = Model::CLOSURE_TOLERANCE * length_scale(model);
    let res = closure_residuals(model, data, q)?;
    for (rc, r) in model.closures.iter().zip(res) {
        if r > tol {
            return Err(DynamicsError::ClosureNotHeld {
                closure: rc.spec.name.clone(),
                residual: r,
                tolerance: tol,
            });
        }
    }
    Ok(())
}

/// [`DynamicsError::WorkspaceMismatch`] when `data` was not made by
/// [`Data::new`] for this closed model (e.g. before `with_closures`).
pub(crate) fn check_workspace(model: &Model, data: &Data) -> Result<(), DynamicsError> {
    let nodes = model.tree.as_ref().map_or(0, |t| t.nodes.len());
    let (n, m) = (model.n_dof(), model.n_constraints());
    let fits = data.nodes.len() == nodes
        && data.tau.len() == n
        && (m == 0
            || data
                .closure
                .as_ref()
                .is_some_and(|w| w.rows.jac.nrows() == m && w.rows.jac.ncols() == n));
    if fits {
        return Ok(());
    }
    Err(DynamicsError::WorkspaceMismatch {
        what: "Data (make it with Data::new after Model::with_closures)",
        built: data.tau.len(),
        got: n,
    })
}

pub(crate) fn residual_and_jacobian(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    exact: bool,
) -> Result<(DVector<f64>, DMatrix<f64>), DynamicsError> {
    check_vec(model, "q", q)?;
    check_workspace(model, data)?;
    let mut rows = ConstraintRows::new(model.n_constraints(), model.n_dof());
    if let Some(tree) = &model.tree {
        let motion = Motion::at_rest(q);
        outward(model, tree, data, motion, Pass::Composite, Forces::ALL);
        assemble(model, tree, data, motion, exact, &mut rows);
    }
    Ok((rows.phi, rows.jac))
}

/// Numerical rank of the closures' Jacobian at `q` (singular values above
/// `1e-10` of the largest): the net DoF of the closed model is
/// `n_dof − rank`.
pub fn constraint_rank(model: &Model, data: &mut Data, q: &[f64]) -> Result<usize, DynamicsError> {
    let j = constraint_jacobian(model, data, q)?;
    if j.nrows() == 0 {
        return Ok(0);
    }
    let sv = j.singular_values();
    let smax = sv.iter().fold(0.0_f64, |a, &b| a.max(b));
    Ok(sv.iter().filter(|&&s| s > 1e-10 * smax).count())
}

/// The constraint state of the last constrained [`crate::forward_dynamics`]
/// in `data`: multipliers `λ` (per closure rows; the wrench on frame a in
/// b's axes, angular first for welds) and the numerical rank of
/// `J M⁻¹ Jᵀ`. `None` for a model without closures.
pub fn closure_multipliers(data: &Data) -> Option<(&DVector<f64>, usize)> {
    data.closure.as_ref().map(|w| (&w.lambda, w.rank))
}

/// The largest closure residual norm (D66) at `q` \[m\].
pub fn max_closure_residual(
    model: &Model,
    data: &mut Data,
    q: &[f64],
) -> Result<f64, DynamicsError> {
    let phi = constraint_residual(model, data, q)?;
    Ok(model
        .closures
        .iter()
        .map(|rc| closure_norm(model, rc, &phi))
        .fold(0.0, f64::max))
}
