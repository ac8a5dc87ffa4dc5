//! Constitutive and actuation models of PCS Cosserat rods: the third layer of
//! softrod.
//!
//! - [`Section`], [`Material`], [`RodProperties`]: area and second moments, the
//!   screw inertia `𝓜 = diag(ρJx, ρJy, ρJz, ρA, ρA, ρA)`, stiffness
//!   `Γ = diag(GJx, EJy, EJz, EA, GA, GA)` and Kelvin–Voigt viscosity
//!   `γ = diag(μJx, 3μJy, 3μJz, 3μA, μA, μA)` ((C5), (C7), bending `EJ`).
//! - [`piece_matrices`]: per-piece `K_n`, `D_n` and the rest offset of the
//!   elastic force `τ_e = K q + e` (D13); [`elastic_energy`] (§7).
//! - Loads (D14), each a separate term returning a body-frame wrench:
//!   [`PointLoad`] (dead or follower), [`DistributedLoad`], [`Drag`]
//!   (gravity is a base acceleration of the dynamics layer).
//! - [`Cable`]s (D15): routing, span, tension schedule, length and the
//!   generalized force `τ_c = −T ∂ℓ_c/∂q`.
//! - [`validity`]: what a rod model and a rigid body can describe (a
//!   positive stretch, strains within the model's validity, curvature
//!   radii above the section, physical inertias), the one set of rules
//!   the scene check and a run's watch apply.
//! - Errors: one [`MechanicsError`] naming the [`Quantity`] at fault and its value.
//! - `reference` (feature `reference`, test support): slow Jacobian-based
//!   projections and potentials, the independent checks for the layers above.
//!
//! Conventions: SI units; 6-vectors angular first (`(M, N)` wrenches,
//! `(k, q)` strains); body frame at the section centre; `s ∈ [0, L]` is the
//! undeformed abscissa and densities are per unit undeformed length.
//! Labels (C·), (D·) refer to `docs/theory.md` of the repository.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod body;
mod cable;
pub mod contact;
mod elastic;
mod error;
mod loads;
mod material;
#[cfg(feature = "reference")]
pub mod reference;
mod section;
pub mod validity;

pub use body::RodProperties;
pub use cable::{Cable, Routing, Span, Tension};
pub use contact::{ContactPoint, ContactSettings, Contactee, Obstacle, ObstacleError, Shape};
pub use elastic::{PieceMatrices, elastic_energy, integrated_constitutive, piece_matrices};
pub use error::{MechanicsError, Quantity};
pub use loads::{DistributedLoad, Drag, LoadFrame, PointLoad};
pub use material::{Material, MaterialBuilder};
pub use section::{Section, SectionProperties};

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
