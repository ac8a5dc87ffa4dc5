//! Dynamics, statics and modes of a model with loop closures
//! (docs/theory.md §11, D67–D69): Lagrange multipliers on top of the tree
//! dynamics, Baumgarte-stabilized; the constrained equilibrium by Newton on
//! `[τ(q) − Jᵀλ; φ(q)] = 0`; modes on the null space of `J`.

use crate::closure::{assemble, closure_norm, length_scale};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::matrices::stiffness_matrix;
use crate::model::Model;
use crate::model::data::{ClosureWork, Data};
use crate::model::tree::Tree;
use crate::modes::Modes;
use crate::statics::{StaticsOptions, StaticsResult};
use crate::tree_algorithms::{TreePass, outward};
use nalgebra::{DMatrix, DVector};

/// Relative pivot threshold of the pivoted Cholesky of `J M⁻¹ Jᵀ` (D68):
/// a pivot below `1e-10 ×` the largest diagonal is a redundant constraint.
pub(crate) const RANK_TOLERANCE: f64 = 1e-10;

/// Pivoted Cholesky of the symmetric positive semidefinite `a` in place
/// (lower triangle, symmetric row/column swaps recorded in `perm`);
/// returns the numerical rank.
fn pivoted_cholesky(a: &mut DMatrix<f64>, perm: &mut [usize]) -> usize {
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
/// `(J M⁻¹ Jᵀ) λ = −(J q̈_free + J̇q̇) − 2α J q̇ − β² φ`.
pub(crate) fn forward_dynamics(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    crate::closure::check_workspace(model, data)?;
    let Some(mut w) = data.closure.take() else {
        unreachable!("check_workspace found the closure buffers")
    };
    let out = forward_inner(model, tree, data, &mut w, forces, t, q, qd, tau_act);
    data.closure = Some(w);
    out
}

// Triangular solves read clearest with explicit indices.
#[allow(clippy::too_many_arguments, clippy::needless_range_loop)]
fn forward_inner(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    w: &mut ClosureWork,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    let m = model.n_constraints();
    // Articulated outward pass: velocities and the velocity-product
    // accelerations (q̈ = 0, no gravity) that J̇q̇ needs.
    outward(
        model,
        tree,
        data,
        q,
        Some(qd),
        None,
        TreePass::Articulated,
        forces,
    );
    assemble(
        model,
        tree,
        data,
        q,
        Some(qd),
        false,
        &mut w.phi,
        &mut w.jac,
        &mut w.jdot_qd,
    );
    crate::tree_algorithms::forward_dynamics(model, tree, data, forces, t, q, qd, tau_act)?;
    // Y = M⁻¹Jᵀ column by column: the articulated inward pass of the
    // forward dynamics just left the factorization of M in `data` (the
    // shifted solve's with a = b = 0), so each column is one O(N)
    // bias-free sweep, not a dense Cholesky of M.
    for c in 0..m {
        for i in 0..q.len() {
            w.y[(i, c)] = w.jac[(c, i)];
        }
        let mut col = w.y.column_mut(c);
        crate::tree_algorithms::shifted_solve(tree, data, &mut w.solve, col.as_mut_slice());
    }
    w.a.gemm(1.0, &w.jac, &w.y, 0.0);
    let rate = model.baumgarte;
    // rhs = −(J q̈_free + J̇q̇) − 2α J q̇ − β² φ (α = β = rate).
    w.rhs.gemv(-1.0, &w.jac, &data.qdd, 0.0);
    let qdv = nalgebra::DVectorView::from_slice(qd, qd.len());
    w.rhs.gemv(-2.0 * rate, &w.jac, &qdv, 1.0);
    let driven = model.n_prescribed() > 0;
    if driven {
        // φ̇ = J q̇ + J_p q̇_p: the drive moves the frames too (D62 of the
        // path, D59). J̇q̇ above is the frames' acceleration at q̈ = 0, which
        // already holds the drive's acceleration.
        crate::closure::prescribed_columns(model, tree, data, q, Some(qd), &mut w.jac_p);
        w.rhs.gemv(-2.0 * rate, &w.jac_p, &data.prescribed_qd, 1.0);
    }
    w.rhs -= &w.jdot_qd;
    w.rhs.axpy(-rate * rate, &w.phi, 1.0);
    w.rank = pivoted_cholesky(&mut w.a, &mut w.perm);
    let r = w.rank;
    let x = &mut w.scratch.as_mut_slice()[..m];
    for i in 0..m {
        x[i] = w.rhs[w.perm[i]];
    }
    // L₁₁ L₁₁ᵀ x₁ = b₁ on the independent rows; the redundant rows get
    // λ = 0 (consistent redundant constraints hold through the others).
    for i in 0..r {
        let mut s = x[i];
        for k in 0..i {
            s -= w.a[(i, k)] * x[k];
        }
        x[i] = s / w.a[(i, i)];
    }
    for i in (0..r).rev() {
        let mut s = x[i];
        for k in i + 1..r {
            s -= w.a[(k, i)] * x[k];
        }
        x[i] = s / w.a[(i, i)];
    }
    w.lambda.fill(0.0);
    for i in 0..r {
        w.lambda[w.perm[i]] = x[i];
    }
    data.qdd.gemv(1.0, &w.y, &w.lambda, 1.0);
    if driven {
        // The drive's force at the constrained motion: what the open tree
        // needs there, less the closures' share `J_pᵀλ` (D60).
        w.qdd.copy_from(&data.qdd);
        crate::tree_algorithms::inverse_dynamics(
            model,
            tree,
            data,
            forces,
            t,
            q,
            Some(qd),
            Some(w.qdd.as_slice()),
        );
        data.prescribed_force
            .gemv_tr(-1.0, &w.jac_p, &w.lambda, 1.0);
        data.qdd.copy_from(&w.qdd);
    }
    Ok(())
}

/// What the constrained Newton (D69) evaluates, at one load scale: the
/// open tree's static force under `forces` and the closures' rows.
#[derive(Clone, Copy)]
struct Closed<'a> {
    model: &'a Model,
    tree: &'a Tree,
    /// Time of the cable tensions and of the prescribed joints' values \[s\].
    t: f64,
    /// The forces of the static evaluations (drives at rest).
    forces: Forces,
}

impl Closed<'_> {
    /// `τ(q) = ID(q, 0, 0)` of the tree under `forces`, ignoring the closures.
    fn static_force(&self, data: &mut Data, q: &[f64]) -> DVector<f64> {
        let zero = vec![0.0; q.len()];
        crate::tree_algorithms::inverse_dynamics(
            self.model,
            self.tree,
            data,
            self.forces,
            self.t,
            q,
            Some(&zero),
            Some(&zero),
        );
        data.tau.clone()
    }

    /// `φ(q)` and the constraint Jacobian: exact `∂φ/∂q` or velocity rows.
    fn phi_jac(&self, data: &mut Data, q: &[f64], exact: bool) -> (DVector<f64>, DMatrix<f64>) {
        let m = self.model.n_constraints();
        let mut phi = DVector::zeros(m);
        let mut jac = DMatrix::zeros(m, q.len());
        let mut jd = DVector::zeros(m);
        outward(
            self.model,
            self.tree,
            data,
            q,
            None,
            None,
            TreePass::Composite,
            Forces::ALL,
        );
        assemble(
            self.model, self.tree, data, q, None, exact, &mut phi, &mut jac, &mut jd,
        );
        (phi, jac)
    }

    /// Top residual `τ(q) − J_vᵀλ` (velocity rows: `J_vᵀλ` is the
    /// generalized force of the constraint wrenches `λ`).
    fn force_residual(&self, data: &mut Data, q: &[f64], lambda: &DVector<f64>) -> DVector<f64> {
        let tau = self.static_force(data, q);
        let (_, jv) = self.phi_jac(data, q, false);
        tau - jv.transpose() * lambda
    }

    /// `∂(τ − J_vᵀλ)/∂q`: `K` exact plus central differences of the rest.
    fn tangent(
        &self,
        data: &mut Data,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
        k: &DMatrix<f64>,
    ) -> DMatrix<f64> {
        let n = q.len();
        let mut jac = k.clone();
        let mut qp = q.clone();
        for j in 0..n {
            let h = 6e-6 * q[j].abs().max(1.0);
            qp[j] = q[j] + h;
            let plus = self.force_residual(data, qp.as_slice(), lambda);
            qp[j] = q[j] - h;
            let minus = self.force_residual(data, qp.as_slice(), lambda);
            qp[j] = q[j];
            for i in 0..n {
                jac[(i, j)] += (plus[i] - minus[i]) / (2.0 * h) - k[(i, j)];
            }
        }
        jac
    }

    /// Least-squares multipliers `λ = argmin ‖τ − J_vᵀλ‖` at `q`.
    fn multipliers(&self, data: &mut Data, q: &[f64]) -> DVector<f64> {
        let tau = self.static_force(data, q);
        let (_, jv) = self.phi_jac(data, q, false);
        let jt = jv.transpose();
        jt.svd(true, true)
            .solve(&tau, 1e-12)
            .unwrap_or_else(|_| DVector::zeros(self.model.n_constraints()))
    }
}

/// Constrained statics (D69): Newton on `F(q, λ) = [τ(q) − J_vᵀλ; φ(q)] = 0`
/// with the KKT matrix `[[∂F₁/∂q, −J_vᵀ], [J, 0]]`, a backtracking line
/// search on the scaled `‖F‖` and load continuation as [`crate::statics`]
/// (the loads scaled by `λ_s` of [`Forces::at_rest`], drives at rest).
pub(crate) fn statics(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q0: &[f64],
    options: &StaticsOptions,
) -> Result<(StaticsResult, DVector<f64>), DynamicsError> {
    let n = model.n_dof();
    let m = model.n_constraints();
    let k = stiffness_matrix(model);
    let ell = length_scale(model).max(f64::MIN_POSITIVE);
    let phi_tol = Model::CLOSURE_TOLERANCE * ell * 1e-2;
    let at = |scale: f64| Closed {
        model,
        tree,
        t: options.time,
        forces: Forces::at_rest(scale),
    };
    let full = at(1.0);
    let mut q = DVector::from_column_slice(q0);
    let r_full = full.static_force(data, q0).amax();
    let f_ref = r_full.max(f64::MIN_POSITIVE);
    let mut iterations = 0;
    // Scaled merit: forces relative to f_ref, residuals relative to ℓ.
    let merit = |r: &DVector<f64>, p: &DVector<f64>| (r.amax() / f_ref).max(p.amax() / ell);
    let solve = |cx: Closed,
                 data: &mut Data,
                 q: &mut DVector<f64>,
                 lam: &mut DVector<f64>,
                 iterations: &mut usize|
     -> Result<Result<f64, f64>, DynamicsError> {
        let mut r = cx.force_residual(data, q.as_slice(), lam);
        let (mut p, _) = cx.phi_jac(data, q.as_slice(), true);
        for _ in 0..options.max_iterations {
            let tol = options.tolerance * f_ref.max((&k * &*q).amax());
            if r.amax() <= tol && p.amax() <= phi_tol {
                return Ok(Ok(r.amax()));
            }
            *iterations += 1;
            let kt = cx.tangent(data, q, lam, &k);
            let (_, jv) = cx.phi_jac(data, q.as_slice(), false);
            let (_, je) = cx.phi_jac(data, q.as_slice(), true);
            let mut kkt = DMatrix::zeros(n + m, n + m);
            kkt.view_mut((0, 0), (n, n)).copy_from(&kt);
            kkt.view_mut((0, n), (n, m)).copy_from(&(-jv.transpose()));
            kkt.view_mut((n, 0), (m, n)).copy_from(&je);
            let mut rhs = DVector::zeros(n + m);
            rhs.rows_mut(0, n).copy_from(&(-&r));
            rhs.rows_mut(n, m).copy_from(&(-&p));
            let Some(dz) = kkt.lu().solve(&rhs) else {
                return Ok(Err(r.amax()));
            };
            if dz.iter().any(|v| !v.is_finite()) {
                return Ok(Err(r.amax()));
            }
            let f0 = merit(&r, &p);
            let mut alpha = 1.0;
            loop {
                let qt = &*q + dz.rows(0, n) * alpha;
                let lt = &*lam + dz.rows(n, m) * alpha;
                let rt = cx.force_residual(data, qt.as_slice(), &lt);
                let (pt, _) = cx.phi_jac(data, qt.as_slice(), true);
                let ok = rt.iter().chain(pt.iter()).all(|v| v.is_finite());
                if ok && (merit(&rt, &pt) < (1.0 - 1e-4 * alpha) * f0 || merit(&rt, &pt) <= 1e-14) {
                    *q = qt;
                    *lam = lt;
                    r = rt;
                    p = pt;
                    break;
                }
                alpha *= 0.5;
                if alpha < 1e-6 {
                    let tol = options.tolerance * f_ref.max((&k * &*q).amax());
                    return Ok(if r.amax() <= 1e3 * tol && p.amax() <= phi_tol {
                        Ok(r.amax())
                    } else {
                        Err(r.amax())
                    });
                }
            }
        }
        let tol = options.tolerance * f_ref.max((&k * &*q).amax());
        Ok(if r.amax() <= tol && p.amax() <= phi_tol {
            Ok(r.amax())
        } else {
            Err(r.amax())
        })
    };
    let mut lam = full.multipliers(data, q0);
    let start = (q.clone(), lam.clone());
    if let Ok(res) = solve(full, data, &mut q, &mut lam, &mut iterations)? {
        return Ok((
            StaticsResult {
                q,
                iterations,
                residual: res,
                load_steps: 1,
            },
            lam,
        ));
    }
    // Load continuation from the unloaded state.
    let (mut q_prev, mut l_prev) = start;
    l_prev.fill(0.0);
    if solve(at(0.0), data, &mut q_prev, &mut l_prev, &mut iterations)?.is_err() {
        return Err(DynamicsError::StaticsFailed {
            reason: "no constrained equilibrium even without loads (do the closures hold, \
                     are they redundant?)"
                .into(),
            load_fraction: 0.0,
            iterations,
            residual: f64::NAN,
        });
    }
    let (mut lam_s, mut step, mut steps, mut last) = (0.0, 0.25, 0, 0.0);
    while lam_s < 1.0 {
        if steps >= options.max_load_steps || step < 1e-5 {
            return Err(DynamicsError::StaticsFailed {
                reason: "constrained load continuation stalled".into(),
                load_fraction: lam_s,
                iterations,
                residual: last,
            });
        }
        steps += 1;
        let target = (lam_s + step).min(1.0);
        let (mut qt, mut lt) = (q_prev.clone(), l_prev.clone());
        match solve(at(target), data, &mut qt, &mut lt, &mut iterations)? {
            Ok(res) => {
                lam_s = target;
                q_prev = qt;
                l_prev = lt;
                last = res;
                step *= 1.5;
            }
            Err(_) => step *= 0.5,
        }
    }
    Ok((
        StaticsResult {
            q: q_prev,
            iterations,
            residual: last,
            load_steps: steps,
        },
        l_prev,
    ))
}

/// Modes of the constrained system (D69) about `q_eq`: `K_eff` and `M`
/// restricted to an orthonormal basis `Z` of the null space of `J(q_eq)`
/// (from its SVD, rank at `1e-10` of the largest singular value); the
/// prescribed joints held at rest at their values at `time`.
pub(crate) fn modes(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q_eq: &[f64],
    time: f64,
) -> Result<Modes, DynamicsError> {
    let n = model.n_dof();
    let k = stiffness_matrix(model);
    let cx = Closed {
        model,
        tree,
        t: time,
        forces: Forces::at_rest(1.0),
    };
    let lam = cx.multipliers(data, q_eq);
    let q = DVector::from_column_slice(q_eq);
    let keff = cx.tangent(data, &q, &lam, &k);
    let asym = (&keff - keff.transpose()).norm() / keff.norm().max(f64::MIN_POSITIVE);
    let ksym = (&keff + keff.transpose()) * 0.5;
    let (_, je) = cx.phi_jac(data, q_eq, true);
    let z = null_space(&je, n);
    crate::tree_algorithms::mass_matrix(model, tree, data, q_eq);
    let mr = z.transpose() * &data.mass * &z;
    let kr = z.transpose() * ksym * &z;
    let l = mr
        .cholesky()
        .ok_or(DynamicsError::NotPositiveDefinite {
            what: "mass matrix on the closures' null space",
        })?
        .l();
    let linv = l.try_inverse().ok_or(DynamicsError::NotPositiveDefinite {
        what: "mass matrix on the closures' null space (singular factor)",
    })?;
    let c = &linv * kr * linv.transpose();
    let c = (&c + c.transpose()) * 0.5;
    let eig = c.symmetric_eigen();
    let nr = z.ncols();
    let mut order: Vec<usize> = (0..nr).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let mut omega = DVector::zeros(nr);
    let mut shapes = DMatrix::zeros(n, nr);
    let back = &z * linv.transpose();
    for (i, &o) in order.iter().enumerate() {
        let w2 = eig.eigenvalues[o];
        omega[i] = w2.signum() * w2.abs().sqrt();
        shapes.set_column(i, &(&back * eig.eigenvectors.column(o)));
    }
    if let Some((i, &value)) = omega.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!("angular frequency of constrained mode {i} [rad/s]"),
            value,
        });
    }
    Ok(Modes {
        omega,
        shapes,
        asymmetry: asym,
    })
}

/// Orthonormal basis (n×(n−r)) of the null space of `j` (m×n): the rank
/// `r` from the singular values of `j` (above `1e-10` of the largest), the
/// basis from the eigenvectors of `JᵀJ` with the `n − r` smallest
/// eigenvalues.
fn null_space(j: &DMatrix<f64>, n: usize) -> DMatrix<f64> {
    if j.nrows() == 0 {
        return DMatrix::identity(n, n);
    }
    let sv = j.singular_values();
    let smax = sv.iter().fold(0.0_f64, |a, &b| a.max(b));
    let rank = sv.iter().filter(|&&s| s > 1e-10 * smax).count();
    let eig = (j.transpose() * j).symmetric_eigen();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let cols = &order[..n - rank];
    DMatrix::from_fn(n, cols.len(), |r, c| eig.eigenvectors[(r, cols[c])])
}

/// Numerical rank of the closures' Jacobian at `q` (singular values above
/// `1e-10` of the largest): the net DoF of the closed model is
/// `n_dof − rank`.
pub fn constraint_rank(model: &Model, data: &mut Data, q: &[f64]) -> Result<usize, DynamicsError> {
    let j = crate::closure::constraint_jacobian(model, data, q)?;
    if j.nrows() == 0 {
        return Ok(0);
    }
    let sv = j.singular_values();
    let smax = sv.iter().fold(0.0_f64, |a, &b| a.max(b));
    Ok(sv.iter().filter(|&&s| s > 1e-10 * smax).count())
}

/// The constraint state of the last constrained [`crate::forward_dynamics`]
/// in `data`: multipliers `λ` (per closure rows; the wrench on frame a in
/// b's axes, angular first for welds) and the numerical rank of
/// `J M⁻¹ Jᵀ`. `None` for a model without closures.
pub fn closure_multipliers(data: &Data) -> Option<(&DVector<f64>, usize)> {
    data.closure.as_ref().map(|w| (&w.lambda, w.rank))
}

/// The largest closure residual norm (D66) at `q` \[m\].
pub fn max_closure_residual(
    model: &Model,
    data: &mut Data,
    q: &[f64],
) -> Result<f64, DynamicsError> {
    let phi = crate::closure::constraint_residual(model, data, q)?;
    Ok(model
        .closures
        .iter()
        .map(|rc| closure_norm(model, rc, &phi))
        .fold(0.0, f64::max))
}

/// [`crate::statics`] of a model with closures, with the multipliers `λ`
/// at the equilibrium (D69; per closure rows of `φ`: for a ball or slider
/// row the force on frame a's origin along that row's direction in b's
/// axes \[N\]; for a weld `(torque, force)` in b's axes, the torque rows
/// through `J_l(r)` — exactly the torque when the weld holds).
pub fn closure_statics(
    model: &Model,
    data: &mut Data,
    q0: &[f64],
    options: &StaticsOptions,
) -> Result<(StaticsResult, DVector<f64>), DynamicsError> {
    crate::algorithms::check_vec(model, "q0", q0)?;
    let Some(tree) = model.tree.as_ref().filter(|_| model.has_closures()) else {
        let r = crate::statics(model, data, q0, options)?;
        return Ok((r, DVector::zeros(0)));
    };
    crate::closure::check_workspace(model, data)?;
    statics(model, tree, data, q0, options)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Attachment, Closure, ClosureFrame, ClosureKind, Joint, RodSpec};
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
        let rod = |n: &str, l: f64| {
            RodSpec::builder(l)
                .name(n)
                .pieces(2)
                .circle(0.01)
                .material(mat)
        };
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
        let lhs = &w.jac * &qdd
            + &w.jdot_qd
            + &w.jac * DVector::from_column_slice(&qd) * (2.0 * rate)
            + &w.phi * (rate * rate);
        assert!(
            lhs.amax() < 1e-8 * (&w.jac * &qdd).amax(),
            "{lhs} rank {}",
            w.rank
        );
    }
}
