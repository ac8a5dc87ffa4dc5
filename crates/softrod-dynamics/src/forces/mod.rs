//! Floor 2, the forces: every force term of the equations of motion — its
//! value where the sweeps need it and its linearization for the derivative
//! sweeps — and [`Forces`], the argument that says which of them an
//! evaluation includes.
//!
//! - [`external`]: gravity as a base acceleration, the distributed wrench
//!   density (drag, distributed loads) at an evaluation point;
//! - [`strain`]: elasticity, damping, cables, joint springs, actuation — the
//!   forces that act in strain space;
//! - [`linearized`]: their derivatives (dead loads, drag, cable Hessian).
//!
//! A new force term goes here: its description on the rod or body in
//! `crate::model`, its value in [`external`] (a wrench density or a point
//! wrench on a section) or [`strain`] (a generalized force), its
//! linearization in [`linearized`], and a field of [`Forces`] if an
//! evaluation can leave it out or scale it. The sweeps of
//! `crate::algorithms` and `crate::derivatives` call it where they call the
//! present terms (point loads: `PieceData::loads` at their abscissae). A
//! per-evaluation list — contact forces at material points, world-frame
//! wrenches at `(rod, s)` that change every evaluation — is a field of
//! [`Forces`] borrowing the caller's list, applied like the point loads.

pub(crate) mod contact;
pub(crate) mod external;
pub(crate) mod linearized;
pub(crate) mod strain;

use crate::error::DynamicsError;

/// How the prescribed joints (D59) move in an evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Drives {
    /// As prescribed: their values, rates and accelerations at the time of
    /// the evaluation.
    #[default]
    Moving,
    /// Held at their values at that time, at rest (no rate, no
    /// acceleration): the configuration statics and modes work about.
    AtRest,
}

/// Which forces one evaluation of the equations of motion includes — the
/// pass argument of every sweep, so that what a sweep computes is said by
/// what it is given, never by state left in a workspace.
///
/// [`Forces::ALL`] (the default) is the model as built: every term, loads
/// at full scale, drives moving. The functions without `_with` in their
/// name use it; statics ramps [`Forces::load_scale`] and holds the drives
/// at rest ([`Forces::at_rest`]).
///
/// ```
/// use softrod_dynamics::{Drives, Forces};
///
/// let half = Forces::ALL.with_load_scale(0.5);
/// assert_eq!(half.load_scale, 0.5);
/// assert_eq!(half.drives, Drives::Moving);
/// assert_eq!(Forces::at_rest(0.5).drives, Drives::AtRest);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Forces {
    /// Factor `λ` on every external load and cable tension: gravity, point,
    /// distributed and body loads, the cables' tensions (the inputs `u` or
    /// the schedules). Elasticity, damping, drag and joint springs are not
    /// scaled. 1: the model as built.
    pub load_scale: f64,
    /// How the prescribed joints move.
    pub drives: Drives,
    /// Gravity alone, the generalized gravity `G(q)` (D22): no elasticity,
    /// damping, cables, loads, drag or joint springs, drives at rest.
    pub(crate) gravity_only: bool,
}

impl Default for Forces {
    fn default() -> Self {
        Self::ALL
    }
}

impl Forces {
    /// Every term of the model, loads at full scale, drives moving.
    pub const ALL: Self = Self {
        load_scale: 1.0,
        drives: Drives::Moving,
        gravity_only: false,
    };

    /// Gravity alone at full scale, drives at rest (the generalized
    /// gravity `G(q)`, [`crate::generalized_gravity`]).
    pub(crate) const GRAVITY: Self = Self {
        load_scale: 1.0,
        drives: Drives::AtRest,
        gravity_only: true,
    };

    /// The static forces of statics' load continuation: every term, loads
    /// scaled by `load_scale`, drives held at rest.
    pub const fn at_rest(load_scale: f64) -> Self {
        Self {
            load_scale,
            drives: Drives::AtRest,
            gravity_only: false,
        }
    }

    /// The same forces with the loads scaled by `load_scale`.
    #[must_use]
    pub const fn with_load_scale(mut self, load_scale: f64) -> Self {
        self.load_scale = load_scale;
        self
    }

    /// The same forces with the drives moving or at rest.
    #[must_use]
    pub const fn with_drives(mut self, drives: Drives) -> Self {
        self.drives = drives;
        self
    }

    /// Whether the prescribed joints move (their rates and accelerations
    /// enter the sweeps).
    #[inline(always)]
    pub(crate) fn drives_move(&self) -> bool {
        !self.gravity_only && self.drives == Drives::Moving
    }

    /// [`DynamicsError::NotFinite`] for a load scale that is not finite.
    pub(crate) fn check(&self) -> Result<(), DynamicsError> {
        if !self.load_scale.is_finite() {
            return Err(DynamicsError::NotFinite {
                what: "load_scale".into(),
                value: self.load_scale,
            });
        }
        Ok(())
    }
}
