//! The structured Newton solve of closed models
//! (`ClosedShiftedSolver`, docs/theory-derivatives.md CD5–CD7) against
//! independent references: the dense KKT system of the same matrix
//! (`mass_matrix`, `stiffness_matrix`, `damping_matrix` and an LU), the
//! constrained forward dynamics (its `q̈` and multipliers are the fixed
//! point: both residuals vanish there), and the exact Newton step of the
//! stage equation from the closed-chain derivatives (CD1–CD4), which the
//! KKT step approaches as the step shrinks. Models: a four-bar of soft
//! links, a pinned–pinned rod (the catenary), welds, sliders, redundant
//! closures and closures on a prescribed joint.

mod common;

use common::closed::{catenary, driven, four_bar, redundant, two_closures};
use common::wavy;

use nalgebra::{DMatrix, DVector};
use softrod_dynamics::{
    ClosedDerivatives, ClosedShiftedSolver, ClosureKind, Data, Model, closed_dynamics_derivatives,
    closure_multipliers, constraint_jacobian, damping_matrix, forward_dynamics,
    generalized_gravity, mass_matrix, stiffness_matrix,
};
use softrod_lie::Vec3;

/// Every model with a name and a time to evaluate at.
fn models() -> Vec<(&'static str, Model, f64)> {
    vec![
        ("four-bar", four_bar(), 0.0),
        ("catenary", catenary(6), 0.0),
        ("weld", two_closures(ClosureKind::Weld), 0.0),
        (
            "slider",
            two_closures(ClosureKind::Slider {
                axis: Vec3::new(0.3, 1.0, -0.2),
            }),
            0.0,
        ),
        ("prescribed", driven(), 0.37),
    ]
}

/// A state off the manifold (the Baumgarte terms act), moving.
fn state(model: &Model, seed: f64) -> (Vec<f64>, Vec<f64>) {
    let n = model.n_dof();
    (wavy(n, 0.3, seed), wavy(n, 0.8, seed + 1.0))
}

/// The residuals `(r, R)` at a trial `q̈`.
#[allow(clippy::too_many_arguments)]
fn residuals(
    kkt: &mut ClosedShiftedSolver,
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> (DVector<f64>, DVector<f64>) {
    let (mut r, mut c) = (vec![0.0; model.n_dof()], vec![0.0; model.n_constraints()]);
    kkt.residuals(model, data, t, q, qd, qdd, None, &mut r, &mut c)
        .unwrap();
    (DVector::from_vec(r), DVector::from_vec(c))
}

/// At the constrained forward dynamics' `q̈` and `λ` (D67–D68, the
/// production solve) both residuals vanish: `r = Jᵀλ` and `R = 0` — the
/// Newton iteration's fixed point is the constrained dynamics.
#[test]
fn the_fixed_point_is_the_constrained_acceleration() {
    for (name, model, t) in models()
        .into_iter()
        .chain([("redundant", redundant(), 0.0)])
    {
        let (q, qd) = state(&model, 0.7);
        let mut data = Data::new(&model);
        let mut kkt = ClosedShiftedSolver::new(&model);
        let qdd = forward_dynamics(&model, &mut data, t, &q, &qd, None)
            .unwrap()
            .clone();
        let lambda = closure_multipliers(&data).unwrap().0.clone();
        let (r, c) = residuals(&mut kkt, &model, &mut data, t, &q, &qd, qdd.as_slice());
        // J from the residual's rows: R is affine in q̈.
        let (_, c0) = residuals(&mut kkt, &model, &mut data, t, &q, &qd, &vec![0.0; q.len()]);
        let scale_c = (&c - &c0).amax();
        assert!(c.amax() <= 1e-10 * scale_c, "{name}: R = {c}");
        let mut jac = DMatrix::zeros(model.n_constraints(), q.len());
        for j in 0..q.len() {
            let mut e = vec![0.0; q.len()];
            e[j] = 1.0;
            let (_, cj) = residuals(&mut kkt, &model, &mut data, t, &q, &qd, &e);
            jac.set_column(j, &(cj - &c0));
        }
        let force = jac.transpose() * &lambda;
        let err = (&r - &force).amax();
        assert!(
            err <= 1e-9 * r.amax().max(force.amax()),
            "{name}: r − Jᵀλ = {err:e} of {:e}",
            r.amax()
        );
    }
}

/// The KKT solve against the dense `[S, −Jᵀ; s·J, 0]` (S from the dense
/// mass, stiffness and damping matrices, `J` the rows' `q̈` coefficients,
/// `s = 1 + 2α b + α² a`), solved by LU: the same solution to rounding.
#[test]
fn kkt_solve_matches_the_dense_kkt_system() {
    let (a, b) = (3e-5, 4e-3);
    for (name, model, t) in models() {
        let (n, m) = (model.n_dof(), model.n_constraints());
        let (q, qd) = state(&model, 1.1);
        let mut data = Data::new(&model);
        let mut kkt = ClosedShiftedSolver::new(&model);
        kkt.factor_at(&model, t, &q, a, b).unwrap();
        let (_, c0) = residuals(&mut kkt, &model, &mut data, t, &q, &qd, &vec![0.0; n]);
        let mut jac = DMatrix::zeros(m, n);
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let (_, cj) = residuals(&mut kkt, &model, &mut data, t, &q, &qd, &e);
            jac.set_column(j, &(cj - &c0));
        }
        model.set_time(&mut data, t);
        let s_mat = mass_matrix(&model, &mut data, &q).unwrap().clone()
            + stiffness_matrix(&model) * a
            + damping_matrix(&model) * b;
        let alpha = model.baumgarte_rate();
        let s = 1.0 + 2.0 * alpha * b + alpha * alpha * a;
        let mut big = DMatrix::zeros(n + m, n + m);
        big.view_mut((0, 0), (n, n)).copy_from(&s_mat);
        big.view_mut((0, n), (n, m)).copy_from(&(-jac.transpose()));
        big.view_mut((n, 0), (m, n)).copy_from(&(&jac * s));
        let rhs_x = DVector::from_vec(wavy(n, 2.0, 0.3));
        let rhs_d = DVector::from_vec(wavy(m, 1.5, 0.9));
        let mut rhs = DVector::zeros(n + m);
        rhs.rows_mut(0, n).copy_from(&rhs_x);
        rhs.rows_mut(n, m).copy_from(&rhs_d);
        let want = big.lu().solve(&rhs).unwrap();
        let mut x = rhs_x.as_slice().to_vec();
        kkt.solve(&model, &mut x, rhs_d.as_slice()).unwrap();
        let got = DVector::from_vec(x);
        let err = (&got - want.rows(0, n)).amax();
        assert!(
            err <= 1e-9 * want.rows(0, n).amax(),
            "{name}: {err:e} of {:e}",
            want.rows(0, n).amax()
        );
    }
}

/// One Newton step of an implicit stage equation `x = q̈(Q(x), V(x))`,
/// `V = v̂ + hγx`, `Q = q̂ + hγV`: the KKT step (CD5–CD7) against the exact
/// step `−(I − hγ ∂q̈/∂q̇ − h²γ² ∂q̈/∂q)⁻¹ (x − q̈)` from the analytic
/// closed-chain derivatives (CD1–CD4). The KKT matrix leaves out terms of
/// order `hγ` and `h²γ²` against `M` (geometric, gyroscopic, load and
/// drag derivatives); on these states the `h²γ²` ones dominate (the
/// closure and internal forces of a state off the manifold), so the two
/// steps differ by `O(h²γ²)` relative: a hundredfold less per decade of
/// the step.
#[test]
fn kkt_step_approaches_the_exact_newton_step() {
    for (name, model, t) in models() {
        let n = model.n_dof();
        let (qh, vh) = state(&model, 0.4);
        let x0 = DVector::from_vec(wavy(n, 1.0, 2.0));
        let mut data = Data::new(&model);
        let mut kkt = ClosedShiftedSolver::new(&model);
        let mut work = ClosedDerivatives::new(&model);
        let mut errs = Vec::new();
        for hg in [1e-4, 1e-5] {
            let v = DVector::from_column_slice(&vh) + &x0 * hg;
            let q = DVector::from_column_slice(&qh) + &v * hg;
            // Exact.
            let d = closed_dynamics_derivatives(
                &model,
                &mut data,
                &mut work,
                t,
                q.as_slice(),
                v.as_slice(),
                None,
            )
            .unwrap();
            let newton = DMatrix::identity(n, n) - &d.dqdd_dqd * hg - &d.dqdd_dq * (hg * hg);
            let exact = newton.lu().solve(&(&d.qdd - &x0)).unwrap();
            // Structured: the matrix at the stage's q (as a fresh Jacobian).
            kkt.factor_at(&model, t, q.as_slice(), hg * hg, hg).unwrap();
            let (r, c) = residuals(
                &mut kkt,
                &model,
                &mut data,
                t,
                q.as_slice(),
                v.as_slice(),
                x0.as_slice(),
            );
            let mut step = (-r).as_slice().to_vec();
            kkt.solve(&model, &mut step, (-c).as_slice()).unwrap();
            let step = DVector::from_vec(step);
            errs.push((&step - &exact).amax() / exact.amax());
        }
        // O(h²γ²): a hundredfold per decade (measured 0.005–0.04 at
        // hγ = 1e-4, about 1e-2 of that at 1e-5).
        assert!(errs[0] < 0.1, "{name}: {errs:?}");
        assert!(errs[1] < 0.05 * errs[0], "{name}: {errs:?}");
    }
}

/// The geometric terms of the KKT matrix (CD11) on a rope pinned at both
/// ends (a ball closure to the world): with them `S` is
/// `M + a(K + K_g) + bD` with `K_g = ∂(G(q) − J(q)ᵀλ)/∂q` at fixed `λ`
/// (`G = ∂V_g/∂q`, the generalized gravity on the inverse dynamics'
/// side, where the closure force enters as `−Jᵀλ`) — the Hessian of the potential of gravity and of the pin's force held
/// fixed in the world — here from central differences of the generalized
/// gravity and of the constraint Jacobian (independent of the
/// recursion), in the dense KKT system solved by LU. Without the terms
/// the solve is far off at these shifts. (At `a = 1e-5` this state's
/// `K_g` — the multipliers of a state off the manifold are large — makes
/// some articulated blocks indefinite, and CT23's modified factorization
/// is by design not this matrix's.)
#[test]
fn geometric_terms_are_the_held_forces_hessian() {
    let model = catenary(8);
    let (n, m) = (model.n_dof(), model.n_constraints());
    let mut data = Data::new(&model);
    // A sagging state near the manifold, and the multipliers there.
    let q: Vec<f64> = wavy(n, 0.05, 0.2);
    let qd = vec![0.0; n];
    forward_dynamics(&model, &mut data, 0.0, &q, &qd, None).unwrap();
    let lambda = closure_multipliers(&data).unwrap().0.clone();
    assert!(lambda.amax() > 1e-3, "the pin carries a force: {lambda}");
    let held = |data: &mut Data, q: &[f64]| -> DVector<f64> {
        generalized_gravity(&model, data, q).unwrap()
            - constraint_jacobian(&model, data, q).unwrap().transpose() * &lambda
    };
    let mut kg = DMatrix::zeros(n, n);
    for j in 0..n {
        let h = 1e-6 * q[j].abs().max(1.0);
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[j] += h;
        qm[j] -= h;
        kg.set_column(
            j,
            &((held(&mut data, &qp) - held(&mut data, &qm)) / (2.0 * h)),
        );
    }
    let jac = constraint_jacobian(&model, &mut data, &q).unwrap();
    let alpha = model.baumgarte_rate();
    let rhs_x = DVector::from_vec(wavy(n, 2.0, 0.3));
    let rhs_d = DVector::from_vec(wavy(m, 1.5, 0.9));
    for (a, b) in [(1e-7, 1e-3), (1e-6, 1e-3)] {
        let s_mat = mass_matrix(&model, &mut data, &q).unwrap().clone()
            + (stiffness_matrix(&model) + &kg) * a
            + damping_matrix(&model) * b;
        let s = 1.0 + 2.0 * alpha * b + alpha * alpha * a;
        let mut big = DMatrix::zeros(n + m, n + m);
        big.view_mut((0, 0), (n, n)).copy_from(&s_mat);
        big.view_mut((0, n), (n, m)).copy_from(&(-jac.transpose()));
        big.view_mut((n, 0), (m, n)).copy_from(&(&jac * s));
        let mut rhs = DVector::zeros(n + m);
        rhs.rows_mut(0, n).copy_from(&rhs_x);
        rhs.rows_mut(n, m).copy_from(&rhs_d);
        let want = big.lu().solve(&rhs).unwrap();
        let want = want.rows(0, n);
        let mut errs = Vec::new();
        for geometric in [true, false] {
            let mut kkt = ClosedShiftedSolver::new(&model);
            kkt.set_geometric(geometric);
            kkt.set_multipliers(lambda.as_slice()).unwrap();
            kkt.factor_at(&model, 0.0, &q, a, b).unwrap();
            assert_eq!(kkt.geometric_in_factor(), geometric);
            let mut x = rhs_x.as_slice().to_vec();
            kkt.solve(&model, &mut x, rhs_d.as_slice()).unwrap();
            errs.push((DVector::from_vec(x) - want).amax() / want.amax());
        }
        // Central differences of step 1e-6: measured 1.2e-9 and 3.5e-9
        // with the terms, 4.1e-2 and 0.29 without.
        assert!(errs[0] < 1e-7, "a = {a}: with the terms {errs:?}");
        assert!(errs[1] > 1e-2, "a = {a}: without them {errs:?}");
    }
}

/// `set_multipliers` refuses a wrong length and non-finite values.
#[test]
fn set_multipliers_checks_its_input() {
    let model = catenary(4);
    let mut kkt = ClosedShiftedSolver::new(&model);
    let m = model.n_constraints();
    assert!(kkt.set_multipliers(&vec![0.0; m + 1]).is_err());
    let mut bad = vec![0.0; m];
    bad[0] = f64::NAN;
    assert!(kkt.set_multipliers(&bad).is_err());
    assert!(kkt.set_multipliers(&vec![1.0; m]).is_ok());
}
