//! Derivatives of the forward dynamics and the linearization of
//! `ẋ = f(x, u)`, from the analytic inverse-dynamics derivatives
//! (docs/theory-derivatives.md §5, (D48)–(D49)).

use super::{IdDerivatives, inverse_dynamics_derivatives_with};
use crate::algorithms::shifted::ShiftedSolver;
use crate::algorithms::{check_forward_inputs, check_qdd, check_vec, forward_dynamics_open};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector};

/// `∂q̈/∂q` and `∂q̈/∂q̇` (n_dof × n_dof each), the Jacobians the stiff
/// integrators use.
#[derive(Clone, Debug)]
pub struct DynamicsJacobians {
    /// `∂q̈/∂q`.
    pub dqdd_dq: DMatrix<f64>,
    /// `∂q̈/∂q̇`.
    pub dqdd_dqd: DMatrix<f64>,
    /// The `q̈` they were taken at.
    pub qdd: DVector<f64>,
}

/// Workspace and results of [`forward_dynamics_derivatives`], allocated
/// once for a model by [`FdDerivatives::new`] (the three result matrices,
/// the inverse-dynamics derivative buffers and an O(N) factorization of
/// `M`); evaluations allocate nothing.
#[derive(Clone, Debug)]
pub struct FdDerivatives {
    /// The inverse-dynamics derivatives at `(q, q̇, q̈(q, q̇))`
    /// (`id.dtau_dq`, `id.dtau_dqd`), kept from the last evaluation.
    pub id: IdDerivatives,
    solver: ShiftedSolver,
    /// `∂q̈/∂q` (n_dof × n_dof): row `i`, column `j` is `∂q̈_i/∂q_j` [1/s²].
    pub dqdd_dq: DMatrix<f64>,
    /// `∂q̈/∂q̇` (n_dof × n_dof) [1/s].
    pub dqdd_dqd: DMatrix<f64>,
    /// `∂q̈/∂u` (n_dof × n_u): column `c` is the response to the tension of
    /// cable `c` (cables numbered rod by rod, in the order given; see
    /// [`crate::actuation_matrix`]) [per N].
    pub dqdd_du: DMatrix<f64>,
    /// The generalized force per unit tension of each cable, scaled by the
    /// load factor `λ` of the evaluation's [`Forces`]: `λ A(q)` (n_dof ×
    /// n_u), `A` of [`crate::actuation_matrix`]; `∂τ/∂u = −λ A(q)` for the
    /// inverse dynamics.
    pub actuation: DMatrix<f64>,
    /// `q̈` at the point of evaluation (n_dof).
    pub qdd: DVector<f64>,
}

impl FdDerivatives {
    /// Allocates the buffers for `model`.
    pub fn new(model: &Model) -> Self {
        let n = model.n_dof();
        let nu = model.n_cables();
        Self {
            id: IdDerivatives::new(model),
            solver: ShiftedSolver::new(model),
            dqdd_dq: DMatrix::zeros(n, n),
            dqdd_dqd: DMatrix::zeros(n, n),
            dqdd_du: DMatrix::zeros(n, nu),
            actuation: DMatrix::zeros(n, nu),
            qdd: DVector::zeros(n),
        }
    }
}

/// `x ← M⁻¹ x` for every column of `x` (n_dof rows), through the O(N)
/// factorization.
fn solve_columns(
    model: &Model,
    solver: &mut ShiftedSolver,
    x: &mut DMatrix<f64>,
) -> Result<(), DynamicsError> {
    let n = x.nrows();
    for col in x.as_mut_slice().chunks_exact_mut(n.max(1)) {
        solver.solve(model, col)?;
    }
    Ok(())
}

/// Derivatives of the forward dynamics `q̈ = FD(q, q̇, τ_act, u)` at time
/// `t`, from `ID(q, q̇, FD(q, q̇, …)) = τ_act` (D48):
///
/// - `∂q̈/∂q = −M⁻¹ ∂τ/∂q`, `∂q̈/∂q̇ = −M⁻¹ ∂τ/∂q̇` (the ID derivatives taken
///   at `q̈ = FD(q, q̇)`, [`crate::inverse_dynamics_derivatives`]);
/// - `∂q̈/∂u = M⁻¹ A(q)` for the cable tensions `u` (the generalized force
///   is linear in them, (D15)).
///
/// `M⁻¹` is applied column by column with the O(N) articulated solve
/// ([`ShiftedSolver`] with `a = b = 0`), so no `n_dof × n_dof` factor is
/// formed. `q`, `q̇`, `τ_act` (`None` = 0): dim `n_dof`. Results in `work`
/// (`dqdd_dq`, `dqdd_dqd`, `dqdd_du`, `qdd`, and the ID derivatives in
/// `work.id`); `data.qdd` also holds `q̈`. No allocation.
pub fn forward_dynamics_derivatives<'a>(
    model: &Model,
    data: &mut Data,
    work: &'a mut FdDerivatives,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a FdDerivatives, DynamicsError> {
    fd_derivatives(model, data, work, Forces::ALL, t, (q, qd), tau_act)
}

/// [`forward_dynamics_derivatives`] under `forces` (`∂q̈/∂u = M⁻¹ λA(q)`,
/// `λ` = [`Forces::load_scale`]); `(q, q̇)` as a pair.
fn fd_derivatives<'a>(
    model: &Model,
    data: &mut Data,
    work: &'a mut FdDerivatives,
    forces: Forces,
    t: f64,
    (q, qd): (&[f64], &[f64]),
    tau_act: Option<&[f64]>,
) -> Result<&'a FdDerivatives, DynamicsError> {
    if work.qdd.len() != model.n_dof() || work.actuation.ncols() != model.n_cables() {
        return Err(DynamicsError::WorkspaceMismatch {
            what: "FdDerivatives",
            built: work.qdd.len(),
            got: model.n_dof(),
        });
    }
    if model.has_closures() {
        return Err(DynamicsError::UnsupportedClosed {
            what: "forward_dynamics_derivatives (closed models: closed_dynamics_derivatives, or linearize)",
        });
    }
    check_forward_inputs(model, forces, q, qd, tau_act)?;
    forward_dynamics_open(model, data, forces, t, q, qd, tau_act)?;
    work.qdd.copy_from(check_qdd(data, t)?);
    work.id.copy_inputs(data);
    if let (Some(from), Some(to)) = (&data.contact, &mut work.id.contact) {
        // The friction state of the run, not a fresh one.
        if let Some(w) = &mut to.contact {
            w.copy_friction_state(from);
        }
    }
    inverse_dynamics_derivatives_with(model, &mut work.id, forces, t, q, qd, work.qdd.as_slice())?;
    work.solver.factor_at(model, t, q, 0.0, 0.0)?;
    work.dqdd_dq.copy_from(&work.id.dtau_dq);
    work.dqdd_dq.neg_mut();
    solve_columns(model, &mut work.solver, &mut work.dqdd_dq)?;
    work.dqdd_dqd.copy_from(&work.id.dtau_dqd);
    work.dqdd_dqd.neg_mut();
    solve_columns(model, &mut work.solver, &mut work.dqdd_dqd)?;
    fill_actuation(model, q, forces.load_scale, &mut work.actuation)?;
    work.dqdd_du.copy_from(&work.actuation);
    solve_columns(model, &mut work.solver, &mut work.dqdd_du)?;
    Ok(work)
}

/// `λ A(q)` into `out` (n_dof × n_cables) without allocating.
pub(crate) fn fill_actuation(
    model: &Model,
    q: &[f64],
    scale: f64,
    out: &mut DMatrix<f64>,
) -> Result<(), DynamicsError> {
    check_vec(model, "q", q)?;
    out.fill(0.0);
    let n = model.n_dof();
    let mut col = 0;
    for rm in model.rods() {
        let range = rm.dofs();
        for cable in &rm.spec.cables {
            let column = &mut out.as_mut_slice()[col * n..(col + 1) * n];
            cable.add_force_per_tension(
                &rm.spec.geometry,
                &q[range.clone()],
                &model.quadrature,
                &mut column[range.clone()],
            );
            for v in column.iter_mut() {
                *v *= scale;
            }
            col += 1;
        }
    }
    Ok(())
}

/// The linearization of the first-order system `ẋ = f(x, u)`,
/// `x = (q, q̇)`, `u` = the cable tensions, about one state (D49).
#[derive(Clone, Debug)]
pub struct Linearization {
    /// `A = ∂f/∂x = [[0, I], [∂q̈/∂q, ∂q̈/∂q̇]]` (2n × 2n, `n = n_dof`; rows
    /// and columns ordered `q_1 … q_n, q̇_1 … q̇_n`).
    pub a: DMatrix<f64>,
    /// `B = ∂f/∂u = [[0], [∂q̈/∂u]]` (2n × n_u; columns: cables rod by rod,
    /// in the order given, as [`crate::actuation_matrix`]) [per N].
    pub b: DMatrix<f64>,
    /// `f(x₀, u₀) = (q̇, q̈)` at the point (2n): zero at an equilibrium.
    pub xdot: DVector<f64>,
    /// The operating inputs `u₀`: each cable's tension at `t` \[N\].
    pub u: DVector<f64>,
}

/// The [`Linearization`] of the derivatives `∂q̈/∂q`, `∂q̈/∂q̇`, `∂q̈/∂u`
/// and `q̈` at `(t, q̇)` (D49), the operating tensions from `data`.
pub(crate) fn assemble_linearization(
    model: &Model,
    data: &Data,
    t: f64,
    qd: &[f64],
    (dqdd_dq, dqdd_dqd, dqdd_du): (&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>),
    qdd: &DVector<f64>,
) -> Linearization {
    let n = model.n_dof();
    let nu = model.n_cables();
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    a.view_mut((0, n), (n, n)).fill_with_identity();
    a.view_mut((n, 0), (n, n)).copy_from(dqdd_dq);
    a.view_mut((n, n), (n, n)).copy_from(dqdd_dqd);
    let mut b = DMatrix::zeros(2 * n, nu);
    b.view_mut((n, 0), (n, nu)).copy_from(dqdd_du);
    let mut xdot = DVector::zeros(2 * n);
    xdot.rows_mut(0, n).copy_from_slice(qd);
    xdot.rows_mut(n, n).copy_from(qdd);
    let u = DVector::from_iterator(
        nu,
        model
            .rods()
            .iter()
            .flat_map(|r| (0..r.spec.cables.len()).map(|c| data.tension(r, c, t))),
    );
    Linearization { a, b, xdot, u }
}

/// Jacobians of the forward dynamics at `(q, q̇, t)` under `τ_act`:
/// `∂q̈/∂q = −M⁻¹ ∂ID/∂q|_{q̈}` and `∂q̈/∂q̇ = −M⁻¹ ∂ID/∂q̇|_{q̈}` with the
/// analytic inverse-dynamics derivatives (every term: the elastic `K`,
/// viscous `D`, geometric, gyroscopic and centrifugal parts alike; D48).
///
/// Allocates its outputs and a workspace per call; for repeated
/// evaluations use [`forward_dynamics_derivatives`] with one
/// [`FdDerivatives`].
pub fn dynamics_jacobians(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<DynamicsJacobians, DynamicsError> {
    dynamics_jacobians_with(model, data, Forces::ALL, t, q, qd, tau_act)
}

/// [`dynamics_jacobians`] of the forward dynamics under `forces` (loads
/// and tensions scaled by [`Forces::load_scale`], drives moving or at
/// rest).
pub fn dynamics_jacobians_with(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<DynamicsJacobians, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    let mut work = FdDerivatives::new(model);
    fd_derivatives(model, data, &mut work, forces, t, (q, qd), tau_act)?;
    Ok(DynamicsJacobians {
        dqdd_dq: work.dqdd_dq,
        dqdd_dqd: work.dqdd_dqd,
        qdd: work.qdd,
    })
}
