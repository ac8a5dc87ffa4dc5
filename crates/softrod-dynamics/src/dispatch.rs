//! The top floor: the public forward dynamics, the one algorithm whose path
//! depends on every floor below — the chain or tree recursion of
//! `crate::algorithms` for an open model, the constrained solve of
//! `crate::constraints` (multipliers on top of the tree's) for a model with
//! loop closures.

use crate::algorithms::{check_forward_inputs, check_qdd, forward_dynamics_open};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::DVector;

/// Forward dynamics by the O(N) articulated recursion (docs/theory.md §6,
/// (D23)–(D27); §9 lists what it corrects in the model document): `q̈`
/// (n_dof) at `(q, q̇, t)` under actuator force `τ_act` (n_dof, `None` = 0)
/// and the forces `forces` selects ([`forward_dynamics`]: all of them).
///
/// Pass 1 (outward): `g, η`, the per-piece integrals (D20) and bias sums
/// (D23). Pass 2 (inward): articulated inertia and bias (D24–D26), one
/// `k_n×k_n` Cholesky per piece. Pass 3 (outward): `q̈_n` and `η̇(L_n)`
/// (D27). Cost O(N·n_g). On a tree the same recursion node by node (D56);
/// with loop closures the Baumgarte-stabilized constrained `q̈` (D67–D68,
/// multipliers in [`crate::closure_multipliers`]; contact forces, CT16,
/// enter the open tree's before the projection). Prescribed joints move
/// as prescribed at `t`. Result in `data.qdd`.
///
/// Fails if `D̂_n` is not positive definite (a degenerate basis or inertia)
/// or `q̈` is not finite.
pub fn forward_dynamics_with<'a>(
    model: &Model,
    data: &'a mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a DVector<f64>, DynamicsError> {
    check_forward_inputs(model, forces, q, qd, tau_act)?;
    match (&model.tree, model.has_closures()) {
        (Some(_), true) => {
            model.set_time(data, t);
            crate::constraints::forward::forward_dynamics(model, data, forces, t, q, qd, tau_act)?;
        }
        _ => forward_dynamics_open(model, data, forces, t, q, qd, tau_act)?,
    }
    check_qdd(data, t)
}

/// [`forward_dynamics_with`] of every force of the model ([`Forces::ALL`]).
pub fn forward_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a DVector<f64>, DynamicsError> {
    forward_dynamics_with(model, data, Forces::ALL, t, q, qd, tau_act)
}
