//! Projection of a state onto the closures (docs/theory.md D121): what an
//! integrator may call after an accepted step so that a loop held only by
//! Baumgarte's stabilization (D67–D68) does not drift apart over a long or
//! loosely toleranced run.

use super::forward::{kept_solve, pivoted_cholesky};
use super::queries::{check_workspace, closure_norm, length_scale};
use super::rows::{assemble, prescribed_columns};
use crate::algorithms::Motion;
use crate::algorithms::check_vec;
use crate::algorithms::shifted::tree_solve;
use crate::algorithms::tree::forward_dynamics as tree_forward_dynamics;
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::{ClosureWork, Data};
use crate::model::tree::Tree;

/// What [`project_onto_closures`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosureProjection {
    /// Newton iterations on the positions (0: the closures held within the
    /// tolerance already).
    pub iterations: usize,
    /// The largest closure residual norm (D66) \[m\] before.
    pub residual_before: f64,
    /// The same after (at the returned `q`).
    pub residual_after: f64,
    /// Whether the positions met the tolerance. When they did not, `q` and
    /// `q̇` are left as they were.
    pub converged: bool,
}

/// Newton iterations allowed on the positions before giving up.
const MAX_ITERATIONS: usize = 20;
/// Halvings of a correction that did not decrease the residual, over the
/// whole projection.
const MAX_HALVINGS: usize = 30;

/// Projects `(q, q̇)` onto the closures at time `t` in the metric of the
/// mass matrix (docs/theory.md D121):
/// `q ← q − M⁻¹Jᵀ(J M⁻¹ Jᵀ)⁻¹ φ(q)` (Newton, `J = ∂φ/∂q` exact, `M` at
/// each iterate; a correction that does not decrease the largest norm is
/// halved) until every closure's residual norm (D66) is at most
/// `tol` \[m\], then `q̇ ← q̇ − M⁻¹J_vᵀ(J_v M⁻¹ J_vᵀ)⁻¹(J_v q̇ + J_p q̇_p)`,
/// so the closures' velocity rows vanish with the prescribed joints' motion
/// at `t` (D59). Both are the smallest changes in kinetic-energy measure:
/// the closest state on the constraint manifold that the motion could have
/// reached. Redundant rows are dropped as in the constrained dynamics (the
/// pivoted Cholesky of D68). `M⁻¹` is the tree's O(N) factorization
/// (`m` solves per iteration), so a projection costs a few forward
/// dynamics. A model without closures is left alone. Allocates nothing
/// (the closure workspace of `data`; the multipliers that
/// [`closure_multipliers`](crate::closure_multipliers) reports are those of
/// the next constrained forward dynamics, not the last one's).
pub fn project_onto_closures(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &mut [f64],
    qd: &mut [f64],
    tol: f64,
) -> Result<ClosureProjection, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qd", qd)?;
    let (Some(tree), true) = (&model.tree, model.has_closures()) else {
        return Ok(ClosureProjection {
            iterations: 0,
            residual_before: 0.0,
            residual_after: 0.0,
            converged: true,
        });
    };
    check_workspace(model, data)?;
    model.set_time(data, t);
    let Some(mut w) = data.closure.take() else {
        unreachable!("check_workspace found the closure buffers")
    };
    let out = project_inner(model, tree, data, &mut w, t, q, qd, tol);
    data.closure = Some(w);
    out
}

#[allow(clippy::too_many_arguments)]
fn project_inner(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    w: &mut ClosureWork,
    t: f64,
    q: &mut [f64],
    qd: &mut [f64],
    tol: f64,
) -> Result<ClosureProjection, DynamicsError> {
    let n = q.len();
    let largest = |w: &ClosureWork| {
        model
            .closures
            .iter()
            .map(|rc| closure_norm(model, rc, &w.rows.phi))
            .fold(0.0, f64::max)
    };
    // The start waits in `scratch` (n entries, free here) in case Newton
    // does not converge.
    w.scratch.as_mut_slice()[..n].copy_from_slice(q);
    let mut iterations = 0;
    let mut halvings = 0;
    let mut before = f64::NAN;
    let mut last = f64::INFINITY;
    let after = loop {
        // The factorization of M that the articulated forward dynamics
        // leaves per node (as in the constrained dynamics, D67; its q̈ is
        // not used), and the rows at q. A trial that fails there (a piece
        // bent beyond what its inertia can be factored at) counts as no
        // decrease.
        let motion = Motion::new(q, Some(qd), None);
        let norm = match tree_forward_dynamics(model, tree, data, Forces::ALL, t, motion, None) {
            Ok(()) => {
                assemble(model, tree, data, Motion::at_rest(q), true, &mut w.rows);
                largest(w)
            }
            Err(e) if iterations == 0 => return Err(e),
            Err(_) => f64::INFINITY,
        };
        if iterations == 0 {
            if !norm.is_finite() {
                return Err(DynamicsError::NotFinite {
                    what: "closure residual before the projection".into(),
                    value: norm,
                });
            }
            before = norm;
        }
        if norm <= tol {
            break norm;
        }
        if norm >= last || norm.is_nan() {
            // Backtracking: half of the last correction, from where it
            // started (a plain Newton step overshoots from far off, where
            // the soft strains make φ strongly nonlinear).
            if halvings < MAX_HALVINGS {
                halvings += 1;
                w.step *= 0.5;
                let mut qv = nalgebra::DVectorViewMut::from_slice(q, n);
                qv -= &w.step;
                continue;
            }
        }
        if iterations == MAX_ITERATIONS || halvings == MAX_HALVINGS {
            q.copy_from_slice(&w.scratch.as_slice()[..n]);
            return Ok(ClosureProjection {
                iterations,
                residual_before: before,
                residual_after: norm,
                converged: false,
            });
        }
        last = norm;
        w.rhs.copy_from(&w.rows.phi);
        correct(tree, data, w);
        let mut qv = nalgebra::DVectorViewMut::from_slice(q, n);
        qv += &w.step;
        iterations += 1;
    };
    // Velocities at the projected q (the factorization and the rows' pass
    // are of this q): the velocity rows, and the drive's part.
    assemble(model, tree, data, Motion::at_rest(q), false, &mut w.rows);
    let qdv = nalgebra::DVectorView::from_slice(qd, n);
    w.rhs.gemv(1.0, &w.rows.jac, &qdv, 0.0);
    if model.n_prescribed() > 0 {
        prescribed_columns(model, tree, data, Motion::at_rest(q), &mut w.jac_p);
        w.rhs.gemv(1.0, &w.jac_p, &data.prescribed_qd, 1.0);
    }
    correct(tree, data, w);
    let mut qdv = nalgebra::DVectorViewMut::from_slice(qd, n);
    qdv += &w.step;
    Ok(ClosureProjection {
        iterations,
        residual_before: before,
        residual_after: after,
        converged: true,
    })
}

/// `w.step = −Y A⁺ w.rhs` with `Y = M⁻¹Jᵀ`, `A = J Y` for the rows
/// `J = w.rows.jac` and the factorization of `M` in `data`; `A⁺` solves on
/// the independent pivots (D68), the redundant rows' part zero.
// Triangular solves read clearest with explicit indices.
#[allow(clippy::needless_range_loop)]
fn correct(tree: &Tree, data: &Data, w: &mut ClosureWork) {
    let m = w.rows.phi.len();
    let n = w.step.len();
    for c in 0..m {
        for i in 0..n {
            w.y[(i, c)] = w.rows.jac[(c, i)];
        }
        let mut col = w.y.column_mut(c);
        tree_solve(tree, data, &mut w.solve, col.as_mut_slice());
    }
    w.a.gemm(1.0, &w.rows.jac, &w.y, 0.0);
    let r = pivoted_cholesky(&mut w.a, &mut w.perm);
    for i in 0..m {
        w.lambda[i] = w.rhs[w.perm[i]];
    }
    kept_solve(&w.a, r, w.lambda.as_mut_slice());
    w.rhs.fill(0.0);
    for i in 0..r {
        w.rhs[w.perm[i]] = w.lambda[i];
    }
    w.step.gemv(-1.0, &w.y, &w.rhs, 0.0);
}

/// The default position tolerance of a projection for `model`: `1e-11 ℓ`
/// (ℓ its longest rod), the closed statics' (D69).
pub fn projection_tolerance(model: &Model) -> f64 {
    1e-11 * length_scale(model)
}
