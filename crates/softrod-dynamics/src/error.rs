//! Errors of model building and the dynamics algorithms.

/// What went wrong, with the values that did.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// The model description is inconsistent.
    #[error("invalid model: {0}")]
    InvalidModel(String),
    /// A vector argument has the wrong length.
    #[error("{what} has {got} entries, the model has {expected} coordinates")]
    SizeMismatch {
        /// Which argument.
        what: &'static str,
        /// Its length.
        got: usize,
        /// `n_dof`.
        expected: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what} is not finite ({value})")]
    NotFinite {
        /// Which quantity and where.
        what: String,
        /// The value.
        value: f64,
    },
    /// A matrix that must be positive definite is not.
    #[error("{what} of rod {rod}, piece {piece} is not positive definite")]
    Singular {
        /// Rod index.
        rod: usize,
        /// Piece index.
        piece: usize,
        /// Which matrix.
        what: &'static str,
    },
    /// Statics did not converge.
    #[error(
        "statics did not converge: {reason} (load fraction {load_fraction:.3}, {iterations} Newton iterations, residual {residual:.3e})"
    )]
    StaticsFailed {
        /// Why it stopped.
        reason: String,
        /// Fraction of the full load reached by continuation.
        load_fraction: f64,
        /// Newton iterations spent in total.
        iterations: usize,
        /// Residual norm (max-abs, N or N·m per coordinate) at the stop.
        residual: f64,
    },
    /// A shift coefficient of `M + a·K + b·D` is negative or not finite
    /// ([`crate::ShiftedSolver::factor`]).
    #[error("shift coefficient {what} = {value} must be finite and non-negative")]
    InvalidShift {
        /// `"a"` (stiffness) or `"b"` (damping).
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A solve was asked of a factorization that does not exist yet (or
    /// whose last `factor` failed).
    #[error("{what}: solve called before a successful factor")]
    NotFactored {
        /// Which solver.
        what: &'static str,
    },
    /// A workspace was built for a model of another shape.
    #[error("{what} was built for a model with {built} coordinates, used with one of {got}")]
    WorkspaceMismatch {
        /// Which workspace.
        what: &'static str,
        /// `n_dof` of the model it was built for.
        built: usize,
        /// `n_dof` of the model it is used with.
        got: usize,
    },
    /// The modal eigenproblem failed.
    #[error("modal analysis failed: {0}")]
    Modes(String),
}
