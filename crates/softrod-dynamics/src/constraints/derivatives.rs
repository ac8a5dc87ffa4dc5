//! Derivatives of the constrained forward dynamics of a closed model
//! (docs/theory-derivatives.md §8, (CD1)–(CD4)): the analytic
//! inverse-dynamics derivatives of the open tree at the constrained `q̈`,
//! the closure force `Jᵀλ` and the stabilized rows differentiated at fixed
//! `λ` and `q̈` (central differences of the rows only: one kinematic sweep
//! over the nodes below the perturbed coordinate per difference), and one
//! projection through the multiplier system the forward solve factored.

use super::forward::{forward_dynamics as constrained_forward, kept_solve};
use super::queries::check_workspace;
use super::rows::{assemble, prescribed_columns};
use crate::algorithms::shifted::tree_solve;
use crate::algorithms::tree::outward_from;
use crate::algorithms::{Motion, Pass, check_forward_inputs, check_qdd, check_vec};
use crate::derivatives::{IdDerivatives, open_tree_id_derivatives};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::{ClosureWork, ConstraintRows, Data, SolveNode};
use crate::model::tree::Tree;
use nalgebra::{DMatrix, DVector};

/// Relative step of the central differences of the closure rows in `q`
/// (≈ ε^{1/3}: truncation and rounding errors balance near 1e-11
/// relative).
const ROW_STEP: f64 = 6e-6;

/// Relative step of the differences in `q̇` (exact for the quadratic rows).
const RATE_STEP: f64 = 0.1;

/// Workspace and results of [`closed_dynamics_derivatives`], allocated
/// once for a closed model by [`ClosedDerivatives::new`] (three
/// `n_dof × n_dof` matrices, the inverse-dynamics derivative buffers and
/// a few `m × n_dof` rows, `m` = [`Model::n_constraints`]); evaluations
/// allocate nothing.
#[derive(Clone, Debug)]
pub struct ClosedDerivatives {
    /// The open tree's inverse-dynamics derivatives at `(q, q̇, q̈)`, `q̈`
    /// the constrained acceleration (the closure forces left out).
    pub id: IdDerivatives,
    /// `∂q̈/∂q` of the constrained, Baumgarte-stabilized `q̈` (n_dof ×
    /// n_dof) [1/s²].
    pub dqdd_dq: DMatrix<f64>,
    /// `∂q̈/∂q̇` (n_dof × n_dof) [1/s].
    pub dqdd_dqd: DMatrix<f64>,
    /// `q̈` at the point of evaluation (n_dof).
    pub qdd: DVector<f64>,
    /// The multipliers `λ` there (m; zero on redundant rows).
    pub lambda: DVector<f64>,
    /// `∂(Jᵀλ)/∂q` at fixed `λ` (n × n), then the columns `M⁻¹g`.
    force_dq: DMatrix<f64>,
    /// `∂R/∂q`, `∂R/∂q̇` of the stabilized rows (CD1) at fixed `q̈` (m × n).
    rows_dq: DMatrix<f64>,
    rows_dqd: DMatrix<f64>,
    /// Rows at a perturbed state, and `J_p` there.
    rows: ConstraintRows,
    jac_p: DMatrix<f64>,
    /// Perturbed coordinates and rates; the values of (CD1) at `±h`
    /// (`Jᵀλ` then `R`).
    qx: DVector<f64>,
    qdx: DVector<f64>,
    plus: DVector<f64>,
    minus: DVector<f64>,
    /// Coordinates in descending order of their node (the sweeps of the
    /// differences then start at the node below the perturbed coordinate).
    order: Vec<(usize, usize)>,
    solve: Vec<SolveNode>,
    /// One right side of the multiplier system (m).
    z: DVector<f64>,
    /// `∂(Jᵀλ)/∂p` at fixed `λ` (n_dof × n_p) by the prescribed
    /// coordinates `p` (docs/theory-control.md G28), from
    /// [`closed_prescribed_derivatives`].
    pub force_dp: DMatrix<f64>,
    /// `∂R/∂p` of the stabilized rows (CD1) at fixed `q̈` (m × n_p; G28),
    /// from [`closed_prescribed_derivatives`].
    pub rows_dp: DMatrix<f64>,
    /// `∂R/∂ṗ` (m × n_p; G28).
    pub rows_dpd: DMatrix<f64>,
    /// `∂R/∂p̈` (m × n_p; G28): the rows' columns `J_p`.
    pub rows_dpdd: DMatrix<f64>,
    /// The prescribed coordinates with the node that holds each.
    pres_order: Vec<(usize, usize)>,
}

/// The free coordinates `(node, j)` of `tree`, deepest nodes first: a
/// kinematic sweep from each coordinate's node in this order leaves the
/// nodes before it at the unperturbed `q` (the differences of CD3).
pub(crate) fn coordinate_order(tree: &Tree) -> Vec<(usize, usize)> {
    let mut order = Vec::new();
    for (i, node) in tree.nodes.iter().enumerate() {
        if node.prescribed.is_none() {
            order.extend((node.dof..node.dof + node.k).map(|j| (i, j)));
        }
    }
    order.sort_by(|a, b| b.cmp(a));
    order
}

impl ClosedDerivatives {
    /// Allocates the buffers for `model` (a model with closures; for an open
    /// one the buffers are empty and [`closed_dynamics_derivatives`]
    /// refuses it).
    pub fn new(model: &Model) -> Self {
        let n = model.n_dof();
        let m = model.n_constraints();
        let np = model.n_prescribed();
        let order = model.tree.as_ref().map_or_else(Vec::new, coordinate_order);
        let mut pres_order = Vec::new();
        if let Some(tree) = &model.tree {
            for (i, node) in tree.nodes.iter().enumerate() {
                if let Some((o, kp)) = node.prescribed {
                    pres_order.extend((o..o + kp).map(|k| (i, k)));
                }
            }
        }
        Self {
            id: IdDerivatives::new(model),
            dqdd_dq: DMatrix::zeros(n, n),
            dqdd_dqd: DMatrix::zeros(n, n),
            qdd: DVector::zeros(n),
            lambda: DVector::zeros(m),
            force_dq: DMatrix::zeros(n, n),
            rows_dq: DMatrix::zeros(m, n),
            rows_dqd: DMatrix::zeros(m, n),
            rows: ConstraintRows::new(m, n),
            jac_p: DMatrix::zeros(m, np),
            qx: DVector::zeros(n),
            qdx: DVector::zeros(n),
            plus: DVector::zeros(n + m),
            minus: DVector::zeros(n + m),
            order,
            solve: vec![SolveNode::default(); model.tree.as_ref().map_or(0, |t| t.nodes.len())],
            z: DVector::zeros(m),
            force_dp: DMatrix::zeros(n, np),
            rows_dp: DMatrix::zeros(m, np),
            rows_dpd: DMatrix::zeros(m, np),
            rows_dpdd: DMatrix::zeros(m, np),
            pres_order,
        }
    }
}

/// The stabilized rows (CD1) at the state of the last kinematic sweep:
/// `R = J q̈ + J̇q̇ + 2α(J q̇ + J_p q̇_p) + α²φ` into `out[n..]` and, with
/// `force`, `Jᵀλ` into `out[..n]` (`q̈`, `λ` fixed).
#[allow(clippy::too_many_arguments)]
fn rows_at(
    model: &Model,
    tree: &Tree,
    data: &Data,
    w: &mut ClosedDerivatives,
    qdd: &DVector<f64>,
    plus: bool,
    force: bool,
) {
    let n = model.n_dof();
    let rate = model.baumgarte;
    let motion = Motion::new(w.qx.as_slice(), Some(w.qdx.as_slice()), None);
    assemble(model, tree, data, motion, false, &mut w.rows);
    let out = if plus { &mut w.plus } else { &mut w.minus };
    let mut r = out.rows_mut(n, model.n_constraints());
    r.copy_from(&w.rows.jdot_qd);
    r.axpy(rate * rate, &w.rows.phi, 1.0);
    r.gemv(1.0, &w.rows.jac, qdd, 1.0);
    r.gemv(2.0 * rate, &w.rows.jac, &w.qdx, 1.0);
    if model.n_prescribed() > 0 {
        prescribed_columns(model, tree, data, motion, &mut w.jac_p);
        r.gemv(2.0 * rate, &w.jac_p, &data.prescribed_qd, 1.0);
    }
    if force {
        out.rows_mut(0, n).gemv_tr(1.0, &w.rows.jac, &w.lambda, 0.0);
    }
}

/// Exact derivatives `∂q̈/∂q`, `∂q̈/∂q̇` of the constrained forward dynamics
/// of a closed model (docs/theory-derivatives.md (CD1)–(CD4)) at time `t`:
/// with `M q̈ = τ_act − b + Jᵀλ`, `J q̈ = −J̇q̇ − 2α(J q̇ + J_p q̇_p) − α²φ`
/// (docs/theory.md D67–D68) on the rows the forward solve keeps
/// (redundant rows carry `λ = 0` there and here),
/// `δq̈ = X + Y A⁻¹(h − J X)` with `X = M⁻¹(−∂ID/∂p + ∂(Jᵀλ)/∂p)`,
/// `h = −∂R/∂p`, `Y = M⁻¹Jᵀ`, `A = J M⁻¹ Jᵀ` for `p = q` and `p = q̇`.
///
/// `∂ID/∂p` is analytic (the open tree's, at the constrained `q̈`);
/// `∂(Jᵀλ)/∂q` and `∂R/∂p` are central differences of the closure rows
/// alone (kinematics, no dynamics: `2n` sweeps over the nodes below each
/// coordinate for `q`, exact for the quadratic `q̇` dependence), to about
/// 1e-10 relative. `M⁻¹` is the O(N) articulated solve the forward
/// dynamics factored. Results in `work` (`qdd`, `lambda` too); `data`
/// holds the constrained forward dynamics at `(t, q, q̇)` afterwards. No
/// allocation. Every force at full scale ([`Forces::ALL`]).
///
/// With contact, `ID` is the open tree's less the contact force `τ_c` of
/// the contact state `data` holds (its analytic derivatives, CT6,
/// CT12–CT14, enter `∂ID/∂p`; docs/theory-contact.md CT16).
///
/// Errors: a model without closures
/// ([`DynamicsError::UnsupportedClosed`]), a workspace of another model,
/// bad inputs, a non-finite result.
pub fn closed_dynamics_derivatives<'a>(
    model: &Model,
    data: &mut Data,
    work: &'a mut ClosedDerivatives,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a ClosedDerivatives, DynamicsError> {
    let forces = Forces::ALL;
    let tree = closed_start(
        model,
        data,
        work,
        (t, q, qd, tau_act),
        "closed_dynamics_derivatives of an open model (use forward_dynamics_derivatives)",
    )?;
    let (n, m) = (model.n_dof(), model.n_constraints());
    work.id.copy_inputs(data);
    if let (Some(from), Some(to)) = (&data.contact, &mut work.id.contact) {
        // The contact state of the run (anchors, raised stiffness), not a
        // fresh one: the open tree's derivatives then carry the contact
        // force's (CT6, CT12–CT14; CT16).
        if let Some(w) = &mut to.contact {
            w.copy_friction_state(from);
        }
    }
    open_tree_id_derivatives(model, &mut work.id, forces, t, q, qd, work.qdd.as_slice())?;

    // (CD3) Differences of the rows: q first (Jᵀλ and R), then q̇ (R only).
    // The factorization of M in `data` survives the kinematic sweeps
    // (they rewrite poses, twists and per-node sums the solve does not
    // read, and the last sweep restores the poses at q).
    let qdd = std::mem::take(&mut work.qdd);
    work.qx.copy_from_slice(q);
    work.qdx.copy_from_slice(qd);
    let sweep = |data: &mut Data, w: &ClosedDerivatives, from: usize| {
        let motion = Motion::new(w.qx.as_slice(), Some(w.qdx.as_slice()), None);
        outward_from(model, tree, data, motion, Pass::Kinematic, forces, from);
    };
    sweep(data, work, 0);
    for k in 0..work.order.len() {
        let (node, j) = work.order[k];
        let h = ROW_STEP * q[j].abs().max(1.0);
        for (plus, x) in [(true, q[j] + h), (false, q[j] - h)] {
            work.qx[j] = x;
            sweep(data, work, node);
            rows_at(model, tree, data, work, &qdd, plus, true);
        }
        work.qx[j] = q[j];
        let inv = 0.5 / h;
        for i in 0..n {
            work.force_dq[(i, j)] = (work.plus[i] - work.minus[i]) * inv;
        }
        for i in 0..m {
            work.rows_dq[(i, j)] = (work.plus[n + i] - work.minus[n + i]) * inv;
        }
    }
    sweep(data, work, 0);
    for k in 0..work.order.len() {
        let (node, j) = work.order[k];
        // R is quadratic in q̇ (J̇q̇) plus linear: a central difference is
        // exact at any step, and a long one keeps the rounding small.
        let h = RATE_STEP * qd[j].abs().max(1.0);
        for (plus, x) in [(true, qd[j] + h), (false, qd[j] - h)] {
            work.qdx[j] = x;
            sweep(data, work, node);
            rows_at(model, tree, data, work, &qdd, plus, false);
        }
        work.qdx[j] = qd[j];
        let inv = 0.5 / h;
        for i in 0..m {
            work.rows_dqd[(i, j)] = (work.plus[n + i] - work.minus[n + i]) * inv;
        }
    }
    sweep(data, work, 0);
    work.qdd = qdd;

    // (CD2) g = −∂ID/∂p + ∂(Jᵀλ)/∂p, X = M⁻¹g column by column.
    let w = &mut *work;
    w.dqdd_dq.copy_from(&w.force_dq);
    w.dqdd_dq -= &w.id.dtau_dq;
    w.dqdd_dqd.copy_from(&w.id.dtau_dqd);
    w.dqdd_dqd.neg_mut();
    for x in [&mut w.dqdd_dq, &mut w.dqdd_dqd] {
        for col in x.as_mut_slice().chunks_exact_mut(n.max(1)) {
            tree_solve(tree, data, &mut w.solve, col);
        }
    }
    // (CD4) δq̈ = X + Y A⁻¹(h − J X), h = −∂R/∂p, on the kept rows.
    let Some(cw) = data.closure.as_ref() else {
        unreachable!("check_workspace found the closure buffers")
    };
    project(cw, &mut w.dqdd_dq, Some(&w.rows_dq), &mut w.z);
    project(cw, &mut w.dqdd_dqd, Some(&w.rows_dqd), &mut w.z);
    for (what, x) in [("dqdd/dq", &w.dqdd_dq), ("dqdd/dqdot", &w.dqdd_dqd)] {
        if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("closed {what} entry ({}, {}) at t = {t}", i % n, i / n),
                value: *v,
            });
        }
    }
    Ok(work)
}

/// The start of [`closed_dynamics_derivatives`] and
/// [`closed_prescribed_derivatives`]: checks the model (closed; `open`
/// names the call in the error otherwise), the workspace and the inputs,
/// runs the constrained forward dynamics at `(t, q, q̇)` and keeps its
/// `q̈`, `λ` in `work`. Returns the model's tree.
fn closed_start<'m>(
    model: &'m Model,
    data: &mut Data,
    work: &mut ClosedDerivatives,
    (t, q, qd, tau_act): (f64, &[f64], &[f64], Option<&[f64]>),
    open: &'static str,
) -> Result<&'m Tree, DynamicsError> {
    let forces = Forces::ALL;
    let (Some(tree), true) = (&model.tree, model.has_closures()) else {
        return Err(DynamicsError::UnsupportedClosed { what: open });
    };
    let (n, m, np) = (model.n_dof(), model.n_constraints(), model.n_prescribed());
    if work.qdd.len() != n
        || work.lambda.len() != m
        || work.solve.len() != tree.nodes.len()
        || work.force_dp.ncols() != np
    {
        return Err(DynamicsError::WorkspaceMismatch {
            what: "ClosedDerivatives",
            built: work.qdd.len(),
            got: n,
        });
    }
    check_workspace(model, data)?;
    check_forward_inputs(model, forces, q, qd, tau_act)?;
    model.set_time(data, t);
    constrained_forward(model, data, forces, t, q, qd, tau_act)?;
    work.qdd.copy_from(check_qdd(data, t)?);
    let Some(cw) = data.closure.as_ref() else {
        unreachable!("check_workspace found the closure buffers")
    };
    work.lambda.copy_from(&cw.lambda);
    Ok(tree)
}

/// (CD4) in place on the columns of `x` (each `X_j = M⁻¹ g_j`):
/// `x_j ← X_j + Y A⁻¹(h_j − J X_j)`, `h_j = −(∂R/∂p)_j` (`dr`; `None`:
/// `h = 0`, the response to a generalized force), with `Y = M⁻¹Jᵀ`, `J`
/// and the pivoted Cholesky of `A = J M⁻¹ Jᵀ` the constrained forward
/// dynamics left in `cw` (its kept rows; redundant ones get `λ = 0`).
// Triangular solves read clearest with explicit indices.
#[allow(clippy::needless_range_loop)]
fn project(
    cw: &ClosureWork,
    x: &mut DMatrix<f64>,
    dr: Option<&DMatrix<f64>>,
    z: &mut DVector<f64>,
) {
    let (n, m, r) = (x.nrows(), z.len(), cw.rank);
    for j in 0..x.ncols() {
        // s = h − J X_j, permuted to the pivot order.
        for i in 0..m {
            let p = cw.perm[i];
            let mut s = dr.map_or(0.0, |d| -d[(p, j)]);
            for c in 0..n {
                s -= cw.rows.jac[(p, c)] * x[(c, j)];
            }
            z[i] = s;
        }
        // L L^T z = s on the first r (kept) rows.
        kept_solve(&cw.a, r, z.as_mut_slice());
        for i in 0..r {
            let p = cw.perm[i];
            let zi = z[i];
            for c in 0..n {
                x[(c, j)] += cw.y[(c, p)] * zi;
            }
        }
    }
}

/// `∂q̈/∂u` of the constrained forward dynamics (CD4 with `h = 0`): the
/// cables' generalized forces `λA(q)` (`x`, n_dof × n_u, overwritten)
/// through `M⁻¹` and the projection on the closures' rows. Call right
/// after [`closed_dynamics_derivatives`] at the same state (its
/// factorizations are in `data`).
pub(crate) fn closed_input_response(
    model: &Model,
    data: &mut Data,
    work: &mut ClosedDerivatives,
    x: &mut DMatrix<f64>,
) {
    let Some(tree) = &model.tree else {
        unreachable!("closures live on the tree")
    };
    let n = model.n_dof();
    for col in x.as_mut_slice().chunks_exact_mut(n.max(1)) {
        tree_solve(tree, data, &mut work.solve, col);
    }
    let Some(cw) = data.closure.as_ref() else {
        unreachable!("the constrained forward dynamics ran")
    };
    project(cw, x, None, &mut work.z);
}

/// `x ← P M⁻¹ x` column by column: the constrained acceleration's response
/// to generalized forces `x` (n_dof × k) at `(t, q, q̇)` of a closed model
/// (docs/theory-control.md G22; CD3 with `h = 0`):
/// `P M⁻¹ = M⁻¹ − Y A⁻¹ J M⁻¹`, `Y = M⁻¹Jᵀ`, `A = J M⁻¹ Jᵀ` on the rows the
/// forward solve keeps (its pivoted Cholesky of `A`: redundant rows carry
/// no multiplier here either). `P M⁻¹` is symmetric, so the same call gives
/// the transposed products `wᵀ P M⁻¹` of an adjoint. Runs the constrained
/// forward dynamics at `(t, q, q̇)` first (its factorizations of `M` and
/// `A` are what is applied; `M`, `J` and the pivots depend on `q` alone),
/// then `k` O(N) solves and `O(k·m·n)` for the projection. `data` holds
/// that forward dynamics afterwards; no allocation.
///
/// Errors: a model without closures, a workspace of another model, bad
/// inputs, `x` without `n_dof` rows, a non-finite result.
#[allow(clippy::too_many_arguments)]
pub fn closed_force_response(
    model: &Model,
    data: &mut Data,
    work: &mut ClosedDerivatives,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
    x: &mut DMatrix<f64>,
) -> Result<(), DynamicsError> {
    let forces = Forces::ALL;
    if model.tree.is_none() || !model.has_closures() {
        return Err(DynamicsError::UnsupportedClosed {
            what: "closed_force_response of an open model (use the mass matrix's solve)",
        });
    }
    let n = model.n_dof();
    if work.qdd.len() != n || x.nrows() != n {
        return Err(DynamicsError::WorkspaceMismatch {
            what: "closed_force_response",
            built: work.qdd.len(),
            got: if x.nrows() != n { x.nrows() } else { n },
        });
    }
    check_workspace(model, data)?;
    check_forward_inputs(model, forces, q, qd, tau_act)?;
    model.set_time(data, t);
    constrained_forward(model, data, forces, t, q, qd, tau_act)?;
    closed_input_response(model, data, work, x);
    if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!(
                "closed force response entry ({}, {}) at t = {t}",
                i % n,
                i / n
            ),
            value: *v,
        });
    }
    Ok(())
}

/// The inverse dynamics of a closed model's open tree (the closure forces
/// `Jᵀλ` left out): `ID(q, q̇, q̈)` of (CD1), whose derivatives in the
/// model's parameters give the constrained acceleration's through
/// [`closed_force_response`] (docs/theory-control.md G22). For an open model
/// the same as `inverse_dynamics`. Result in `data.tau`; no allocation.
pub fn open_tree_inverse_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    check_vec(model, "qddot", qdd)?;
    crate::algorithms::inverse_dynamics_open(
        model,
        data,
        Forces::ALL,
        t,
        Motion::new(q, Some(qd), Some(qdd)),
    );
    Ok(&data.tau)
}

/// The closure terms' derivatives by the prescribed coordinates `p` of a
/// closed model with prescribed joints (docs/theory-control.md G28):
/// `∂(Jᵀλ)/∂p` at fixed `λ` into `work.force_dp`, and `∂R/∂p`, `∂R/∂ṗ`,
/// `∂R/∂p̈` of the stabilized rows (CD1) at fixed `q̈` into
/// `work.rows_dp`, `rows_dpd`, `rows_dpdd`, at `(t, q, q̇)` with `q̈`, `λ`
/// the constrained forward dynamics' (run here first; `data` holds it
/// afterwards, its factorizations of `M` and `A` intact for
/// [`closed_row_response`] and [`closed_row_response_transposed`]).
///
/// As (CD4) in `q`: central differences of the closure rows alone, the
/// prescribed values moved in `data` (one kinematic sweep from the node
/// that holds the coordinate per difference), steps `6e-6 max(1, |p_k|)`
/// in `p` and `0.1 max(1, |ṗ_k|)`, `0.1 max(1, |p̈_k|)` in the rate and
/// acceleration, where `R` is quadratic and linear (exact but for
/// rounding). No allocation.
///
/// Errors: a model without closures, a workspace of another model, bad
/// inputs, a non-finite result.
#[allow(clippy::too_many_arguments)]
pub fn closed_prescribed_derivatives(
    model: &Model,
    data: &mut Data,
    work: &mut ClosedDerivatives,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    let forces = Forces::ALL;
    let tree = closed_start(
        model,
        data,
        work,
        (t, q, qd, tau_act),
        "closed_prescribed_derivatives of an open model",
    )?;
    let (n, m) = (model.n_dof(), model.n_constraints());
    let qdd = std::mem::take(&mut work.qdd);
    work.qx.copy_from_slice(q);
    work.qdx.copy_from_slice(qd);
    let sweep = |data: &mut Data, w: &ClosedDerivatives, from: usize| {
        let motion = Motion::new(w.qx.as_slice(), Some(w.qdx.as_slice()), None);
        outward_from(model, tree, data, motion, Pass::Kinematic, forces, from);
    };
    // Which of the prescribed value, rate, acceleration a difference moves.
    #[derive(Clone, Copy, PartialEq)]
    enum Which {
        Value,
        Rate,
        Acc,
    }
    for which in [Which::Value, Which::Rate, Which::Acc] {
        for idx in 0..work.pres_order.len() {
            let (node, k) = work.pres_order[idx];
            let slot = match which {
                Which::Value => &mut data.prescribed_q,
                Which::Rate => &mut data.prescribed_qd,
                Which::Acc => &mut data.prescribed_qdd,
            };
            let x0 = slot[k];
            let h = if which == Which::Value {
                ROW_STEP
            } else {
                RATE_STEP
            } * x0.abs().max(1.0);
            for (plus, x) in [(true, x0 + h), (false, x0 - h)] {
                match which {
                    Which::Value => data.prescribed_q[k] = x,
                    Which::Rate => data.prescribed_qd[k] = x,
                    Which::Acc => data.prescribed_qdd[k] = x,
                }
                sweep(data, work, node);
                rows_at(model, tree, data, work, &qdd, plus, which == Which::Value);
            }
            match which {
                Which::Value => data.prescribed_q[k] = x0,
                Which::Rate => data.prescribed_qd[k] = x0,
                Which::Acc => data.prescribed_qdd[k] = x0,
            }
            let inv = 0.5 / h;
            let rows = match which {
                Which::Value => &mut work.rows_dp,
                Which::Rate => &mut work.rows_dpd,
                Which::Acc => &mut work.rows_dpdd,
            };
            for i in 0..m {
                rows[(i, k)] = (work.plus[n + i] - work.minus[n + i]) * inv;
            }
            if which == Which::Value {
                for i in 0..n {
                    work.force_dp[(i, k)] = (work.plus[i] - work.minus[i]) * inv;
                }
            }
        }
    }
    sweep(data, work, 0);
    work.qdd = qdd;
    for (what, x) in [
        ("d(J^T lambda)/dp", &work.force_dp),
        ("dR/dp", &work.rows_dp),
        ("dR/dpdot", &work.rows_dpd),
        ("dR/dpddot", &work.rows_dpdd),
    ] {
        if let Some((i, v)) = x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            let r = x.nrows().max(1);
            return Err(DynamicsError::NotFinite {
                what: format!("closed {what} entry ({}, {}) at t = {t}", i % r, i / r),
                value: *v,
            });
        }
    }
    Ok(())
}

/// The closure rows' state in `data` after a constrained forward dynamics,
/// checked against a row vector of `m` and a coordinate vector of `n`
/// entries; errors name `what`.
fn row_response_work<'a>(
    data: &'a Data,
    work: &ClosedDerivatives,
    m: usize,
    n: usize,
    what: &'static str,
) -> Result<&'a ClosureWork, DynamicsError> {
    let cw = data
        .closure
        .as_ref()
        .ok_or(DynamicsError::UnsupportedClosed {
            what: "a closed row response without a constrained forward dynamics",
        })?;
    if m != work.z.len() || n != cw.y.nrows() {
        return Err(DynamicsError::WorkspaceMismatch {
            what,
            built: work.z.len(),
            got: m,
        });
    }
    Ok(cw)
}

/// `out += Y A⁻¹ h`: the constrained acceleration's response to a change
/// `h` (m) of the stabilized rows' right side (CD3–CD4 with `g = 0`,
/// `δq̈ = Y A⁻¹ h`; docs/theory-control.md G28), on the rows the forward
/// solve kept (redundant rows take no part), with the factorizations the
/// last constrained forward dynamics left in `data` (call after
/// [`closed_prescribed_derivatives`] or [`closed_force_response`] at the
/// state). No allocation.
pub fn closed_row_response(
    data: &Data,
    work: &mut ClosedDerivatives,
    h: &DVector<f64>,
    out: &mut DVector<f64>,
) -> Result<(), DynamicsError> {
    let cw = row_response_work(data, work, h.len(), out.len(), "closed_row_response")?;
    let (m, r) = (h.len(), cw.rank);
    for i in 0..m {
        work.z[i] = h[cw.perm[i]];
    }
    kept_solve(&cw.a, r, work.z.as_mut_slice());
    for i in 0..r {
        let zi = work.z[i];
        let p = cw.perm[i];
        for c in 0..out.len() {
            out[c] += cw.y[(c, p)] * zi;
        }
    }
    Ok(())
}

/// `ν = A⁻¹ Yᵀ w` (m; zero on redundant rows): the transposed product of
/// [`closed_row_response`], `wᵀ Y A⁻¹ h = νᵀ h` for every `h`
/// (docs/theory-control.md G28). Same preconditions; no allocation.
pub fn closed_row_response_transposed(
    data: &Data,
    work: &mut ClosedDerivatives,
    w: &DVector<f64>,
    nu: &mut DVector<f64>,
) -> Result<(), DynamicsError> {
    let cw = row_response_work(
        data,
        work,
        nu.len(),
        w.len(),
        "closed_row_response_transposed",
    )?;
    let (m, r) = (nu.len(), cw.rank);
    for i in 0..m {
        let p = cw.perm[i];
        work.z[i] = (0..w.len()).map(|c| cw.y[(c, p)] * w[c]).sum();
    }
    kept_solve(&cw.a, r, work.z.as_mut_slice());
    nu.fill(0.0);
    for i in 0..r {
        nu[cw.perm[i]] = work.z[i];
    }
    Ok(())
}
