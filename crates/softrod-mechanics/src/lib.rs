//! Constitutive and actuation models of PCS Cosserat rods: the third layer of
//! softrod.
//!
//! - [`Section`], [`Material`], [`RodBody`]: area and second moments, the
//!   screw inertia `𝓜 = diag(ρJx, ρJy, ρJz, ρA, ρA, ρA)`, stiffness
//!   `Γ = diag(GJx, EJy, EJz, EA, GA, GA)` and Kelvin–Voigt viscosity
//!   `γ = diag(μJx, 3μJy, 3μJz, 3μA, μA, μA)` (seed (5)–(6), bending `EJ`).
//! - [`piece_matrices`]: per-piece `K_n`, `D_n` and the rest offset of the
//!   elastic force `τ_e = K q + e` (D13); [`elastic_energy`] (§7).
//! - Loads (D14), each a separate term returning a body-frame wrench:
//!   [`Gravity`], [`PointLoad`] (dead or follower), [`DistributedLoad`],
//!   [`Drag`]; [`LineLoad`] bundles the distributed ones.
//! - [`Cable`]s (D15): routing, span, tension schedule, length and the
//!   generalized force `τ_c = −T ∂ℓ_c/∂q`.
//! - [`reference`]: slow Jacobian-based projections and potentials, the
//!   independent checks for the layers above.
//!
//! Conventions: SI units; 6-vectors angular first (`(M, N)` wrenches,
//! `(k, q)` strains); body frame at the section centre; `s ∈ [0, L]` is the
//! undeformed abscissa and densities are per unit undeformed length.
//! Labels (D·) refer to `docs/derivations.md`.
#![warn(missing_docs)]

mod body;
mod cable;
mod elastic;
mod error;
mod loads;
mod material;
pub mod reference;
mod section;

pub use body::RodBody;
pub use cable::{Cable, Routing, Tension};
pub use elastic::{
    PieceMatrices, add_damping_force, add_elastic_force, elastic_energy, integrated_constitutive,
    piece_matrices,
};
pub use error::MechanicsError;
pub use loads::{DistributedLoad, Drag, Gravity, LineLoad, LoadFrame, PointLoad};
pub use material::Material;
pub use reference::{
    dead_load_potential, generalized_gravity_by_jacobian, gravity_potential,
    line_load_force_by_jacobian, point_load_force_by_jacobian,
};
pub use section::{Section, SectionProperties};
