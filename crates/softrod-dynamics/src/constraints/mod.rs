//! Floor 5, the constraints: loop closures on the tree (docs/theory.md
//! §11, D63–D69) — their rows `φ`, `J`, `J̇q̇` ([`rows`]), what a caller
//! asks of them at a state ([`queries`]), and the constrained forward
//! dynamics ([`forward`]), Lagrange multipliers on top of the tree's
//! recursion, and its derivatives ([`derivatives`], the open tree's
//! analytic ones projected through the multiplier system), and the
//! structured Newton matrix of a closed model's implicit step ([`newton`],
//! KKT form on the open tree's shifted solve), and the projection of a state onto
//! the closures ([`project`], D121). The constrained statics and modes are `crate::analysis`'s.
//! A new kind of closure goes in `crate::model::closure` (its spec and
//! number of rows) and [`rows`] (its residual and row operator).

pub(crate) mod derivatives;
pub(crate) mod forward;
pub(crate) mod newton;
pub(crate) mod project;
pub(crate) mod queries;
pub(crate) mod rows;

pub use derivatives::{
    ClosedDerivatives, closed_dynamics_derivatives, closed_force_response,
    closed_prescribed_derivatives, closed_row_response, closed_row_response_transposed,
    open_tree_inverse_dynamics,
};
pub use newton::ClosedShiftedSolver;
pub use project::{ClosureProjection, project_onto_closures, projection_tolerance};
pub use queries::{
    check_closures, closure_multipliers, closure_residuals, constraint_jacobian, constraint_rank,
    constraint_residual, max_closure_residual,
};
