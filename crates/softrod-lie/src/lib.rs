//! SE(3) and se(3) for Cosserat rods: the Lie-group layer of softrod.
//!
//! Everything the upper layers need to move along a piecewise-constant-strain
//! (PCS) rod: hat/vee, the adjoint maps `ad`, `ad*`, `Ad_g`, `Ad*_g`, the group
//! exponential `exp(x·ξ̂)`, the closed-form `exp(x·ad_ξ)`, the tangent operator
//! `T(x) = ∫₀ˣ exp(l·ad_ξ) dl` and its strain derivative.
//!
//! # Conventions (fixed everywhere in softrod)
//! - Twists and wrenches are 6-vectors, **angular part first**: a strain
//!   `ξ = (k, q)` (curvature/torsion, then shear/extension), a velocity
//!   `η = (ω, v)`, a wrench `𝓕 = (M, N)` (moment, force). All body-frame.
//! - `ad_ξ = [[k̃, 0], [q̃, k̃]]`, coadjoint `ad*_ξ = [[k̃, q̃], [0, k̃]] = −ad_ξᵀ`,
//!   `Ad_g = [[R, 0], [p̃R, R]]`, `Ad*_g = Ad_g⁻ᵀ`.
//!
//! # Numerics
//! The closed forms divide by up to `ψ⁷` (`ψ = x·|k|`); below the switch point
//! [`series::PSI_SWITCH`] every coefficient is evaluated by its Taylor series
//! (14 terms, Horner in `ψ²`), so all maps are accurate to ~1e-15 relative on
//! both sides of the switch and at `θ = 0` exactly (derivations.md (D5)).
//!
//! Equation labels `(D·)` refer to `shared/docs/derivations.md`; "seed (k)"
//! refers to equation k of the model document.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod adop;
mod exp;
mod ops;
mod piece;
mod pose;
pub mod series;
mod types;

pub use adop::AdOp;
pub use exp::{
    d_exp_ad, d_tangent, d_tangent_minus, d_tangent_minus_self, exp_ad, exp_and_tangent_minus,
    exp_twist, tangent, tangent_minus,
};
pub use ops::{ad, ad_vec, coad, coad_vec, hat, skew, unskew, vee};
pub use piece::PieceMaps;
pub use pose::Pose;
pub use types::*;

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
