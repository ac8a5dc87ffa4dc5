//! Floor 3, the algorithms: the O(N) recursions of the equations of motion
//! `M q̈ + b(q, q̇, t) = τ_act` on open models — the outward sweep of poses,
//! twists and accelerations (D7–D10) and the inward passes of the inverse
//! dynamics (D17–D18), the articulated forward dynamics (D23–D27), the
//! composite mass matrix (D19–D20) and the shifted solve of `M + aK + bD`
//! (docs/theory-derivatives.md §6), each in three forms:
//!
//! - [`chain`]: rods clamped to the world, piece by piece (and its AVX2
//!   copies);
//! - [`planar`]: the same for planar rods on se(2), 3×3 blocks (D71–D75);
//! - [`tree`]: models with joints, bodies or parents, node by node
//!   (D54–D58), with [`frames`] for the pose, twist and spatial columns of
//!   any section on the tree.
//!
//! A model without joints, bodies or parents keeps the chain path: a lone
//! rod is the simplest tree, but the tree recursion (dense 6×6 per node)
//! costs 1.5× the chain's at N = 10, so the two stay apart.
//!
//! This module chooses the path ([`inverse_dynamics_open`],
//! [`forward_dynamics_open`], [`mass_matrix`]) and holds the public inverse
//! dynamics, mass matrix and bias. The public forward dynamics is `crate::dispatch`'s: on a closed
//! chain it is the constrained solve of `crate::constraints`. A new
//! algorithm on the equations of motion goes here, with a chain and a tree
//! form.

pub(crate) mod chain;
pub(crate) mod contact;
pub(crate) mod frames;
pub(crate) mod pairs;
pub(crate) mod planar;
pub(crate) mod shifted;
pub(crate) mod shifted_contact;
pub(crate) mod shifted_geometric;
pub(crate) mod tree;

use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector};

/// What the outward sweep accumulates per piece or node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Pass {
    /// (D17–D18) sums with `f = 𝓜η̇ + ad*_η𝓜η − 𝓕_ext`; needs `q̈`.
    Inverse,
    /// (D20) integrals and (D23) bias sums with `h = 𝓜a + ad*_η𝓜η − 𝓕_ext`.
    Articulated,
    /// (D20) integrals only (mass matrix).
    Composite,
    /// Tree only: poses, twists and the velocity-product accelerations of
    /// the node tips and attachment frames (what the closure rows `φ`, `J`,
    /// `J̇q̇` read, D63–D65), no per-point sums: the cheap kinematic sweep
    /// of the closed-chain derivatives (docs/theory-derivatives.md D81).
    Kinematic,
}

/// The motion a sweep evaluates at: coordinates `q`, their rates `q̇`
/// (`None`: at rest) and accelerations `q̈` (`None`: not given — zero in
/// an inverse sweep), each of dim `n_dof`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Motion<'a> {
    pub(crate) q: &'a [f64],
    pub(crate) qd: Option<&'a [f64]>,
    pub(crate) qdd: Option<&'a [f64]>,
}

impl<'a> Motion<'a> {
    #[inline(always)]
    pub(crate) fn new(q: &'a [f64], qd: Option<&'a [f64]>, qdd: Option<&'a [f64]>) -> Self {
        Self { q, qd, qdd }
    }

    /// `q` at rest, no acceleration.
    #[inline(always)]
    pub(crate) fn at_rest(q: &'a [f64]) -> Self {
        Self {
            q,
            qd: None,
            qdd: None,
        }
    }
}

/// Checks a generalized vector argument: length `n_dof`, all finite.
pub(crate) fn check_vec(model: &Model, what: &'static str, v: &[f64]) -> Result<(), DynamicsError> {
    if v.len() != model.n_dof() {
        return Err(DynamicsError::SizeMismatch {
            what,
            got: v.len(),
            expected: model.n_dof(),
        });
    }
    // One pass without an early exit, which the compiler vectorizes; the
    // index search only on failure.
    if !v.iter().fold(true, |ok, x| ok & x.is_finite()) {
        if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("{what}[{i}]"),
                value: *x,
            });
        }
    }
    Ok(())
}

/// The arguments of a forward dynamics: a finite load scale, `q`, `q̇` and
/// `τ_act` of dim `n_dof`, all finite.
pub(crate) fn check_forward_inputs(
    model: &Model,
    forces: Forces,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    forces.check()?;
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    if let Some(ta) = tau_act {
        check_vec(model, "tau", ta)?;
    }
    Ok(())
}

/// `data.qdd`, or the first entry that is not finite as an error (of the
/// result, not of the arguments, which the caller checked).
pub(crate) fn check_qdd(data: &Data, t: f64) -> Result<&DVector<f64>, DynamicsError> {
    if let Some((i, v)) = data.qdd.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DynamicsError::NonFiniteResult {
            what: format!("qddot[{i}] at t = {t}"),
            value: *v,
        });
    }
    Ok(&data.qdd)
}

/// The inverse dynamics of an open model under `forces` at `motion`
/// (arguments checked by the caller): the tree's with the prescribed joints
/// at `t`, else the chain's (its specialized copy when `q̇` and `q̈` are
/// given). Result in `data.tau`.
pub(crate) fn inverse_dynamics_open(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    motion: Motion,
) {
    // Contact first: on a tree its outward sweep leaves node data that the
    // inverse dynamics' own sweep then overwrites.
    let contact = contact_force(model, data, forces, t, motion.q, motion.qd);
    if let Some(tree) = &model.tree {
        model.set_time(data, t);
        tree::inverse_dynamics(model, tree, data, forces, t, motion);
    } else {
        match motion {
            Motion {
                q,
                qd: Some(qd),
                qdd: Some(qdd),
            } => chain::inverse_dynamics(model, data, forces, t, q, qd, qdd),
            _ => chain::inverse_dynamics_general(model, data, forces, t, motion),
        }
    }
    if contact {
        if let Some(mut w) = data.contact.take() {
            data.tau -= &w.tau;
            // The drives hold the rods against the contact forces too (CT18).
            contact::prescribed_share(model, data, &mut w, motion.q);
            data.prescribed_force -= &w.tau_p;
            data.contact = Some(w);
        }
    }
}

/// The generalized contact force at `(q, q̇)` into `data.contact.tau`
/// (docs/theory-contact.md); false (and nothing done) for a model without
/// contact or forces without it (the generalized gravity).
#[inline]
pub(crate) fn contact_force(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: Option<&[f64]>,
) -> bool {
    if !model.contact.active() {
        return false;
    }
    let Some(ask) = contact::Ask::of(forces, qd.is_some()) else {
        return false;
    };
    let Some(mut work) = data.contact.take() else {
        return false;
    };
    if model.tree.is_some() {
        model.set_time(data, t);
    }
    contact::evaluate(model, data, &mut work, q, qd, ask);
    data.contact = Some(work);
    true
}

/// The forward dynamics of an open model, or of a closed model's open tree
/// (without its closures), under `forces` (arguments checked by the
/// caller): the tree's with the prescribed joints at `t`, else the chain's.
/// Result in `data.qdd`.
pub(crate) fn forward_dynamics_open(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    if contact_force(model, data, forces, t, q, Some(qd)) {
        let mut work = data.contact.take().expect("contact work");
        match tau_act {
            Some(ta) => work.tau_total.as_mut_slice().copy_from_slice(ta),
            None => work.tau_total.fill(0.0),
        }
        work.tau_total += &work.tau;
        let result = forward_open_paths(
            model,
            data,
            forces,
            t,
            q,
            qd,
            Some(work.tau_total.as_slice()),
        );
        if result.is_ok() {
            // The drives hold the rods against the contact forces too (CT18).
            contact::prescribed_share(model, data, &mut work, q);
            data.prescribed_force -= &work.tau_p;
        }
        data.contact = Some(work);
        return result;
    }
    forward_open_paths(model, data, forces, t, q, qd, tau_act)
}

fn forward_open_paths(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    match &model.tree {
        Some(tree) => {
            model.set_time(data, t);
            tree::forward_dynamics(
                model,
                tree,
                data,
                forces,
                t,
                Motion::new(q, Some(qd), None),
                tau_act,
            )
        }
        None => chain::forward_dynamics(model, data, forces, t, q, qd, tau_act),
    }
}

/// Inverse dynamics by recursive Newton–Euler for PCS (docs/theory.md §4):
/// the actuator force `τ_act` (n_dof) that produces `q̈` at `(q, q̇, t)`,
///
/// `τ_act = M q̈ + C q̇ + G + τ_e + D q̇ − τ_c − Σ Jᵀ𝓕_p − ∫Jᵀ𝓕_d`,
///
/// with the forces `forces` selects ([`inverse_dynamics`]: all of them).
/// Outward pass (D7–D10) at the Gauss points, point-load abscissae and piece
/// tips; inward pass (D17) for the transmitted wrenches `W_n`; projection
/// (D18) on each piece's `S_n`. Gravity enters as a base acceleration. O(N).
/// `q`, `q̇`, `q̈`: dim `n_dof`. Result in `data.tau`. Models with loop
/// closures: [`DynamicsError::UnsupportedClosed`].
pub fn inverse_dynamics_with<'a>(
    model: &Model,
    data: &'a mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    forces.check()?;
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    check_vec(model, "qddot", qdd)?;
    if model.has_closures() {
        return Err(DynamicsError::UnsupportedClosed {
            what: "inverse_dynamics",
        });
    }
    inverse_dynamics_open(model, data, forces, t, Motion::new(q, Some(qd), Some(qdd)));
    Ok(&data.tau)
}

/// [`inverse_dynamics_with`] of every force of the model ([`Forces::ALL`]).
pub fn inverse_dynamics<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    inverse_dynamics_with(model, data, Forces::ALL, t, q, qd, qdd)
}

/// Mass matrix `M(q) = ∫ Jᵀ𝓜J ds` (D19) by the composite recursion (D20):
/// `𝓜ᶜ_n = 𝓜ᵗ_n + A_ℓᵀ𝓜ᶜ_{n+1}A_ℓ`, `M_mm = 𝓓_m + S_ℓᵀ𝓜ᶜ_{m+1}S_ℓ`, and
/// the off-diagonal blocks `M_nm = S_n(ℓ)ᵀ A…ᵀ F_m` (n < m) of
/// `F_m = 𝓤_m + A_ℓᵀ𝓜ᶜ_{m+1}S_ℓ` carried down the chain, evaluated as the
/// pairing `(Ad_{g_n(ℓ)}S_n(ℓ))ᵀ(Ad*_{g_m(0)⁻¹}F_m)` of world-frame twists
/// and wrenches (the pairing is frame-independent). Block diagonal across
/// rods; on a tree, the composite recursion of (D57). Result in `data.mass`
/// (n_dof × n_dof, symmetric positive definite). Cost O(N·n_dof). With
/// prescribed joints (D59), at their values of the last [`Model::set_time`]
/// or dynamics evaluation.
pub fn mass_matrix<'a>(
    model: &Model,
    data: &'a mut Data,
    q: &[f64],
) -> Result<&'a DMatrix<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    match &model.tree {
        Some(tree) => tree::mass_matrix(model, tree, data, q),
        None => chain::mass_matrix(model, data, q),
    }
    Ok(&data.mass)
}

/// The bias `b(q, q̇, t) = ID(q, q̇, 0)`: `C q̇ + G + τ_e + D q̇ − τ_c − Q_ext`
/// (the equations of motion read `M q̈ + b = τ_act`; with loop closures
/// `M q̈ + b = τ_act + Jᵀλ`, docs/theory.md D67: `b` is the open tree's,
/// without the constraint forces), with prescribed joints (D59) moving as
/// prescribed at `t` (with their acceleration's effect: only the free
/// coordinates' `M q̈` is left out). Result in `data.tau`.
pub fn bias_force<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    bias_force_with(model, data, Forces::ALL, t, q, qd)
}

/// [`bias_force`] under `forces`.
pub(crate) fn bias_force_with<'a>(
    model: &Model,
    data: &'a mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    inverse_dynamics_open(model, data, forces, t, Motion::new(q, Some(qd), None));
    Ok(&data.tau)
}

/// The strain-space generalized forces alone (docs/theory.md D13, D15,
/// D53): `τ_s = τ_c(q, t) − τ_e(q) − D q̇ − k_j(q_j − q_rest) − d_j q̇_j`
/// — cable forces at their tensions at `t` (schedules, or the inputs of
/// [`Data::set_cable_tensions`]), elasticity with its stress-free offset,
/// Kelvin–Voigt damping, joint springs and dampers, joint actuators' forces
/// (docs/theory-control.md IS14). Every inverse dynamics
/// subtracts exactly this vector from its other terms (`ID = ID_rest − τ_s`,
/// `ID_rest` the inertial, gravity, load and drag terms), so the part of
/// `ID` that depends on Young's or shear modulus, viscosity or a cable's
/// tension is `−τ_s`, at O(N) strain-space cost with no kinematic sweep
/// (the parameter products of docs/theory-control.md G8). Result in
/// `data.strain_force` (dim `n_dof`, N·m or N per coordinate unit); no
/// allocation.
pub fn strain_space_force<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<&'a DVector<f64>, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    crate::forces::strain::strain_forces(model, data, Forces::ALL, t, q, Some(qd), None);
    crate::forces::strain::joint_forces(model, data, Forces::ALL, t, q, Some(qd));
    Ok(&data.strain_force)
}

/// Forward dynamics through the mass matrix, the cross-check of the O(N)
/// recursion: `q̈ = M⁻¹(τ_act − ID(q, q̇, 0))` with a dense Cholesky
/// (O(n_dof³), allocates the factor). Result in `data.qdd`.
pub fn forward_dynamics_cholesky<'a>(
    model: &Model,
    data: &'a mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<&'a DVector<f64>, DynamicsError> {
    let zero = vec![0.0; model.n_dof()];
    inverse_dynamics(model, data, t, q, qd, &zero)?;
    let mut rhs = -data.tau.clone();
    if let Some(ta) = tau_act {
        check_vec(model, "tau", ta)?;
        rhs += DVector::from_column_slice(ta);
    }
    mass_matrix(model, data, q)?;
    let chol = data
        .mass
        .clone()
        .cholesky()
        .ok_or(DynamicsError::NotPositiveDefinite {
            what: "mass matrix",
        })?;
    data.qdd = chol.solve(&rhs);
    Ok(&data.qdd)
}
