//! The constrained forward dynamics (docs/theory.md §11, D67–D68):
//! Lagrange multipliers on top of the tree's forward dynamics,
//! Baumgarte-stabilized, with `M⁻¹Jᵀ` from the O(N) solves of the tree's
//! articulated factorization.

use super::queries::check_workspace;
use super::rows::{assemble, prescribed_columns};
use crate::algorithms::Motion;
use crate::algorithms::Pass;
use crate::algorithms::contact::prescribed_share;
use crate::algorithms::contact_force;
use crate::algorithms::shifted::tree_solve;
use crate::algorithms::tree::{self, outward};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::{ClosureWork, Data};
use nalgebra::DMatrix;

/// Relative pivot threshold of the pivoted Cholesky of `J M⁻¹ Jᵀ` (D68):
/// a pivot below `1e-10 ×` the largest diagonal is a redundant constraint.
pub(crate) const RANK_TOLERANCE: f64 = 1e-10;

/// `L Lᵀ x = x` on the first `r` entries (the kept rows, in pivot order)
/// with the factor [`pivoted_cholesky`] left in the lower triangle of `l`.
// Triangular solves read clearest with explicit indices.
#[allow(clippy::needless_range_loop)]
pub(crate) fn kept_solve(l: &DMatrix<f64>, r: usize, x: &mut [f64]) {
    for i in 0..r {
        let mut s = x[i];
        for k in 0..i {
            s -= l[(i, k)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
    for i in (0..r).rev() {
        let mut s = x[i];
        for k in i + 1..r {
            s -= l[(k, i)] * x[k];
        }
        x[i] = s / l[(i, i)];
    }
}

/// Pivoted Cholesky of the symmetric positive semidefinite `a` in place
/// (lower triangle, symmetric row/column swaps recorded in `perm`);
/// returns the numerical rank.
pub(crate) fn pivoted_cholesky(a: &mut DMatrix<f64>, perm: &mut [usize]) -> usize {
    let m = a.nrows();
    for (i, p) in perm.iter_mut().enumerate() {
        *p = i;
    }
    let dmax = (0..m).map(|i| a[(i, i)]).fold(0.0, f64::max);
    let tol = RANK_TOLERANCE * dmax;
    for k in 0..m {
        let (p, &dp) = (k..m)
            .map(|i| (i, &a[(i, i)]))
            .max_by(|x, y| x.1.total_cmp(y.1))
            .expect("k < m");
        if dp.is_nan() || dp <= tol {
            return k;
        }
        if p != k {
            a.swap_rows(p, k);
            a.swap_columns(p, k);
            perm.swap(p, k);
        }
        let d = a[(k, k)].sqrt();
        a[(k, k)] = d;
        for i in k + 1..m {
            a[(i, k)] /= d;
        }
        for j in k + 1..m {
            for i in j..m {
                let v = a[(i, j)] - a[(i, k)] * a[(j, k)];
                a[(i, j)] = v;
                a[(j, i)] = v;
            }
        }
    }
    m
}

/// Constrained forward dynamics (D67–D68), after the free `q̈` is in
/// `data.qdd`: `q̈ = q̈_free + M⁻¹Jᵀλ` with
/// `(J M⁻¹ Jᵀ) λ = −(J q̈_free + J̇q̇) − 2α J q̇ − β² φ`, the free `q̈`
/// under `τ_act` plus the contact force `τ_c` (CT16).
/// Arguments checked by the caller, the prescribed joints set to `t`.
pub(crate) fn forward_dynamics(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    check_workspace(model, data)?;
    let Some(mut w) = data.closure.take() else {
        unreachable!("check_workspace found the closure buffers")
    };
    // Contact (docs/theory-contact.md CT16): its generalized force joins
    // τ_act in the open tree's forward dynamics, before the projection —
    // the multipliers then see it like any other applied force. It runs
    // first: on a tree its outward sweep rewrites the node data the
    // articulated pass below then sets.
    let out = if contact_force(model, data, forces, t, q, Some(qd)) {
        let mut cw = data.contact.take().expect("contact work");
        match tau_act {
            Some(ta) => cw.tau_total.as_mut_slice().copy_from_slice(ta),
            None => cw.tau_total.fill(0.0),
        }
        cw.tau_total += &cw.tau;
        let total = Some(cw.tau_total.as_slice());
        let out = forward_inner(model, data, &mut w, forces, t, (q, qd), total);
        if out.is_ok() && model.n_prescribed() > 0 {
            // The drives hold the rods against the contact forces too
            // (CT18), on top of the closures' share.
            prescribed_share(model, data, &mut cw, q);
            data.prescribed_force -= &cw.tau_p;
        }
        data.contact = Some(cw);
        out
    } else {
        forward_inner(model, data, &mut w, forces, t, (q, qd), tau_act)
    };
    data.closure = Some(w);
    out
}

// Triangular solves read clearest with explicit indices.
#[allow(clippy::needless_range_loop)]
fn forward_inner(
    model: &Model,
    data: &mut Data,
    w: &mut ClosureWork,
    forces: Forces,
    t: f64,
    (q, qd): (&[f64], &[f64]),
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    let Some(tree) = &model.tree else {
        unreachable!("closures live on the tree")
    };
    let m = model.n_constraints();
    let motion = Motion::new(q, Some(qd), None);
    // Articulated outward pass: velocities and the velocity-product
    // accelerations (q̈ = 0, no gravity) that J̇q̇ needs.
    outward(model, tree, data, motion, Pass::Articulated, forces);
    assemble(model, tree, data, motion, false, &mut w.rows);
    tree::forward_dynamics(model, tree, data, forces, t, motion, tau_act)?;
    // Y = M⁻¹Jᵀ column by column: the articulated inward pass of the
    // forward dynamics just left the factorization of M in `data` (the
    // shifted solve's with a = b = 0), so each column is one O(N)
    // bias-free sweep, not a dense Cholesky of M.
    for c in 0..m {
        for i in 0..q.len() {
            w.y[(i, c)] = w.rows.jac[(c, i)];
        }
        let mut col = w.y.column_mut(c);
        tree_solve(tree, data, &mut w.solve, col.as_mut_slice());
    }
    w.a.gemm(1.0, &w.rows.jac, &w.y, 0.0);
    let rate = model.baumgarte;
    // rhs = −(J q̈_free + J̇q̇) − 2α J q̇ − β² φ (α = β = rate).
    w.rhs.gemv(-1.0, &w.rows.jac, &data.qdd, 0.0);
    let qdv = nalgebra::DVectorView::from_slice(qd, qd.len());
    w.rhs.gemv(-2.0 * rate, &w.rows.jac, &qdv, 1.0);
    let driven = model.n_prescribed() > 0;
    if driven {
        // φ̇ = J q̇ + J_p q̇_p: the drive moves the frames too (D62 of the
        // path, D59). J̇q̇ above is the frames' acceleration at q̈ = 0, which
        // already holds the drive's acceleration.
        prescribed_columns(model, tree, data, motion, &mut w.jac_p);
        w.rhs.gemv(-2.0 * rate, &w.jac_p, &data.prescribed_qd, 1.0);
    }
    w.rhs -= &w.rows.jdot_qd;
    w.rhs.axpy(-rate * rate, &w.rows.phi, 1.0);
    w.rank = pivoted_cholesky(&mut w.a, &mut w.perm);
    let r = w.rank;
    let x = &mut w.scratch.as_mut_slice()[..m];
    for i in 0..m {
        x[i] = w.rhs[w.perm[i]];
    }
    // L₁₁ L₁₁ᵀ x₁ = b₁ on the independent rows; the redundant rows get
    // λ = 0 (consistent redundant constraints hold through the others).
    kept_solve(&w.a, r, x);
    w.lambda.fill(0.0);
    for i in 0..r {
        w.lambda[w.perm[i]] = x[i];
    }
    data.qdd.gemv(1.0, &w.y, &w.lambda, 1.0);
    if driven {
        // The drive's force at the constrained motion: what the open tree
        // needs there, less the closures' share `J_pᵀλ` (D60).
        w.qdd.copy_from(&data.qdd);
        let moving = Motion::new(q, Some(qd), Some(w.qdd.as_slice()));
        tree::inverse_dynamics(model, tree, data, forces, t, moving);
        data.prescribed_force
            .gemv_tr(-1.0, &w.jac_p, &w.lambda, 1.0);
        data.qdd.copy_from(&w.qdd);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::{Attachment, Closure, ClosureFrame, ClosureKind, Data, Joint, Rod};
    use nalgebra::DVector;
    use softrod_lie::{Pose, Vec3};
    use softrod_mechanics::Material;

    #[test]
    fn constrained_acceleration_satisfies_the_stabilized_rows() {
        let mat = Material::builder()
            .density(1000.0)
            .young(1e6)
            .poisson(0.5)
            .build()
            .unwrap();
        let rod = |n: &str, l: f64| Rod::builder(l).name(n).pieces(2).circle(0.01).material(mat);
        let model = crate::Model::builder()
            .rod_on(
                rod("a", 0.3),
                Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.2])),
            )
            .rod_on(rod("c", 0.25), Attachment::world_joint(Joint::free()))
            .gravity([0.0, 0.0, -9.81])
            .closure(Closure::new(
                "t",
                ClosureKind::Ball,
                ClosureFrame::on("a", Some(0.13), Pose::identity()),
                ClosureFrame::on(
                    "c",
                    None,
                    Pose::new(softrod_lie::Mat3::identity(), Vec3::new(0.0, 0.02, -0.01)),
                ),
            ))
            .build()
            .unwrap();
        let mut data = Data::new(&model);
        let n = model.n_dof();
        let q: Vec<f64> = (0..n).map(|i| 0.3 * ((i as f64) * 1.7).sin()).collect();
        let qd: Vec<f64> = (0..n)
            .map(|i| 0.5 * ((i as f64) * 2.3 + 1.0).cos())
            .collect();
        let qdd = crate::forward_dynamics(&model, &mut data, 0.0, &q, &qd, None)
            .unwrap()
            .clone();
        let w = data.closure.as_ref().unwrap();
        let rate = model.baumgarte;
        let lhs = &w.rows.jac * &qdd
            + &w.rows.jdot_qd
            + &w.rows.jac * DVector::from_column_slice(&qd) * (2.0 * rate)
            + &w.rows.phi * (rate * rate);
        assert!(
            lhs.amax() < 1e-8 * (&w.rows.jac * &qdd).amax(),
            "{lhs} rank {}",
            w.rank
        );
    }
}
