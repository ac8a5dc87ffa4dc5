//! Statics and modes of a model with loop closures (docs/theory.md §11,
//! D69): the constrained equilibrium by Newton on `[τ(q) − Jᵀλ; φ(q)] = 0`,
//! modes on the null space of `J`.

use super::matrices::stiffness_matrix;
use super::modes::{Modes, difference_noise, frequencies, mapped_noise};
use super::statics::{MAX_STIFFNESS_ROUNDS, StaticsOptions, StaticsResult};
use crate::algorithms::tree::{self, outward, outward_from};
use crate::algorithms::{Motion, Pass, contact_force};
use crate::constraints::derivatives::coordinate_order;
use crate::constraints::forward::pivoted_cholesky;
use crate::constraints::queries::{check_workspace, length_scale};
use crate::constraints::rows::assemble;
use crate::derivatives::{IdDerivatives, open_tree_id_derivatives};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::data::{ConstraintRows, Data};
use crate::model::tree::Tree;
use nalgebra::{DMatrix, DVector};

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
    /// `τ(q) = ID(q, 0, 0)` of the tree under `forces`, ignoring the
    /// closures, less the frictionless contact force at rest with the
    /// stiffness `data` holds (CT5, CT15; CT16).
    fn static_force(&self, data: &mut Data, q: &[f64]) -> DVector<f64> {
        let zero = vec![0.0; q.len()];
        let at_rest = Motion::new(q, Some(&zero), Some(&zero));
        // Contact first: its outward sweep rewrites the node data the
        // inverse dynamics' own sweep then sets.
        let contact = contact_force(self.model, data, self.forces, self.t, q, Some(&zero));
        tree::inverse_dynamics(self.model, self.tree, data, self.forces, self.t, at_rest);
        let mut tau = data.tau.clone();
        if contact {
            if let Some(w) = &data.contact {
                tau -= &w.tau;
            }
        }
        tau
    }

    /// `φ(q)` and the constraint Jacobian: exact `∂φ/∂q` or velocity rows.
    fn phi_jac(&self, data: &mut Data, q: &[f64], exact: bool) -> (DVector<f64>, DMatrix<f64>) {
        let mut rows = ConstraintRows::new(self.model.n_constraints(), q.len());
        let motion = Motion::at_rest(q);
        outward(
            self.model,
            self.tree,
            data,
            motion,
            Pass::Composite,
            Forces::ALL,
        );
        assemble(self.model, self.tree, data, motion, exact, &mut rows);
        (rows.phi, rows.jac)
    }

    /// Top residual `τ(q) − J_vᵀλ` (velocity rows: `J_vᵀλ` is the
    /// generalized force of the constraint wrenches `λ`).
    fn force_residual(&self, data: &mut Data, q: &[f64], lambda: &DVector<f64>) -> DVector<f64> {
        let tau = self.static_force(data, q);
        let (_, jv) = self.phi_jac(data, q, false);
        tau - jv.transpose() * lambda
    }

    /// `∂(τ − J_vᵀλ)/∂q`: `K` exact plus central differences of the
    /// rest; and the bound of the differences' round-off, entry by entry
    /// (for the rigid tolerance of the modes, docs/theory.md E7).
    fn tangent(
        &self,
        data: &mut Data,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
        k: &DMatrix<f64>,
    ) -> (DMatrix<f64>, DMatrix<f64>) {
        let n = q.len();
        let mut jac = k.clone();
        let mut qp = q.clone();
        let mut noise = DMatrix::zeros(n, n);
        for j in 0..n {
            let h = 6e-6 * q[j].abs().max(1.0);
            qp[j] = q[j] + h;
            let plus = self.force_residual(data, qp.as_slice(), lambda);
            qp[j] = q[j] - h;
            let minus = self.force_residual(data, qp.as_slice(), lambda);
            qp[j] = q[j];
            for i in 0..n {
                jac[(i, j)] += (plus[i] - minus[i]) / (2.0 * h) - k[(i, j)];
                noise[(i, j)] = difference_noise(plus[i], minus[i], h);
            }
        }
        (jac, noise)
    }

    /// `∂(τ − J_vᵀλ)/∂q` for Newton and the sensitivities: the open
    /// tree's `∂τ/∂q` analytic (D37–D47 at `q̇ = q̈ = 0`, under the
    /// evaluation's forces and `data`'s tensions and joint inputs) less
    /// central differences of `J_vᵀλ` alone at fixed `λ` (the closure
    /// rows: kinematics, no dynamics), as the closed dynamics' (CD3).
    /// With contact, [`Self::tangent`] (whose static force takes the
    /// frictionless contact at rest, which the derivatives do not).
    fn newton_tangent(
        &self,
        data: &mut Data,
        q: &DVector<f64>,
        lambda: &DVector<f64>,
        k: &DMatrix<f64>,
        work: &mut Option<IdDerivatives>,
    ) -> Result<DMatrix<f64>, DynamicsError> {
        if self.model.has_contact() {
            return Ok(self.tangent(data, q, lambda, k).0);
        }
        let n = q.len();
        let w = work.get_or_insert_with(|| IdDerivatives::new(self.model));
        w.copy_inputs(data);
        let zero = vec![0.0; n];
        open_tree_id_derivatives(
            self.model,
            w,
            self.forces,
            self.t,
            q.as_slice(),
            &zero,
            &zero,
        )?;
        let mut jac = w.dtau_dq.clone();
        // One kinematic sweep from the node that holds each coordinate,
        // deepest nodes first (the nodes before it are at `q`), as CD3.
        let order = coordinate_order(self.tree);
        let mut rows = ConstraintRows::new(self.model.n_constraints(), n);
        let (mut plus, mut minus) = (DVector::zeros(n), DVector::zeros(n));
        let mut qp = q.clone();
        let sweep = |data: &mut Data, qp: &DVector<f64>, from: usize| {
            let motion = Motion::at_rest(qp.as_slice());
            outward_from(
                self.model,
                self.tree,
                data,
                motion,
                Pass::Kinematic,
                Forces::ALL,
                from,
            );
        };
        sweep(data, &qp, 0);
        for &(node, j) in &order {
            let h = 6e-6 * q[j].abs().max(1.0);
            for (x, out) in [(q[j] + h, &mut plus), (q[j] - h, &mut minus)] {
                qp[j] = x;
                sweep(data, &qp, node);
                assemble(
                    self.model,
                    self.tree,
                    data,
                    Motion::at_rest(qp.as_slice()),
                    false,
                    &mut rows,
                );
                out.gemv_tr(1.0, &rows.jac, lambda, 0.0);
            }
            qp[j] = q[j];
            let mut col = jac.column_mut(j);
            col.axpy(-0.5 / h, &plus, 1.0);
            col.axpy(0.5 / h, &minus, 1.0);
        }
        sweep(data, &qp, 0);
        Ok(jac)
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

/// Constrained statics (D69) with contact stiffness raised to the loads
/// (CT15, CT16): `statics_once`, then, as long as a resting contact's
/// spring carries its force deeper than its target, the scales raised
/// and the equilibrium solved again from where it was (as the open
/// statics, at most `MAX_STIFFNESS_ROUNDS` rounds).
pub(crate) fn statics(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q0: &[f64],
    options: &StaticsOptions,
) -> Result<(StaticsResult, DVector<f64>), DynamicsError> {
    let (mut result, mut lambda) = statics_once(model, tree, data, q0, options)?;
    let mut rounds = 0;
    while model.has_contact()
        && rounds < MAX_STIFFNESS_ROUNDS
        && super::raise_for_rest(model, data, options.time, result.q.as_slice())
    {
        let (again, l) = statics_once(model, tree, data, result.q.as_slice(), options)?;
        result = StaticsResult {
            iterations: result.iterations + again.iterations,
            load_steps: result.load_steps.max(again.load_steps),
            ..again
        };
        lambda = l;
        rounds += 1;
    }
    Ok((result, lambda))
}

/// Constrained statics (D69) at the contact stiffness `data` holds:
/// Newton on `F(q, λ) = [τ(q) − J_vᵀλ; φ(q)] = 0`
/// with the KKT matrix `[[∂F₁/∂q, −J_vᵀ], [J, 0]]`, a backtracking line
/// search on the scaled `‖F‖` and load continuation as [`crate::statics`]
/// (the loads scaled by `λ_s` of [`Forces::at_rest`], drives at rest).
fn statics_once(
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
    let mut derivatives = None;
    // Scaled merit: forces relative to f_ref, residuals relative to ℓ.
    let merit = |r: &DVector<f64>, p: &DVector<f64>| (r.amax() / f_ref).max(p.amax() / ell);
    let solve = |cx: Closed,
                 data: &mut Data,
                 q: &mut DVector<f64>,
                 lam: &mut DVector<f64>,
                 iterations: &mut usize,
                 derivatives: &mut Option<IdDerivatives>|
     -> Result<Result<f64, f64>, DynamicsError> {
        let mut r = cx.force_residual(data, q.as_slice(), lam);
        let (mut p, _) = cx.phi_jac(data, q.as_slice(), true);
        for _ in 0..options.max_iterations {
            let tol = options.tolerance * f_ref.max((&k * &*q).amax());
            if r.amax() <= tol && p.amax() <= phi_tol {
                return Ok(Ok(r.amax()));
            }
            *iterations += 1;
            let kt = cx.newton_tangent(data, q, lam, &k, derivatives)?;
            let (_, jv) = cx.phi_jac(data, q.as_slice(), false);
            let (_, je) = cx.phi_jac(data, q.as_slice(), true);
            // Only independent rows enter the KKT matrix (D69): a
            // redundant row (a planar model's out-of-plane weld rows) would
            // make it singular; its multiplier keeps its value.
            let rows = independent_rows(&je);
            let mr = rows.len();
            let mut kkt = DMatrix::zeros(n + mr, n + mr);
            kkt.view_mut((0, 0), (n, n)).copy_from(&kt);
            let mut rhs = DVector::zeros(n + mr);
            rhs.rows_mut(0, n).copy_from(&(-&r));
            for (c, &row) in rows.iter().enumerate() {
                for i in 0..n {
                    kkt[(i, n + c)] = -jv[(row, i)];
                    kkt[(n + c, i)] = je[(row, i)];
                }
                rhs[n + c] = -p[row];
            }
            let Some(dz) = kkt.lu().solve(&rhs) else {
                return Ok(Err(r.amax()));
            };
            if dz.iter().any(|v| !v.is_finite()) {
                return Ok(Err(r.amax()));
            }
            let mut dl = DVector::zeros(m);
            for (c, &row) in rows.iter().enumerate() {
                dl[row] = dz[n + c];
            }
            let f0 = merit(&r, &p);
            let mut alpha = 1.0;
            loop {
                let qt = &*q + dz.rows(0, n) * alpha;
                let lt = &*lam + &dl * alpha;
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
    if let Ok(res) = solve(
        full,
        data,
        &mut q,
        &mut lam,
        &mut iterations,
        &mut derivatives,
    )? {
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
    if solve(
        at(0.0),
        data,
        &mut q_prev,
        &mut l_prev,
        &mut iterations,
        &mut derivatives,
    )?
    .is_err()
    {
        return Err(DynamicsError::StaticsFailed {
            reason: "no constrained equilibrium even without loads (do the closures hold?)".into(),
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
        match solve(
            at(target),
            data,
            &mut qt,
            &mut lt,
            &mut iterations,
            &mut derivatives,
        )? {
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
    let (keff, noise) = cx.tangent(data, &q, &lam, &k);
    let asym = (&keff - keff.transpose()).norm() / keff.norm().max(f64::MIN_POSITIVE);
    let ksym = (&keff + keff.transpose()) * 0.5;
    let (_, je) = cx.phi_jac(data, q_eq, true);
    let z = null_space(&je, n);
    tree::mass_matrix(model, tree, data, q_eq);
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
    let bound = mapped_noise(&(&linv * z.transpose()), &noise);
    let (omega, rigid_tolerance) = frequencies(&eig.eigenvalues, bound, "constrained mode")?;
    let mut shapes = DMatrix::zeros(n, nr);
    let back = &z * linv.transpose();
    for (i, o) in super::modes::ascending(&eig.eigenvalues)
        .into_iter()
        .enumerate()
    {
        shapes.set_column(i, &(&back * eig.eigenvectors.column(o)));
    }
    Ok(Modes {
        omega,
        shapes,
        asymmetry: asym,
        rigid_tolerance,
    })
}

/// The rows of the constraint Jacobian `j` (m×n) kept in the statics' KKT
/// matrix (D69): those of the independent pivots of the pivoted Cholesky
/// of `j jᵀ` (the algorithm and threshold of the dynamics, D68: a pivot
/// below `1e-10` of the largest diagonal is a redundant row), ascending.
fn independent_rows(j: &DMatrix<f64>) -> Vec<usize> {
    let m = j.nrows();
    let mut gram = j * j.transpose();
    let mut perm = vec![0; m];
    let rank = pivoted_cholesky(&mut gram, &mut perm);
    let mut rows = perm[..rank].to_vec();
    rows.sort_unstable();
    rows
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
        let r = super::statics::statics(model, data, q0, options)?;
        return Ok((r, DVector::zeros(0)));
    };
    check_workspace(model, data)?;
    statics(model, tree, data, q0, options)
}

/// `∂q/∂p` and `∂λ/∂p` of an equilibrium, from [`statics_sensitivity`].
#[derive(Clone, Debug)]
pub struct StaticsSensitivity {
    /// `∂q/∂p` (n_dof × k), in the units of `q` per unit of `p`.
    pub dq: DMatrix<f64>,
    /// `∂λ/∂p` (n_constraints × k; zero on redundant rows; 0 × k on an open
    /// model), in the units of `λ` (N, N·m) per unit of `p`.
    pub dlambda: DMatrix<f64>,
}

/// The sensitivity of a static equilibrium to a parameter `p` that enters
/// its generalized force linearly (docs/theory-control.md IS3, IS8–IS10):
/// with the equilibrium `F(q, λ, p) = [τ_s(q) − G(q) p − J_vᵀλ; φ(q)] = 0`
/// (`τ_s` the static force of [`crate::statics`] with the cable tensions
/// `data` holds, `G` given as `rhs` = `−∂τ/∂p` at `q`, n_dof × k; for cable
/// tensions `G = B`, [`crate::actuation_matrix`]), returns `∂q/∂p`
/// (n_dof × k) and `∂λ/∂p` (n_constraints × k, zero on redundant rows)
/// ([`StaticsSensitivity`]) from the bordered system (IS9)
///
/// ```text
/// [ K_t   −J_vᵀ ] [∂q/∂p]   [G]
/// [ J_e     0   ] [∂λ/∂p] = [0],    K_t = ∂(τ_s − J_vᵀλ)/∂q,
/// ```
///
/// the Newton matrix of the constrained statics at its solution (D69):
/// the same tangent (central differences of `τ_s − J_vᵀλ`, relative
/// error ~1e-10), the same exact rows `J_e = ∂φ/∂q` and the same choice of
/// independent rows. `q` and `lambda` must be an equilibrium and its
/// multipliers, as [`closure_statics`] returns them. An open model has
/// no rows: `∂q/∂p = K_t⁻¹ G` with the analytic `K_t` (D37–D47). `Ok(None)`
/// when the matrix is singular (a buckling or limit point, a redundant
/// closure the rank test missed) or the solution is not finite. Allocates.
pub fn statics_sensitivity(
    model: &Model,
    data: &mut Data,
    time: f64,
    q: &[f64],
    lambda: &[f64],
    rhs: &DMatrix<f64>,
) -> Result<Option<StaticsSensitivity>, DynamicsError> {
    crate::algorithms::check_vec(model, "q", q)?;
    let n = model.n_dof();
    let m = model.n_constraints();
    if rhs.nrows() != n {
        return Err(DynamicsError::SizeMismatch {
            what: "rhs (rows)",
            got: rhs.nrows(),
            expected: n,
        });
    }
    if lambda.len() != m {
        return Err(DynamicsError::SizeMismatch {
            what: "lambda (one per closure row)",
            got: lambda.len(),
            expected: m,
        });
    }
    let k = rhs.ncols();
    let finite = |x: &DMatrix<f64>| x.iter().all(|v| v.is_finite());
    let Some(tree) = model.tree.as_ref().filter(|_| model.has_closures()) else {
        let mut w = crate::derivatives::IdDerivatives::new(model);
        w.tensions = data.cable_tensions().map(DVector::from_column_slice);
        w.copy_joint_inputs(data);
        let zero = vec![0.0; n];
        crate::derivatives::inverse_dynamics_derivatives_with(
            model,
            &mut w,
            Forces::at_rest(1.0),
            time,
            q,
            &zero,
            &zero,
        )?;
        let dq = w.dtau_dq.clone().lu().solve(rhs);
        return Ok(dq.filter(finite).map(|dq| StaticsSensitivity {
            dq,
            dlambda: DMatrix::zeros(0, k),
        }));
    };
    check_workspace(model, data)?;
    let cx = Closed {
        model,
        tree,
        t: time,
        forces: Forces::at_rest(1.0),
    };
    let qv = DVector::from_column_slice(q);
    let lam = DVector::from_column_slice(lambda);
    let stiffness = stiffness_matrix(model);
    let kt = cx.newton_tangent(data, &qv, &lam, &stiffness, &mut None)?;
    let (_, jv) = cx.phi_jac(data, q, false);
    let (_, je) = cx.phi_jac(data, q, true);
    let rows = independent_rows(&je);
    let mr = rows.len();
    let mut kkt = DMatrix::zeros(n + mr, n + mr);
    kkt.view_mut((0, 0), (n, n)).copy_from(&kt);
    for (c, &row) in rows.iter().enumerate() {
        for i in 0..n {
            kkt[(i, n + c)] = -jv[(row, i)];
            kkt[(n + c, i)] = je[(row, i)];
        }
    }
    let mut b = DMatrix::zeros(n + mr, k);
    b.view_mut((0, 0), (n, k)).copy_from(rhs);
    let Some(x) = kkt.lu().solve(&b).filter(finite) else {
        return Ok(None);
    };
    let mut dl = DMatrix::zeros(m, k);
    for (c, &row) in rows.iter().enumerate() {
        dl.row_mut(row).copy_from(&x.row(n + c));
    }
    Ok(Some(StaticsSensitivity {
        dq: x.rows(0, n).into_owned(),
        dlambda: dl,
    }))
}
