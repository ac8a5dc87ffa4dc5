//! Errors of rod descriptions and kinematic queries.

/// What can be wrong with a rod description or a kinematic query.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KinematicsError {
    /// A length (rod or piece) is zero, negative or not finite.
    #[error("{what} must be a positive finite length in metres, got {value}")]
    BadLength {
        /// Which length (e.g. "piece 3 length").
        what: String,
        /// The offending value.
        value: f64,
    },
    /// The rod has no pieces.
    #[error("a rod needs at least one piece")]
    NoPieces,
    /// A strain basis is not of full column rank, or has too many columns.
    #[error("strain basis of piece {piece} is invalid: {reason}")]
    BadBasis {
        /// Piece index (0-based).
        piece: usize,
        /// Why.
        reason: String,
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
    /// A number that must be finite is NaN or infinite.
    #[error("{what} is not finite ({value})")]
    NotFinite {
        /// Which quantity.
        what: String,
        /// The offending value.
        value: f64,
    },
}
