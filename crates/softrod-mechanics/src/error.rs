//! Errors of constitutive, load and actuator descriptions.

/// What can be wrong with a section, material, load or cable description.
///
/// Every variant names the offending quantity and carries its value, so a
/// scene loader can point at the exact field.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MechanicsError {
    /// A quantity that must be strictly positive and finite is not.
    #[error("{what} must be positive and finite, got {value}")]
    NotPositive {
        /// Which quantity (e.g. "section radius [m]").
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A quantity that must be non-negative and finite is not.
    #[error("{what} must be non-negative and finite, got {value}")]
    Negative {
        /// Which quantity.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A quantity that must be finite is NaN or infinite.
    #[error("{what} is not finite ({value})")]
    NotFinite {
        /// Which quantity.
        what: String,
        /// The offending value.
        value: f64,
    },
    /// A tube's inner radius is not smaller than its outer radius.
    #[error("tube inner radius {inner} m must be smaller than its outer radius {outer} m")]
    InnerRadius {
        /// Inner radius [m].
        inner: f64,
        /// Outer radius [m].
        outer: f64,
    },
    /// A Poisson ratio outside `(−1, 0.5]`.
    #[error("Poisson ratio must lie in (-1, 0.5], got {value}")]
    PoissonRatio {
        /// The offending value.
        value: f64,
    },
    /// A cable span that is not `0 ≤ from < to ≤ L`.
    #[error("cable span [{from}, {to}] m must satisfy 0 <= from < to <= rod length {length} m")]
    CableSpan {
        /// Start of the span [m].
        from: f64,
        /// End (anchor) of the span [m].
        to: f64,
        /// Rod length [m].
        length: f64,
    },
    /// A table's abscissae (routing `s`, tension times) are not strictly increasing.
    #[error("{what}: entry {index} ({value}) is not greater than the previous entry ({previous})")]
    NotIncreasing {
        /// Which table.
        what: String,
        /// Index of the offending entry.
        index: usize,
        /// Its abscissa.
        value: f64,
        /// The previous abscissa.
        previous: f64,
    },
    /// A table that needs at least one entry is empty.
    #[error("{what} needs at least one entry")]
    Empty {
        /// Which table.
        what: String,
    },
    /// Two sizes that must agree do not.
    #[error("{what} has {got} entries, expected {expected}")]
    SizeMismatch {
        /// Which quantity.
        what: String,
        /// The size given.
        got: usize,
        /// The size required.
        expected: usize,
    },
    /// The mechanical body and the kinematic rod disagree on the length.
    #[error("body length {body} m differs from the rod length {rod} m")]
    LengthMismatch {
        /// Length of the [`crate::RodBody`] [m].
        body: f64,
        /// Length of the kinematic rod [m].
        rod: f64,
    },
    /// An abscissa outside the rod.
    #[error("{what}: abscissa s = {s} m lies outside the rod [0, {length}] m")]
    OutOfRod {
        /// Which load or quantity.
        what: String,
        /// The abscissa [m].
        s: f64,
        /// The rod length [m].
        length: f64,
    },
}

pub(crate) fn positive(what: &str, value: f64) -> Result<(), MechanicsError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(MechanicsError::NotPositive {
            what: what.to_string(),
            value,
        })
    }
}

pub(crate) fn non_negative(what: &str, value: f64) -> Result<(), MechanicsError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(MechanicsError::Negative {
            what: what.to_string(),
            value,
        })
    }
}

pub(crate) fn finite(what: &str, value: f64) -> Result<(), MechanicsError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(MechanicsError::NotFinite {
            what: what.to_string(),
            value,
        })
    }
}
