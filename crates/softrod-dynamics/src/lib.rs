//! PCS dynamics: inverse and O(N) forward dynamics, the matrices of the
//! Lagrangian form, energies, statics and linearized modes — the fourth
//! layer of softrod.
//!
//! A [`Model`] (rods, their bodies and force terms, gravity, quadrature) is
//! immutable, built with [`Model::builder`] from rods built with
//! [`Rod::builder`]; a [`Data`] holds every buffer an evaluation needs. Algorithms
//! are free functions that write into `data` and return a reference to the
//! result:
//!
//! | function | computes | reference |
//! |---|---|---|
//! | [`inverse_dynamics`] | `τ_act(q, q̇, q̈)` | docs/theory.md §4 (D17–D18) |
//! | [`forward_dynamics`] | `q̈`, O(N) articulated recursion | §6 (D23–D27) |
//! | [`forward_dynamics_cholesky`] | `q̈ = M⁻¹(τ − b)` | cross-check |
//! | [`mass_matrix`] | `M(q)`, composite recursion | (D19–D20) |
//! | [`bias_force`] | `b = C q̇ + G + τ_e + D q̇ − τ_c − Q_ext` | (D21–D22) |
//! | [`strain_space_force`] | `τ_c − τ_e − D q̇` (and joint springs), the strain-space part of `−ID` | (D13, D15, D53) |
//! | [`energies`] | kinetic, elastic, gravitational | §7 |
//! | [`statics`] | equilibrium, Newton + line search + continuation | |
//! | [`modes`] | natural frequencies about an equilibrium | |
//! | [`lowest_modes`] | the lowest modes, matrix-free, O(N) per step | docs/theory.md E11 |
//! | [`inverse_dynamics_derivatives`] | `∂τ/∂q`, `∂τ/∂q̇` (`∂τ/∂q̈ = M`) | docs/theory-derivatives.md (D37–D47) |
//! | [`inverse_dynamics_linearization_with`], [`inverse_dynamics_vjp`], [`inverse_dynamics_jvp`] | `uᵀ∂τ/∂q`, `uᵀ∂τ/∂q̇`, `∂τ/∂q·a + ∂τ/∂q̇·b` in O(N), no dense matrix | (D81–D84) |
//! | [`inverse_dynamics_inertia_vjp`] | `zᵀ∂τ/∂(inertia)` of every rod and body at once, O(N) | (D85) |
//! | [`inverse_dynamics_mass_product`] | `M(q) v` from the same linearization, O(N), no mass matrix | (D86) |
//! | [`forward_dynamics_derivatives`] | `∂q̈/∂q`, `∂q̈/∂q̇`, `∂q̈/∂u` | (D48) |
//! | [`closed_dynamics_derivatives`] | `∂q̈/∂q`, `∂q̈/∂q̇` of a closed model's constrained `q̈` | (CD1–CD4) |
//! | [`linearize`] | `(A, B)` of `ẋ = f(x, u)`, `x = (q, q̇)`; closed models: of the constrained `q̈` | (D49), (CD9) |
//! | [`dynamics_jacobians`] | `∂q̈/∂q`, `∂q̈/∂q̇` (allocating) | (D48) |
//! | [`section_jacobian`] | world pose and spatial Jacobian of a rod section, through joints and parents | (D11), (D57), (D62) |
//! | [`body_jacobian`] | world pose and spatial Jacobian of a rigid body's frame | (D11), (D57) |
//! | [`statics_sensitivity`] | `∂q/∂p`, `∂λ/∂p` of an equilibrium, closed models by the bordered system | docs/theory-control.md (IS3), (IS8–IS10) |
//! | [`ShiftedSolver`] | `(M + aK + bD)⁻¹ x`, O(N), chains and trees; with the contact's stiffness and damping ([`ShiftedSolver::linearize_contact`]) | §6 with armature `aK_n + bD_n`; docs/theory-contact.md CT17 |
//! | [`ClosedShiftedSolver`] | the KKT solve of a closed model's implicit step, O(N·m) | docs/theory-derivatives.md (CD5–CD7) |
//!
//! Robots: rods and rigid bodies ([`BodySpec`]) hang from parents (the world,
//! a rod's piece boundary, a body) through joints ([`Joint`]: fixed,
//! revolute, prismatic, universal, spherical, free), built with
//! [`ModelBuilder::rod_on`], [`ModelBuilder::body`] or
//! [`Model::with_elements`]. A joint is a massless unit PCS piece whose
//! basis is its motion subspace (docs/theory.md §11, D50–D58); inverse and
//! forward dynamics, the mass matrix, energies, statics and modes run on the
//! tree, and so do the O(N) [`ShiftedSolver`] and the analytic derivatives
//! (docs/theory-derivatives.md §7, D76–D80; neither on closed chains).
//! Models without bodies, parents or joints keep the chain path
//! unchanged; [`coriolis_matrix`] returns [`DynamicsError::Unsupported`]
//! for the others.
//!
//! Closed chains: [`Closure`]s (weld, ball, slider between rod points at any
//! `s`, body frames and the world; [`ModelBuilder::closure`],
//! [`Model::with_closures`]) hold two frames together (docs/theory.md
//! D63–D69). [`forward_dynamics`] then returns the Baumgarte-stabilized
//! constrained `q̈` (multipliers in [`closure_multipliers`]), [`statics`]
//! and [`modes`] solve the constrained system ([`closure_statics`] also
//! returns the multipliers); [`constraint_residual`], [`constraint_jacobian`],
//! [`closure_residuals`], [`check_closures`] and [`constraint_rank`] expose
//! the constraints; [`inverse_dynamics`] returns
//! [`DynamicsError::UnsupportedClosed`].
//!
//! Planar rods (every piece's strains among `κ_a, q_b, q_c` for one bending
//! axis, a rest strain in that plane; [`RodModel::is_planar`]) run the
//! forward and inverse dynamics on se(2): 3-vectors and 3×3 blocks instead
//! of 6 and 6×6, a third of the cost, equal to the general path to
//! rounding (docs/theory.md §13, D71–D75; [`Model::with_planar_path`]
//! turns it off).
//!
//! Which forces an evaluation includes is an argument, [`Forces`]: every
//! term at full scale with the prescribed joints moving ([`Forces::ALL`],
//! what the functions without `_with` use), the loads scaled
//! ([`Forces::with_load_scale`], statics' continuation), the drives held at
//! rest ([`Drives::AtRest`], statics and modes). Nothing of an evaluation's
//! mode is kept in [`Data`]; what `Data` keeps between calls is the clock
//! of the prescribed joints ([`Model::set_time`], set by every function
//! that takes `t`) and the cable inputs ([`Data::set_cable_tensions`]).
//!
//! Units SI; twists and wrenches angular first; body frame (see `softrod-lie`).
//!
//! # Where things live
//!
//! Floors, bottom to top: `kernels/` → `model/` → `forces/` →
//! `algorithms/` → `derivatives/` → `constraints/` → `analysis/` →
//! `dispatch.rs`.
//!
//! A module names only its own folder, the floors below it and `error.rs`
//! (tests/layout.rs checks it, and that no source file passes 800 lines):
//!
//! | floor | holds | a new … goes here |
//! |---|---|---|
//! | `kernels/` | arithmetic on one piece or point, no model: 3×3-block 6×6 products, the small Cholesky of a piece, inertia sums over a piece's points, strain derivatives of the piece maps (D30–D36), the planar se(2) maps, the AVX2 copies' dispatch | faster per-piece math |
//! | `model/` | [`Model`] and its builders, [`Rod`]/[`RodModel`], joints and bodies, prescribed curves, the tree of nodes, closures as the model holds them, planar detection, contact as the model holds it (obstacles, contact points, which rod points may touch), and [`Data`] with every algorithm's work space | **joint type** (`model/joint.rs`: its motion subspace as virtual pieces, D50), element, or the description of a load |
//! | `forces/` | [`Forces`]; each force term's value — gravity as base acceleration, drag and distributed loads per point, elasticity, damping, cables, joint springs in strain space — and its linearization | **force term**: value in `external.rs` or `strain.rs`, linearization in `linearized.rs`, a field of [`Forces`] if an evaluation may leave it out (contact forces at material points: a per-evaluation list there, applied like point loads) |
//! | `algorithms/` | the O(N) recursions on open models, each on the chain (`chain.rs`, AVX2 copies), the planar chain (`planar.rs`) and the tree (`tree.rs`, `frames.rs`): inverse dynamics, articulated forward dynamics, mass matrix, shifted solve; the public [`inverse_dynamics`], [`mass_matrix`], [`bias_force`] | **algorithm** on the equations of motion (an integrator's evaluation), with a chain and a tree form |
//! | `derivatives/` | `∂τ/∂q`, `∂τ/∂q̇` on chain and tree (point linearization, piece closing), their O(N) products (`vjp.rs`), forward-dynamics derivatives, [`linearize`] | **derivative** |
//! | `constraints/` | loop closures: `φ`, `J`, `J̇q̇`, their queries, the constrained forward dynamics | kind of closure (with `model/closure.rs`) |
//! | `analysis/` | energies, frames and section Jacobians, `K`, `D`, `G`, `C`, actuation, [`statics`] and [`modes`], open and closed | analysis built on the above |
//! | `dispatch.rs` | the public [`forward_dynamics`]: the open recursion, or the constrained solve on a closed chain | — |
//!
//! A lone rod is the simplest tree, but the tree recursion (dense 6×6 per
//! node) costs 1.5× the chain's at N = 10, so models without joints,
//! bodies or parents keep the chain path (docs/performance.md).
#![warn(missing_docs)]
#![deny(unsafe_code)]

mod algorithms;
mod analysis;
mod constraints;
mod derivatives;
mod dispatch;
mod error;
mod forces;
mod kernels;
mod model;

pub use algorithms::shifted::ShiftedSolver;
pub use algorithms::{
    bias_force, forward_dynamics_cholesky, inverse_dynamics, inverse_dynamics_with, mass_matrix,
    strain_space_force,
};
pub use analysis::{
    ContactChange, Energies, IMPACT_LIMIT, ModeKind, Modes, StaticsOptions, StaticsResult,
    StaticsSensitivity, StaticsSolver, actuation_matrix, body_jacobian, closure_statics,
    commit_contact, commit_contact_change, coriolis_matrix, damping_matrix, energies, frames,
    friction_stop, generalized_gravity, lowest_modes, modes, section_jacobian, static_force,
    statics, statics_sensitivity, stiffness_matrix,
};
pub use constraints::{
    ClosedDerivatives, ClosedShiftedSolver, ClosureProjection, check_closures,
    closed_dynamics_derivatives, closed_force_response, closed_prescribed_derivatives,
    closed_row_response, closed_row_response_transposed, closure_multipliers, closure_residuals,
    constraint_jacobian, constraint_rank, constraint_residual, max_closure_residual,
    open_tree_inverse_dynamics, project_onto_closures, projection_tolerance,
};
pub use derivatives::{
    DynamicsJacobians, FdDerivatives, IdDerivatives, Linearization, dynamics_jacobians,
    dynamics_jacobians_with, forward_dynamics_derivatives, inverse_dynamics_derivatives,
    inverse_dynamics_derivatives_with, inverse_dynamics_inertia_vjp, inverse_dynamics_jvp,
    inverse_dynamics_linearization_with, inverse_dynamics_mass_product, inverse_dynamics_vjp,
};
pub use dispatch::{forward_dynamics, forward_dynamics_with, linearize};
pub use error::{DynamicsError, RodId};
pub use forces::{Drives, Forces};
pub use model::Data;
pub use model::{Attachment, BodyLoad, BodySpec, Joint, JointActuator, JointForce, JointKind};
pub use model::{BodyModel, Element, ElementInfo, ElementKind, Model, Rod, RodModel};
pub use model::{Closure, ClosureFrame, ClosureKind};
pub use model::{Curve, Prescribed, Spline};
pub use model::{IntoRod, ModelBuilder, RodBuilder};

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
