//! Derivatives of the forward dynamics (`forward_dynamics_derivatives`,
//! `dynamics_jacobians`) and the linearization `(A, B)` against central
//! differences of the O(N) forward dynamics itself — a second algorithm,
//! independent of the inverse-dynamics derivatives they are built from —
//! and the input matrix against models whose cable tensions are changed.

mod common;

use common::{Lcg, Shape, Terms, bases, model, rel, richardson_jacobians, state, two_rods};
use nalgebra::{DMatrix, DVector};
use softrod_dynamics::*;
use softrod_kinematics::Basis;
use softrod_mechanics::Tension;

/// Central differences of `forward_dynamics` (Richardson, as in
/// `id_derivatives.rs`): in `q` with step `1e-3·max(1, |q_j|)`; in `q̇`,
/// where `q̈ = M⁻¹(τ − b)` is exactly quadratic, with step `0.5·max(1, |q̇_j|)`
/// (exact up to round-off).
fn fd(m: &Model, t: f64, q: &[f64], qd: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut data = Data::new(m);
    richardson_jacobians(q, qd, |q, qd| {
        forward_dynamics(m, &mut data, t, q, qd, None)
            .unwrap()
            .clone()
    })
}

/// Analytic against differences of the forward dynamics, relative to the
/// largest entry. The differences carry the forward dynamics' own
/// round-off, ε·cond(M)·‖q̈‖/h: with cond(M) ≤ 1e5 for these short, soft
/// models that is ≤ 1e-8 of the largest entry; measured agreement ≤ 1e-10
/// (∂q̈/∂q) and ≤ 1e-12 (∂q̈/∂q̇). A missing term of the derivation shows up
/// at ≥ 1e-5 (drag, the smallest, relative to the elastic entries).
const FD_TOL: f64 = 1e-8;

fn soft(mut shape: Shape, terms: Terms) -> Model {
    shape.young = 2e4;
    model(&shape, terms)
}

#[test]
fn jacobians_equal_differences_of_the_forward_dynamics() {
    let mut rng = Lcg(61);
    let mut tapered = Shape::new(5, bases());
    tapered.tapered = true;
    for (label, m) in [
        (
            "one piece, all strains",
            soft(Shape::new(1, vec![Basis::all()]), Terms::ALL),
        ),
        ("every basis, tapered", soft(tapered, Terms::ALL)),
        ("two rods", two_rods(2, Terms::ALL, 2e4)),
    ] {
        let (q, qd, _) = state(&mut rng, m.n_dof(), 0.8, 2.0, 0.0);
        let mut data = Data::new(&m);
        let j = dynamics_jacobians(&m, &mut data, 0.3, &q, &qd, None).unwrap();
        let (fq, fv) = fd(&m, 0.3, &q, &qd);
        let e1 = rel(&j.dqdd_dq, &fq);
        let e2 = rel(&j.dqdd_dqd, &fv);
        assert!(e1 < FD_TOL, "{label}: ∂q̈/∂q {e1:e}");
        assert!(e2 < FD_TOL, "{label}: ∂q̈/∂q̇ {e2:e}");
        let qdd = forward_dynamics(&m, &mut data, 0.3, &q, &qd, None).unwrap();
        assert!(
            (&j.qdd - qdd).amax() == 0.0,
            "{label}: q̈ is the forward dynamics' own"
        );
    }
}

/// `q̈` is affine in the tensions, so the difference of two forward
/// dynamics whose tensions differ by 1 N is `∂q̈/∂u` exactly, up to the
/// forward dynamics' round-off (~ε·cond(M)·‖q̈‖/‖∂q̈/∂u‖; measured ≤ 2e-14).
const INPUT_TOL: f64 = 1e-11;

#[test]
fn input_matrix_equals_the_response_to_each_tension() {
    let mut rng = Lcg(67);
    let shape = Shape::new(4, bases());
    let terms = Terms::ALL;
    let m = soft(shape.clone(), terms);
    let (q, qd, _) = state(&mut rng, m.n_dof(), 0.8, 2.0, 0.0);
    let mut data = Data::new(&m);
    let mut work = FdDerivatives::new(&m);
    let lin = linearize(&m, &mut data, &mut work, 0.3, &q, &qd, None).unwrap();
    let n = m.n_dof();
    assert_eq!(m.n_cables(), 2);
    let base = forward_dynamics(&m, &mut data, 0.3, &q, &qd, None)
        .unwrap()
        .clone();
    for c in 0..m.n_cables() {
        let mut spec = m.rods()[0].spec.clone();
        let t0 = spec.cables[c].tension_at(0.3);
        assert_eq!(lin.u[c], t0);
        spec.cables[c].tension = Tension::Constant(t0 + 1.0);
        let m2 = Model::new(vec![spec], m.gravity(), 4).unwrap();
        let mut d2 = Data::new(&m2);
        let plus = forward_dynamics(&m2, &mut d2, 0.3, &q, &qd, None)
            .unwrap()
            .clone();
        let response = plus - &base;
        let col: DVector<f64> = lin.b.view((n, c), (n, 1)).column(0).into_owned();
        let e = (&col - &response).amax() / response.amax();
        assert!(e < INPUT_TOL, "cable {c}: {e:e}");
        assert_eq!(lin.b.view((0, c), (n, 1)).amax(), 0.0);
        // ∂τ/∂u = −A: the inverse dynamics at fixed q̈ drops by A per newton.
        let a = actuation_matrix(&m, &q).unwrap();
        let id1 = inverse_dynamics(&m2, &mut d2, 0.3, &q, &qd, base.as_slice())
            .unwrap()
            .clone();
        let id0 = inverse_dynamics(&m, &mut data, 0.3, &q, &qd, base.as_slice())
            .unwrap()
            .clone();
        let da = -(id1 - id0);
        let e = (&da - a.column(c)).amax() / a.column(c).amax();
        assert!(e < 1e-12, "actuation column {c}: {e:e}");
        let e = (work.actuation.column(c) - a.column(c)).amax() / a.column(c).amax();
        assert!(e == 0.0, "workspace actuation {c}: {e:e}");
    }
    // A = [[0, I], [∂q̈/∂q, ∂q̈/∂q̇]], ẋ = (q̇, q̈).
    assert_eq!(lin.a.view((0, 0), (n, n)).amax(), 0.0);
    assert_eq!(
        lin.a.view((0, n), (n, n)).into_owned(),
        DMatrix::identity(n, n)
    );
    assert_eq!(lin.a.view((n, 0), (n, n)).into_owned(), work.dqdd_dq);
    assert_eq!(lin.a.view((n, n), (n, n)).into_owned(), work.dqdd_dqd);
    assert_eq!(
        lin.xdot.rows(0, n).into_owned(),
        DVector::from_column_slice(&qd)
    );
    assert_eq!(lin.xdot.rows(n, n).into_owned(), base);
}

#[test]
fn jacobians_follow_the_load_scale() {
    // Statics' continuation scales every load and tension: the Jacobians
    // must see the same model the forward dynamics does.
    let mut rng = Lcg(71);
    let m = soft(Shape::new(3, bases()), Terms::ALL);
    let (q, qd, _) = state(&mut rng, m.n_dof(), 0.8, 2.0, 0.0);
    let mut data = Data::new(&m);
    let forces = Forces::ALL.with_load_scale(0.4);
    let j = dynamics_jacobians_with(&m, &mut data, forces, 0.3, &q, &qd, None).unwrap();
    // Differences of the forward dynamics at the same load scale.
    let (dq, _) = richardson_jacobians(&q, &qd, |a, b| {
        forward_dynamics_with(&m, &mut data, forces, 0.3, a, b, None)
            .unwrap()
            .clone()
    });
    let e = rel(&j.dqdd_dq, &dq);
    assert!(e < FD_TOL, "λ = 0.4: {e:e}");
}
