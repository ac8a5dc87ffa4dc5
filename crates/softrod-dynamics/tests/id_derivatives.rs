//! Analytic `∂τ/∂q`, `∂τ/∂q̇` of the inverse dynamics
//! (`inverse_dynamics_derivatives`) against fourth-order central differences
//! of `inverse_dynamics` (an independent code path: the production RNEA),
//! term by term and all together, on curved moving states, near θ = 0, at
//! several turns per piece, with tapered sections, every kind of basis and
//! several rods.

mod common;

use common::{Lcg, Shape, Terms, bases, model, rel, state, two_rods};
use nalgebra::DMatrix;
use softrod_dynamics::*;
use softrod_kinematics::Basis;

/// Fourth-order central differences of `inverse_dynamics`
/// ([`common::id_differences`]). In `q`: step `h = 1e-3·max(1, |q_j|)`,
/// truncation O(h⁴) ≈ 1e-12 of the derivative scale, round-off ~ε‖τ‖/h. In
/// `q̇`: `τ` is exactly quadratic in `q̇` (η is linear in it, η̇ and the
/// gyroscopic force quadratic, drag linear), so central differences are
/// exact for any step and the only error is round-off: a large step
/// `h = 0.5·max(1, |q̇_j|)` keeps it at ~ε‖τ‖ (a small one would amplify the
/// elastic part of τ, ~1e4 × the velocity derivatives, by 1/h).
use common::id_differences as fd;

/// Analytic vs differences, relative to the largest entry of what is
/// compared. The differences are good to ~ε‖τ‖/h ≈ 1e-13‖τ‖ (see [`fd`]);
/// the comparisons below remove the exact linear parts `K`, `D` (or compare a
/// term's own contribution, the model with it minus the model without it),
/// whose entries are ~1e2…1e4 times the rest, and the models use a soft
/// material for the same reason. Measured agreement ≤ 4e-10 on every case
/// below; an error in any term of the derivation shows up at O(1) of that
/// term's contribution.
const FD_TOL: f64 = 1e-8;

/// Analytic derivatives (and a check that `work.tau` is the production τ).
fn analytic(m: &Model, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let mut work = IdDerivatives::new(m);
    inverse_dynamics_derivatives(m, &mut work, t, q, qd, qdd).unwrap();
    let mut data = Data::new(m);
    let tau = inverse_dynamics(m, &mut data, t, q, qd, qdd)
        .unwrap()
        .clone();
    // Same sums in another order: round-off of the largest force.
    let e_tau = (&work.tau - &tau).amax() / tau.amax();
    assert!(e_tau < 1e-13, "τ {e_tau:e}");
    (work.dtau_dq.clone(), work.dtau_dqd.clone())
}

/// Everything but the exact `K`, `D`: analytic against differences.
fn check(m: &Model, t: f64, q: &[f64], qd: &[f64], qdd: &[f64], label: &str) -> f64 {
    let (aq, av) = analytic(m, t, q, qd, qdd);
    let (fq, fv) = fd(m, t, q, qd, qdd);
    let (k, d) = (stiffness_matrix(m), damping_matrix(m));
    let e1 = rel(&(&aq - &k), &(&fq - &k));
    let e2 = rel(&(&av - &d), &(&fv - &d));
    assert!(e1 < FD_TOL, "{label}: ∂τ/∂q − K: {e1:e}");
    assert!(e2 < FD_TOL, "{label}: ∂τ/∂q̇ − D: {e2:e}");
    e1.max(e2)
}

/// One term's own contribution (model with it minus model without it).
fn check_term(with: &Model, without: &Model, q: &[f64], qd: &[f64], qdd: &[f64], label: &str) {
    let t = 0.3;
    let (aq1, av1) = analytic(with, t, q, qd, qdd);
    let (aq0, av0) = analytic(without, t, q, qd, qdd);
    let (fq1, fv1) = fd(with, t, q, qd, qdd);
    let (fq0, fv0) = fd(without, t, q, qd, qdd);
    for (what, a, f, whole) in [
        ("∂τ/∂q", &aq1 - &aq0, &fq1 - &fq0, fq1.amax()),
        ("∂τ/∂q̇", &av1 - &av0, &fv1 - &fv0, fv1.amax()),
    ] {
        // A term that does not depend on this variable (damping in q, loads
        // in q̇): the differences see only their round-off, ≤ 1e-10 of the
        // whole; the analytic contribution must be as small.
        let noise = 1e-10 * whole;
        if f.amax() < 10.0 * noise {
            assert!(
                a.amax() < 10.0 * noise,
                "{label}: {what} {:e} where none is",
                a.amax()
            );
            continue;
        }
        let e = rel(&a, &f);
        assert!(e < FD_TOL, "{label}: own part of {what}: {e:e}");
    }
}

#[test]
fn every_term_separately_and_all_together() {
    let mut rng = Lcg(41);
    let one = |f: &dyn Fn(&mut Terms)| {
        let mut t = Terms::NONE;
        f(&mut t);
        t
    };
    let cases: Vec<(&str, Terms)> = vec![
        ("gravity", one(&|t| t.gravity = true)),
        ("damping", one(&|t| t.damping = true)),
        ("dead point loads", one(&|t| t.dead_point = true)),
        ("follower point load", one(&|t| t.follower_point = true)),
        ("distributed loads", one(&|t| t.distributed = true)),
        ("cables", one(&|t| t.cable = true)),
        ("drag", one(&|t| t.drag = true)),
    ];
    for (n, b) in [(1, vec![Basis::all()]), (4, bases())] {
        // A soft material: the exact elastic part K q of τ then does not
        // swamp the differences' round-off (K is checked separately).
        let mut shape = Shape::new(n, b);
        shape.young = 2e4;
        let bare = model(&shape, Terms::NONE);
        let (q, qd, qdd) = state(&mut rng, bare.n_dof(), 0.8, 2.0, 5.0);
        check(
            &bare,
            0.3,
            &q,
            &qd,
            &qdd,
            &format!("inertia + elasticity, N = {n}"),
        );
        for (label, terms) in &cases {
            let m = model(&shape, *terms);
            check_term(&m, &bare, &q, &qd, &qdd, &format!("{label}, N = {n}"));
        }
        let m = model(&shape, Terms::ALL);
        check(&m, 0.3, &q, &qd, &qdd, &format!("all, N = {n}"));
    }
}

/// A soft test model (see [`every_term_separately_and_all_together`]).
fn soft(mut shape: Shape, terms: Terms) -> Model {
    shape.young = 2e4;
    model(&shape, terms)
}

#[test]
fn straight_and_near_straight_states() {
    // θ = 0 exactly and 1e-9: the series branch of every coefficient family
    // (σ included) at its expansion point. Straight rest strain, q = 0 on
    // the curvatures, moving.
    let mut rng = Lcg(43);
    let mut shape = Shape::new(4, bases());
    shape.rest = softrod_kinematics::straight();
    let m = soft(shape, Terms::ALL);
    let (_, qd, qdd) = state(&mut rng, m.n_dof(), 0.0, 2.0, 5.0);
    for eps in [0.0, 1e-9] {
        let q: Vec<f64> = (0..m.n_dof())
            .map(|i| eps * ((i % 3) as f64 - 1.0))
            .collect();
        check(&m, 0.3, &q, &qd, &qdd, &format!("θ ~ {eps:e}"));
    }
}

#[test]
fn several_turns_per_piece() {
    // Curvatures near 100 rad/m on 0.1 m pieces: θℓ up to ~2 turns, far
    // past the series switch (ψ* = 2.5).
    let mut rng = Lcg(47);
    let m = soft(Shape::new(4, vec![Basis::all()]), Terms::ALL);
    let (mut q, qd, qdd) = state(&mut rng, m.n_dof(), 0.5, 1.0, 3.0);
    for (i, v) in q.iter_mut().enumerate() {
        if i % 6 < 3 {
            *v = 70.0 + 30.0 * *v;
        }
    }
    check(&m, 0.3, &q, &qd, &qdd, "several turns");
}

#[test]
fn tapered_mixed_bases_and_several_rods() {
    let mut rng = Lcg(53);
    let mut shape = Shape::new(8, bases());
    shape.tapered = true;
    let m = soft(shape, Terms::ALL);
    let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.8, 2.0, 5.0);
    check(&m, 0.3, &q, &qd, &qdd, "tapered, every basis");
    let m = two_rods(3, Terms::ALL, 2e4);
    let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.8, 2.0, 5.0);
    check(&m, 0.3, &q, &qd, &qdd, "two rods");
}

#[test]
fn bad_arguments_are_errors() {
    let m = soft(Shape::new(2, bases()), Terms::NONE);
    let n = m.n_dof();
    let mut work = IdDerivatives::new(&m);
    let z = vec![0.0; n];
    assert!(matches!(
        inverse_dynamics_derivatives(&m, &mut work, 0.0, &z[1..], &z, &z),
        Err(DynamicsError::SizeMismatch { .. })
    ));
    let mut bad = z.clone();
    bad[0] = f64::NAN;
    assert!(matches!(
        inverse_dynamics_derivatives(&m, &mut work, 0.0, &z, &bad, &z),
        Err(DynamicsError::NotFinite { .. })
    ));
    let other = soft(Shape::new(3, bases()), Terms::NONE);
    let zo = vec![0.0; other.n_dof()];
    assert!(matches!(
        inverse_dynamics_derivatives(&other, &mut work, 0.0, &zo, &zo, &zo),
        Err(DynamicsError::WorkspaceMismatch { .. })
    ));
}
