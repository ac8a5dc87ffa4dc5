//! Floor 4, the derivatives: analytic `∂τ/∂q`, `∂τ/∂q̇` of the inverse
//! dynamics `τ = ID(q, q̇, q̈)` (docs/theory-derivatives.md §2–§4,
//! (D37)–(D47)) by one outward and one inward sweep plus a pairing of
//! per-piece quantities — the structure of the RNEA derivatives of rigid
//! chains, with each piece's own points differentiated through the strain
//! derivatives of its maps (D30)–(D36) — on a chain ([`chain`]) or a tree
//! ([`tree`], D76–D80); and what is built on them ([`forward`]): the
//! derivatives of the forward dynamics (D48) and the linearization of
//! `ẋ = f(x, u)` (D49). [`vjp`]: the same sweeps without the dense
//! matrices, and their O(N) products `uᵀ∂τ/∂(q, q̇)` and `∂τ/∂(q, q̇)·v`
//! (D81–D84).
//!
//! [`point`] linearizes one evaluation point, [`piece`] closes one piece.
//! A new force term adds its linearization (`crate::forces::linearized`)
//! where [`point::own_points`] and [`piece::write_piece`] add the present
//! ones; a new derivative of the equations of motion goes here.

pub(crate) mod chain;
pub(crate) mod contact;
pub(crate) mod forward;
pub(crate) mod pairs;
pub(crate) mod piece;
pub(crate) mod planar;
pub(crate) mod planar_close;
pub(crate) mod planar_products;
pub(crate) mod point;
pub(crate) mod second;
pub(crate) mod tree;
pub(crate) mod vjp;

pub use forward::{
    DynamicsJacobians, FdDerivatives, Linearization, dynamics_jacobians, dynamics_jacobians_with,
    forward_dynamics_derivatives,
};

use crate::algorithms::check_vec;
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::data::Data;
use crate::model::planar::PlanarRod;
use crate::model::{Model, RodModel};
use nalgebra::{DMatrix, DVector};
use piece::PieceWork;
pub use vjp::{
    inverse_dynamics_inertia_vjp, inverse_dynamics_jvp, inverse_dynamics_mass_product,
    inverse_dynamics_vjp,
};

/// Where the derivatives are taken: the time \[s\], the motion `(q, q̇, q̈)`
/// (dim n_dof each) and the forces of the evaluation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct At<'a> {
    pub t: f64,
    pub q: &'a [f64],
    pub qd: &'a [f64],
    pub qdd: &'a [f64],
    pub forces: Forces,
    /// Whether the dense `∂τ/∂q`, `∂τ/∂q̇` are formed (the off-diagonal
    /// pairings, O(N·n_dof)), or only what the O(N) products need (D81).
    pub dense: bool,
}

/// Workspace and results of [`inverse_dynamics_derivatives`]
/// (Pinocchio-style: allocated once for a model by [`IdDerivatives::new`],
/// every evaluation writes into it and allocates nothing).
#[derive(Clone, Debug)]
pub struct IdDerivatives {
    pub(crate) pieces: Vec<Vec<PieceWork>>,
    /// The per-piece buffers of the planar rods' sweeps (D107; empty for
    /// the other rods), and per rod whether the last evaluation took them
    /// (the products read the buffers it wrote).
    pub(crate) planar: Vec<Vec<planar::PlanarWork>>,
    pub(crate) planar_taken: Vec<bool>,
    /// `∂τ/∂q` (n_dof × n_dof): row `i`, column `j` is `∂τ_i/∂q_j` at fixed
    /// `q̇, q̈` [N·m or N per coordinate unit].
    pub dtau_dq: DMatrix<f64>,
    /// `∂τ/∂q̇` (n_dof × n_dof) at fixed `q, q̈`.
    pub dtau_dqd: DMatrix<f64>,
    /// `τ = ID(q, q̇, q̈)` itself (n_dof), as [`crate::inverse_dynamics`]
    /// returns it (to round-off).
    pub tau: DVector<f64>,
    /// Cable tensions replacing the schedules, as
    /// [`crate::Data::set_cable_tensions`] (copied from the `Data` by
    /// [`crate::forward_dynamics_derivatives`]).
    pub tensions: Option<DVector<f64>>,
    /// Joint actuator forces replacing their schedules, as
    /// [`crate::Data::set_joint_forces`] (they enter `tau` only: a force of
    /// time alone has no derivative in `q`, `q̇`).
    pub joint_inputs: Option<DVector<f64>>,
    n_dof: usize,
    /// The per-node buffers of an articulated model (D76–D80).
    tree: Option<Box<tree::TreeWork>>,
    /// The buffers and friction anchors of contact (models with contact
    /// only; [`crate::forward_dynamics_derivatives`] copies the anchors of
    /// its `Data` here).
    pub(crate) contact: Option<Box<Data>>,
    /// A linearization (dense or not) succeeded: the per-piece quantities
    /// of [`inverse_dynamics_vjp`] are those of the last evaluation.
    pub(crate) linearized: bool,
    /// That linearization was the one without the dense matrices: it kept
    /// the mass matrix's blocks too ([`inverse_dynamics_mass_product`]).
    pub(crate) mass_kept: bool,
}

impl IdDerivatives {
    /// Allocates the buffers and the two `n_dof × n_dof` results for `model`.
    pub fn new(model: &Model) -> Self {
        Self::with_dense(model, true)
    }

    /// The buffers of [`inverse_dynamics_linearization_with`] and
    /// [`inverse_dynamics_vjp`] alone: O(N) memory, no `n_dof × n_dof`
    /// matrices (`dtau_dq`, `dtau_dqd` are 0×0; the dense
    /// [`inverse_dynamics_derivatives_with`] refuses this workspace).
    pub fn for_products(model: &Model) -> Self {
        Self::with_dense(model, false)
    }

    /// Takes `data`'s joint force inputs ([`crate::Data::set_joint_forces`])
    /// into [`IdDerivatives::joint_inputs`], as the evaluations of `data`
    /// see them. No allocation once set.
    pub fn copy_joint_inputs(&mut self, data: &Data) {
        match (data.joint_forces(), &mut self.joint_inputs) {
            (None, f) => *f = None,
            (Some(u), Some(f)) if f.len() == u.len() => f.as_mut_slice().copy_from_slice(u),
            (Some(u), f) => *f = Some(DVector::from_column_slice(u)),
        }
    }

    /// Takes `data`'s joint force inputs and cable tensions
    /// ([`crate::Data::set_cable_tensions`]) into the workspace, as the
    /// evaluations of `data` see them. No allocation once set.
    pub fn copy_inputs(&mut self, data: &Data) {
        self.copy_joint_inputs(data);
        match (data.cable_tensions(), &mut self.tensions) {
            (None, t) => *t = None,
            (Some(u), Some(t)) if t.len() == u.len() => t.as_mut_slice().copy_from_slice(u),
            (Some(u), t) => *t = Some(DVector::from_column_slice(u)),
        }
    }

    fn with_dense(model: &Model, dense: bool) -> Self {
        let n = model.n_dof();
        let nd = if dense { n } else { 0 };
        Self {
            pieces: model
                .rods()
                .iter()
                .map(|r| {
                    (0..r.spec.geometry.n_pieces())
                        .map(|_| PieceWork::new())
                        .collect()
                })
                .collect(),
            planar: model
                .rods()
                .iter()
                .map(|r| match &r.planar {
                    Some(pr) => pr
                        .pieces
                        .iter()
                        .map(|_| planar::PlanarWork::new())
                        .collect(),
                    None => Vec::new(),
                })
                .collect(),
            planar_taken: vec![false; model.rods().len()],
            dtau_dq: DMatrix::zeros(nd, nd),
            dtau_dqd: DMatrix::zeros(nd, nd),
            tau: DVector::zeros(n),
            tensions: None,
            joint_inputs: None,
            contact: model.has_contact().then(|| Box::new(Data::new(model))),
            n_dof: n,
            tree: model
                .tree
                .as_ref()
                .map(|t| Box::new(tree::TreeWork::new(model, t))),
            linearized: false,
            mass_kept: false,
        }
    }
}

crate::kernels::simd::dispatch! {
    /// Analytic `∂τ/∂q` and `∂τ/∂q̇` of the inverse dynamics
    /// `τ = ID(q, q̇, q̈)` at time `t` (docs/theory-derivatives.md, (D37)–(D47)),
    /// with every term of the model: inertia, Coriolis and centrifugal forces,
    /// gravity, elasticity and Kelvin–Voigt damping, cables, dead and follower
    /// point loads, distributed loads, drag. `∂τ/∂q̈ = M(q)`
    /// ([`crate::mass_matrix`]).
    ///
    /// One outward sweep linearizes every evaluation point in its own piece's
    /// strain (D39–D42); one inward sweep carries the composite inertia,
    /// velocity-product and dead-load operators (D43) and forms each piece's
    /// diagonal block and the change of its transmitted wrench (D44); the
    /// off-diagonal blocks are pairings of per-piece world-frame quantities
    /// (D45–D46). Cost O(N·n_dof) (the result is dense), no allocation.
    ///
    /// `q`, `q̇`, `q̈`: dim `n_dof`. Results in `work.dtau_dq`, `work.dtau_dqd`
    /// (n_dof × n_dof, row = component of `τ`, column = coordinate) and
    /// `work.tau`, of the inverse dynamics under `forces` (loads and cable
    /// tensions scaled by [`Forces::load_scale`]; prescribed joints moving or
    /// at rest).
    pub fn inverse_dynamics_derivatives_with<'a>(model: &Model, work: &'a mut IdDerivatives, forces: Forces, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<&'a IdDerivatives, DynamicsError>
    => id_derivatives_impl, id_derivatives_avx2
}

crate::kernels::simd::dispatch! {
    /// The linearization of the inverse dynamics without its dense
    /// matrices (docs/theory-derivatives.md §8, D81): the sweeps of
    /// [`inverse_dynamics_derivatives_with`] — `τ` into `work.tau`, each
    /// piece's and joint's diagonal blocks and world-frame pairing
    /// quantities kept per piece — but not the off-diagonal blocks, which
    /// [`inverse_dynamics_vjp`] then applies as products in O(N). Cost O(N),
    /// no allocation; `work.dtau_dq`, `work.dtau_dqd` are not touched
    /// (a workspace from [`IdDerivatives::for_products`] has none).
    ///
    /// Arguments as [`inverse_dynamics_derivatives_with`]. Models with
    /// contact: [`DynamicsError::UnsupportedContact`] (their contact forces
    /// enter the dense derivatives only); with closures:
    /// [`DynamicsError::UnsupportedClosed`].
    pub fn inverse_dynamics_linearization_with<'a>(model: &Model, work: &'a mut IdDerivatives, forces: Forces, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<&'a IdDerivatives, DynamicsError>
    => id_linearization_impl, id_linearization_avx2
}

/// [`inverse_dynamics_derivatives_with`] of every force of the model
/// ([`Forces::ALL`]).
pub fn inverse_dynamics_derivatives<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a IdDerivatives, DynamicsError> {
    inverse_dynamics_derivatives_with(model, work, Forces::ALL, t, q, qd, qdd)
}

#[inline(always)]
pub(crate) fn id_derivatives_impl<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a IdDerivatives, DynamicsError> {
    checked(model, work, forces, t, (q, qd, qdd), true)
}

#[inline(always)]
fn id_linearization_impl<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a IdDerivatives, DynamicsError> {
    if model.has_contact() {
        return Err(DynamicsError::UnsupportedContact {
            what: "inverse_dynamics_linearization",
        });
    }
    checked(model, work, forces, t, (q, qd, qdd), false)
}

/// The checks of both evaluations, then the sweeps.
#[inline(always)]
fn checked<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    forces: Forces,
    t: f64,
    (q, qd, qdd): (&[f64], &[f64], &[f64]),
    dense: bool,
) -> Result<&'a IdDerivatives, DynamicsError> {
    work.linearized = false;
    work.mass_kept = false;
    let nodes = model.tree.as_ref().map(|t| t.nodes.len());
    if work.n_dof != model.n_dof()
        || (dense && work.dtau_dq.nrows() != work.n_dof)
        || work.pieces.len() != model.rods().len()
        || work.tree.as_ref().map(|t| t.n_nodes()) != nodes
        || work
            .planar
            .iter()
            .zip(model.rods())
            .any(|(p, r)| p.len() != r.planar.as_ref().map_or(0, |pr| pr.pieces.len()))
    {
        return Err(DynamicsError::WorkspaceMismatch {
            what: "IdDerivatives",
            built: work.n_dof,
            got: model.n_dof(),
        });
    }
    forces.check()?;
    // Gravity alone is no public pass; its derivatives are not taken.
    debug_assert!(!forces.gravity_only, "derivatives of gravity alone");
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    check_vec(model, "qddot", qdd)?;
    if model.has_closures() {
        return Err(DynamicsError::UnsupportedClosed {
            what: "inverse_dynamics_derivatives",
        });
    }
    open_tree_core(model, work, forces, t, (q, qd, qdd), dense)
}

crate::kernels::simd::dispatch! {
    /// The derivatives of the open tree's inverse dynamics of a model with
    /// closures (the closure forces `Jᵀλ` left out: the constrained
    /// derivatives add theirs, docs/theory-derivatives.md (CD2)). Arguments
    /// checked by the caller.
    pub(crate) fn open_tree_id_derivatives<'a>(model: &Model, work: &'a mut IdDerivatives, forces: Forces, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<&'a IdDerivatives, DynamicsError>
    => open_tree_dense, open_tree_dense_avx2
}

#[inline(always)]
fn open_tree_dense<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a IdDerivatives, DynamicsError> {
    work.linearized = false;
    work.mass_kept = false;
    open_tree_core(model, work, forces, t, (q, qd, qdd), true)
}

/// A planar rod's sweeps and pairs (D107), out of line: inlined into
/// [`open_tree_core`] they would change how the six-strain sweeps beside
/// them are compiled (+6.8 % instructions on the six-strain analytic pair,
/// the instruction-count gate).
#[inline(never)]
fn planar_rod(
    model: &Model,
    rm: &RodModel,
    pr: &PlanarRod,
    work: &mut IdDerivatives,
    r: usize,
    at: &At,
    dense: bool,
) {
    planar::outward(model, rm, pr, &mut work.planar[r], at);
    planar_close::inward(model, rm, pr, work, r, at);
    if dense {
        planar_products::pairs(rm, work, r);
    }
}

/// The body of [`id_derivatives_impl`] after its checks; the dense
/// matrices only when `dense`. Not forced inline: with the planar rods'
/// sweeps beside the six-strain ones (D107), forcing it into its callers
/// cost the six-strain analytic pair 6.8 % more instructions (the
/// instruction-count gate); out of line it is 2.4 % below the count before.
fn open_tree_core<'a>(
    model: &Model,
    work: &'a mut IdDerivatives,
    forces: Forces,
    t: f64,
    (q, qd, qdd): (&[f64], &[f64], &[f64]),
    dense: bool,
) -> Result<&'a IdDerivatives, DynamicsError> {
    let at = At {
        t,
        q,
        qd,
        qdd,
        forces,
        dense,
    };
    if let (Some(tr), Some(mut tw)) = (&model.tree, work.tree.take()) {
        tree::tree_id_derivatives(model, tr, work, &mut tw, &at);
        work.tree = Some(tw);
    } else {
        if dense && model.rods().len() > 1 {
            work.dtau_dq.fill(0.0);
            work.dtau_dqd.fill(0.0);
        }
        for (r, rm) in model.rods().iter().enumerate() {
            // Planar rods on the forward run's planar path: the sweeps on
            // se(2) (D95–D100), their buffers 3×3 (D107).
            let pr = rm.planar.as_ref().filter(|_| model.planar_path);
            work.planar_taken[r] = pr.is_some();
            if let Some(pr) = pr {
                planar_rod(model, rm, pr, work, r, &at, dense);
                continue;
            }
            chain::outward(model, rm, &mut work.pieces[r], &at);
            chain::inward(model, rm, work, r, &at);
            if dense {
                chain::pairs(rm, work, r);
            }
        }
    }
    if !dense {
        // The products check what they return (vjp.rs); τ here.
        if let Some(i) = work.tau.iter().position(|v| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("tau[{i}] of the linearization at t = {t}"),
                value: work.tau[i],
            });
        }
        work.linearized = true;
        work.mass_kept = true;
        return Ok(work);
    }
    if let Some(mut cd) = work.contact.take() {
        contact::subtract_contact(
            model,
            &mut cd,
            forces,
            t,
            q,
            qd,
            &mut work.tau,
            &mut work.dtau_dq,
            &mut work.dtau_dqd,
        );
        work.contact = Some(cd);
    }
    for (what, m) in [("dtau/dq", &work.dtau_dq), ("dtau/dqdot", &work.dtau_dqd)] {
        // One vectorizable pass (x·0 is NaN exactly for non-finite x), the
        // index search only on failure.
        let probe: f64 = m.as_slice().iter().map(|v| v * 0.0).sum();
        if probe.is_nan() {
            if let Some((i, v)) = m.iter().enumerate().find(|(_, v)| !v.is_finite()) {
                return Err(DynamicsError::NotFinite {
                    what: format!(
                        "{what} entry ({}, {}) at t = {t}",
                        i % m.nrows(),
                        i / m.nrows()
                    ),
                    value: *v,
                });
            }
        }
    }
    work.linearized = true;
    Ok(work)
}
