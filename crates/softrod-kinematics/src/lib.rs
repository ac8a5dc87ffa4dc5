//! Piecewise-constant-strain (PCS) Cosserat rod kinematics: the second layer
//! of softrod.
//!
//! A [`RodGeometry`] is cut into pieces of constant strain `ξ_n = B_n q_n + ξ̄_n`
//! (docs/theory.md §0.6, (C9)); [`RodKinematics`] evaluates, in one O(N) sweep from the
//! clamped base to the tip, everything about where the rod is and how it
//! moves: poses `g(s)` (D7), velocities `η(s) = J(s) q̇` (D8), accelerations `η̇ = J q̈ + J̇ q̇` ((D10)), the geometric Jacobian
//! `J(s)` ((D11)) and its time derivative `J̇(s)` ((D12)), in the body frame
//! or in world axes. [`GaussLegendre`] gives the per-piece quadrature the
//! layers above integrate with.
//!
//! Units SI; twists angular first (see `softrod-lie`).
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod basis;
mod error;
mod fit;
mod quadrature;
mod rod;
mod state;
mod strain;

pub use basis::Basis;
pub use error::{KinematicsError, LengthOf};
pub use fit::{CenterlineFit, fit_centerline};
pub use quadrature::GaussLegendre;
pub use rod::{Piece, PieceSpec, RodGeometry, straight};
pub use state::{Frame, RodKinematics};
pub use strain::Strain;

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
