//! The top floor: the public forward dynamics and its linearization, whose
//! paths depend on every floor below — the chain or tree recursion of
//! `crate::algorithms` and the derivatives of `crate::derivatives` for an
//! open model, the constrained solve and derivatives of
//! `crate::constraints` (multipliers on top of the tree's) for a model
//! with loop closures.

use crate::algorithms::{check_forward_inputs, check_qdd, forward_dynamics_open};
use crate::constraints::derivatives::closed_input_response;
use crate::constraints::{ClosedDerivatives, closed_dynamics_derivatives};
use crate::derivatives::forward::{assemble_linearization, fill_actuation};
use crate::derivatives::{FdDerivatives, Linearization, forward_dynamics_derivatives};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector};

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

/// Linearizes `ẋ = f(x, u)`, `x = (q, q̇)`, about `(q, q̇)` at time `t`
/// under `τ_act` (`None` = 0), with `u` the cable tensions (their operating
/// values are the tension schedules at `t`, or the inputs set by
/// [`Data::set_cable_tensions`]):
/// `ẋ ≈ f(x₀, u₀) + A (x − x₀) + B (u − u₀)` with `A`, `B` of
/// [`Linearization`] (D49). What model-based control (LQR, MPC,
/// trajectory optimization) needs. Allocates the outputs (A: 2n × 2n,
/// B: 2n × n_u); the heavy work is in `work`.
///
/// Open models: from [`forward_dynamics_derivatives`] (D48). Closed
/// models (loop closures): `f` is the constrained, Baumgarte-stabilized
/// forward dynamics [`forward_dynamics`] integrates (docs/theory.md
/// D67–D68), in the model's own coordinates `x = (q, q̇)` (2·n_dof, the
/// tree's coordinates, not a minimal set): `∂q̈/∂q`, `∂q̈/∂q̇` from
/// [`closed_dynamics_derivatives`] (CD1–CD4) and `∂q̈/∂u = P M⁻¹ λA`
/// with `P` the projection of (CD4) at `h = 0`. On the constraint
/// manifold's tangent (`J δq = 0`, `J δq̇ = 0` with the drives still) `A`
/// is the constrained motion's linearization; off it, each independent
/// row contributes the stabilization's double eigenvalue `−α`
/// ([`Model::baumgarte_rate`]): `J δq̈ = −2α J δq̇ − α² J δq`
/// (docs/theory-derivatives.md CD9). The closed path allocates its
/// workspace ([`ClosedDerivatives`]) per call.
pub fn linearize(
    model: &Model,
    data: &mut Data,
    work: &mut FdDerivatives,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<Linearization, DynamicsError> {
    if !model.has_closures() {
        forward_dynamics_derivatives(model, data, work, t, q, qd, tau_act)?;
        return Ok(assemble_linearization(
            model,
            data,
            t,
            qd,
            (&work.dqdd_dq, &work.dqdd_dqd, &work.dqdd_du),
            &work.qdd,
        ));
    }
    let mut closed = ClosedDerivatives::new(model);
    closed_dynamics_derivatives(model, data, &mut closed, t, q, qd, tau_act)?;
    let mut du = DMatrix::zeros(model.n_dof(), model.n_cables());
    fill_actuation(model, q, Forces::ALL.load_scale, &mut du)?;
    closed_input_response(model, data, &mut closed, &mut du);
    if let Some((i, v)) = du.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!("closed dqdd/du entry {i} at t = {t}"),
            value: *v,
        });
    }
    Ok(assemble_linearization(
        model,
        data,
        t,
        qd,
        (&closed.dqdd_dq, &closed.dqdd_dqd, &du),
        &closed.qdd,
    ))
}
