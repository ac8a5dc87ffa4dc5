//! Errors of rod descriptions and kinematic queries.

use crate::strain::Strain;
use std::fmt;

/// Which length a [`KinematicsError::BadLength`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LengthOf {
    /// The whole rod `L`.
    RodGeometry,
    /// Piece `n` (0-based, base to tip).
    Piece(usize),
}

impl fmt::Display for LengthOf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LengthOf::RodGeometry => f.write_str("rod length"),
            LengthOf::Piece(n) => write!(f, "piece {n} length"),
        }
    }
}

/// What can be wrong with a rod description or a kinematic query.
///
/// Every variant carries the offending values, so that a caller (a scene
/// loader) can point at the field without reading the message.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// A length (rod or piece) is zero, negative or not finite.
    #[error("{what} must be a positive finite length in metres, got {value}")]
    BadLength {
        /// Which length.
        what: LengthOf,
        /// The offending value.
        value: f64,
    },
    /// The rod has no pieces.
    #[error("a rod needs at least one piece")]
    NoPieces,
    /// More pieces than [`crate::RodGeometry::MAX_PIECES`] (a typo rather than a model).
    #[error("{pieces} pieces is more than the maximum of {max}")]
    TooManyPieces {
        /// Pieces asked for.
        pieces: usize,
        /// [`crate::RodGeometry::MAX_PIECES`].
        max: usize,
    },
    /// A strain basis with no column or more than six.
    #[error("a strain basis needs 1 to 6 columns (strains), got {columns}")]
    BasisColumns {
        /// Number of columns (selected strains) given.
        columns: usize,
    },
    /// A strain index outside `0..6`.
    #[error("strain index {index} is not in 0..6")]
    StrainIndex {
        /// The index given.
        index: usize,
    },
    /// A strain selected twice.
    #[error("strain {strain} selected twice")]
    DuplicateStrain {
        /// The repeated strain.
        strain: Strain,
    },
    /// A basis matrix with NaN or infinite entries.
    #[error("strain basis contains NaN or infinity")]
    BasisNotFinite,
    /// A basis matrix that is not of full column rank.
    #[error(
        "strain basis is not of full column rank (singular values {largest:.3e} … {smallest:.3e})"
    )]
    RankDeficient {
        /// Largest singular value.
        largest: f64,
        /// Smallest singular value (≤ 1e-10 × the largest).
        smallest: f64,
    },
    /// A strain name that is not one of `kx, ky, kz, qx, qy, qz`.
    #[error("unknown strain {name:?} (valid: kx, ky, kz, qx, qy, qz)")]
    UnknownStrain {
        /// The name given.
        name: String,
    },
    /// The base pose has a NaN or infinite entry.
    #[error("base pose is not finite ({value})")]
    BaseNotFinite {
        /// The offending entry.
        value: f64,
    },
    /// The base rotation is not orthonormal with determinant +1 (to
    /// [`crate::RodGeometry::ROTATION_TOL`]).
    #[error(
        "base rotation is not a rotation matrix: must be orthonormal with determinant +1 within \
         {tolerance:e} (max |R Rᵀ − I| = {deviation:.3e}, det R = {determinant})"
    )]
    BaseNotRotation {
        /// `max |R Rᵀ − I|` (entrywise).
        deviation: f64,
        /// `det R`.
        determinant: f64,
        /// The tolerance applied to both.
        tolerance: f64,
    },
    /// A rest-strain component is NaN or infinite.
    #[error("rest strain {component} of piece {piece} is not finite ({value})")]
    RestStrainNotFinite {
        /// Piece index (0-based).
        piece: usize,
        /// The component.
        component: Strain,
        /// The offending value.
        value: f64,
    },
    /// A vector or matrix has the wrong size.
    #[error("{what} has size {got}, expected {expected}")]
    SizeMismatch {
        /// Which argument.
        what: &'static str,
        /// The size given.
        got: usize,
        /// The size required.
        expected: usize,
    },
    /// An arc-length abscissa lies outside `[0, L]`.
    #[error("abscissa s = {s} m lies outside the rod [0, {length}] m")]
    OutOfRod {
        /// The abscissa asked for.
        s: f64,
        /// The rod length.
        length: f64,
    },
    /// An entry of a coordinate vector (`q`, `qdot`, `qddot`) is NaN or infinite.
    #[error("{what}[{index}] is not finite ({value})")]
    NotFinite {
        /// Which vector.
        what: &'static str,
        /// Index of the entry.
        index: usize,
        /// The offending value.
        value: f64,
    },
}
