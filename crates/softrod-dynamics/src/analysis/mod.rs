//! Floor 6, the analysis: what is built on the equations of motion and
//! their derivatives — energies ([`energy`], docs/theory.md §7), world
//! frames and section Jacobians ([`frames`]), the matrices of the
//! Lagrangian form `K`, `D`, `G`, `C` and the actuation matrix
//! ([`matrices`]), static equilibrium ([`statics`]) and linearized modes
//! ([`modes`]), for open models and, through [`closed`], models with loop
//! closures (D69). A new analysis of a model goes here.

pub(crate) mod closed;
pub(crate) mod contact;
pub(crate) mod energy;
pub(crate) mod frames;
pub(crate) mod krylov;
pub(crate) mod lanczos;
pub(crate) mod matrices;
pub(crate) mod modes;
pub(crate) mod statics;

pub use crate::model::contact::IMPACT_LIMIT;
pub use closed::{StaticsSensitivity, closure_statics, statics_sensitivity};
pub(crate) use contact::raise_for_rest;
pub use contact::{ContactChange, commit_contact, commit_contact_change, friction_stop};
pub use energy::{Energies, energies};
pub use frames::{body_jacobian, frames, section_jacobian};
pub use lanczos::lowest_modes;
pub use matrices::{
    actuation_matrix, coriolis_matrix, damping_matrix, generalized_gravity, stiffness_matrix,
};
pub use modes::{ModeKind, Modes, modes};
pub use statics::{StaticsOptions, StaticsResult, StaticsSolver, static_force, statics};
