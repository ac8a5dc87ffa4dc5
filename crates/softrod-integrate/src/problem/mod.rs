//! The internal adaptors the methods run on: a [`Problem`] gives
//! evaluations, keeps a Jacobian and solves with the shifted matrix
//! `(c·I − J)`. A first-order system does so with dense matrices
//! ([`FirstOrderProblem`]); a second-order one through `n×n` Schur
//! complements instead of the `2n×2n` matrix, and with the iteration matrix
//! of the methods that solve for accelerations ([`SecondOrderProblem`]).

use nalgebra::DVector;

use crate::error::{IntegrateError, SystemError};

mod first_order;
mod second_order;

pub(crate) use first_order::FirstOrderProblem;
pub(crate) use second_order::{JacKind, SecondOrderProblem};

/// What the methods need from a problem: evaluations, a Jacobian kept inside,
/// and solves with the shifted matrix `(c·I − J)`. Implemented by the two
/// adaptors so a second-order problem is solved with an `n×n` Schur complement
/// instead of the `2n×2n` matrix.
pub(crate) trait Problem {
    /// The user's system type (handed to callbacks).
    type User;
    /// The user's system.
    fn user(&mut self) -> &mut Self::User;
    /// Whether `f` is autonomous.
    fn is_autonomous(&self) -> bool;
    /// `dy = f(t, y)`.
    fn rhs(&mut self, t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), SystemError>;
    /// Evaluates and stores `J = ∂f/∂y(t, y)`. Returns `Err(what)` on a system
    /// error; non-finite entries are reported as `Ok(Some(index))`.
    fn update_jacobian(&mut self, t: f64, y: &DVector<f64>) -> Result<Option<usize>, SystemError>;
    /// Whether [`update_jacobian`](Self::update_jacobian) gives a cheap
    /// approximation (the mass-matrix form) rather than the exact Jacobian.
    fn has_cheap_jacobian(&self) -> bool {
        false
    }
    /// Evaluates and stores the exact `J` (the same as
    /// [`update_jacobian`](Self::update_jacobian) unless that is a cheap
    /// approximation).
    fn update_exact_jacobian(
        &mut self,
        t: f64,
        y: &DVector<f64>,
    ) -> Result<Option<usize>, SystemError> {
        self.update_jacobian(t, y)
    }
    /// Factors `c·I − J`; `false` if singular.
    fn factor_shifted(&mut self, c: f64) -> bool;
    /// Solves `(c·I − J) x = b` in place with the last factorization.
    fn solve_shifted(&mut self, b: &mut DVector<f64>);
    /// Factors the complex `(α + iβ)·I − J` (kept beside the real one);
    /// `false` if singular.
    fn factor_shifted_complex(&mut self, alpha: f64, beta: f64) -> bool;
    /// Solves `((α + iβ)·I − J)(x_r + i x_i) = b_r + i b_i` in place with
    /// the last complex factorization.
    fn solve_shifted_complex(&mut self, br: &mut DVector<f64>, bi: &mut DVector<f64>);
    /// The system changed (a callback said so): parts of the Jacobian kept
    /// for the whole run (the constant `K`, `D` of the mass-matrix form) are
    /// fetched again at the next update.
    fn system_changed(&mut self) {}
}

/// Maps a system error to an [`IntegrateError`].
pub(crate) fn sys_err(
    t: f64,
    h: f64,
    what: &'static str,
) -> impl FnOnce(SystemError) -> IntegrateError {
    move |source| IntegrateError::System { t, h, what, source }
}
