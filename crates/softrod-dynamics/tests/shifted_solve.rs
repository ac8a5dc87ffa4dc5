//! The O(N) solve of `S = M(q) + a·K + b·D` (`ShiftedSolver`) against a
//! dense Cholesky of the same matrix assembled from `mass_matrix`,
//! `stiffness_matrix` and `damping_matrix`: curved states, every kind of
//! basis, tapered sections, several rods, shifts from 0 to the stiff
//! 1e6 scale, up to a few hundred pieces.

mod common;

use common::{Lcg, Shape, Terms, bases, model, state, two_rods};
use nalgebra::{DMatrix, DVector};
use softrod_dynamics::*;
use softrod_kinematics::Basis;

/// Backward error `‖S x − r‖∞ / (‖S‖∞ ‖x‖∞)` of the recursive solve. The
/// recursion is a block elimination with one small Cholesky per piece, so it
/// is backward stable like a dense Cholesky: of the order of ε = 2.2e-16.
/// Measured ≤ 4e-17 over every case below (N ≤ 240, all shifts); an
/// algorithmic error (a missing armature or coupling term) shows up at
/// O(1e-3 … 1).
const BACKWARD_TOL: f64 = 1e-15;

/// Forward error against the dense Cholesky solve, relative: both solves are
/// backward stable, so they differ by at most ~ε·cond(S) each; the bound
/// used is `FORWARD_FACTOR · ε · cond(S)` with a floor of 1e-13.
const FORWARD_FACTOR: f64 = 50.0;

/// Shifts from none (S = M) through integrator-sized ones to the stiff
/// extreme where `a·K` dominates `M` by ~12 orders of magnitude.
const SHIFTS: [(f64, f64); 7] = [
    (0.0, 0.0),
    (1e-8, 1e-6),
    (1e-6, 0.0),
    (1e-4, 1e-2),
    (1.0, 1.0),
    (1e3, 0.0),
    (1e6, 1e3),
];

/// `‖S‖∞`, the largest absolute row sum.
fn norm_inf(s: &DMatrix<f64>) -> f64 {
    s.row_iter().map(|r| r.abs().sum()).fold(0.0, f64::max)
}

fn dense_shifted(m: &Model, q: &[f64], a: f64, b: f64) -> DMatrix<f64> {
    let mut data = Data::new(m);
    let mass = mass_matrix(m, &mut data, q).unwrap().clone();
    mass + stiffness_matrix(m) * a + damping_matrix(m) * b
}

fn check(m: &Model, q: &[f64], rng: &mut Lcg, label: &str) -> f64 {
    let mut solver = ShiftedSolver::new(m);
    let mut worst: f64 = 0.0;
    for &(a, b) in &SHIFTS {
        let s = dense_shifted(m, q, a, b);
        let r = DVector::from_vec(rng.vec(m.n_dof(), 1.0));
        solver.factor(m, q, a, b).unwrap();
        let mut x = r.as_slice().to_vec();
        solver.solve(m, &mut x).unwrap();
        let x = DVector::from_vec(x);
        let backward = (&s * &x - &r).amax() / (norm_inf(&s) * x.amax());
        worst = worst.max(backward);
        assert!(
            backward < BACKWARD_TOL,
            "{label}, a = {a:e}, b = {b:e}: backward error {backward:e}"
        );
        let ev = s.clone().symmetric_eigen().eigenvalues;
        let cond = ev.max() / ev.min();
        let reference = s.cholesky().expect("S is SPD").solve(&r);
        let forward = (&x - &reference).amax() / reference.amax();
        let bound = (FORWARD_FACTOR * f64::EPSILON * cond).max(1e-13);
        assert!(
            forward < bound,
            "{label}, a = {a:e}, b = {b:e}: O(N) vs Cholesky {forward:e} (cond {cond:e})"
        );
    }
    worst
}

#[test]
fn solves_m_plus_ak_plus_bd_like_a_dense_cholesky() {
    let mut rng = Lcg(17);
    let terms = Terms {
        damping: true,
        ..Terms::NONE
    };
    for (n, mixed, tapered) in [
        (1, false, false),
        (1, true, true),
        (3, true, false),
        (8, true, true),
        (13, false, true),
        (24, true, false),
    ] {
        let mut shape = Shape::new(n, if mixed { bases() } else { vec![Basis::all()] });
        shape.tapered = tapered;
        let m = model(&shape, terms);
        let (q, _, _) = state(&mut rng, m.n_dof(), 0.8, 0.0, 0.0);
        check(
            &m,
            &q,
            &mut rng,
            &format!("N = {n}, mixed {mixed}, tapered {tapered}"),
        );
    }
}

#[test]
fn several_rods_and_strongly_curved_states() {
    let mut rng = Lcg(29);
    let terms = Terms {
        damping: true,
        ..Terms::NONE
    };
    let m = two_rods(5, terms, 2e6);
    let (q, _, _) = state(&mut rng, m.n_dof(), 0.8, 0.0, 0.0);
    check(&m, &q, &mut rng, "two rods");
    // Curvatures up to 60 rad/m on 0.05 m pieces: several radians per
    // piece, past the series switch of the maps.
    let shape = Shape::new(8, bases());
    let m = model(&shape, terms);
    let (q, _, _) = state(&mut rng, m.n_dof(), 60.0, 0.0, 0.0);
    check(&m, &q, &mut rng, "curled");
}

#[test]
fn long_chains_of_a_few_hundred_pieces() {
    let mut rng = Lcg(31);
    let terms = Terms {
        damping: true,
        ..Terms::NONE
    };
    let mut shape = Shape::new(240, bases());
    shape.length = 2.0;
    let m = model(&shape, terms);
    let (q, _, _) = state(&mut rng, m.n_dof(), 0.3, 0.0, 0.0);
    let mut solver = ShiftedSolver::new(&m);
    for &(a, b) in &[(0.0, 0.0), (1e-4, 1e-2), (1e6, 1e3)] {
        let s = dense_shifted(&m, &q, a, b);
        let r = DVector::from_vec(rng.vec(m.n_dof(), 1.0));
        solver.factor(&m, &q, a, b).unwrap();
        let mut x = r.as_slice().to_vec();
        solver.solve(&m, &mut x).unwrap();
        let x = DVector::from_vec(x);
        let backward = (&s * &x - &r).amax() / (norm_inf(&s) * x.amax());
        assert!(
            backward < BACKWARD_TOL,
            "a = {a:e}: backward error {backward:e}"
        );
    }
}

#[test]
fn bad_arguments_are_errors() {
    let m = model(&Shape::new(3, bases()), Terms::NONE);
    let n = m.n_dof();
    let mut solver = ShiftedSolver::new(&m);
    let mut x = vec![1.0; n];
    assert!(matches!(
        solver.solve(&m, &mut x),
        Err(DynamicsError::NotFactored { .. })
    ));
    let q = vec![0.0; n];
    for (a, b, what) in [
        (-1.0, 0.0, "a"),
        (0.0, f64::NAN, "b"),
        (f64::INFINITY, 0.0, "a"),
    ] {
        match solver.factor(&m, &q, a, b) {
            Err(DynamicsError::InvalidShift { what: w, .. }) => assert_eq!(w, what),
            other => panic!("{other:?}"),
        }
    }
    assert!(matches!(
        solver.factor(&m, &q[1..], 0.0, 0.0),
        Err(DynamicsError::SizeMismatch { .. })
    ));
    solver.factor(&m, &q, 0.0, 0.0).unwrap();
    assert!(matches!(
        solver.solve(&m, &mut x[1..]),
        Err(DynamicsError::SizeMismatch { .. })
    ));
    x[0] = f64::NAN;
    assert!(matches!(
        solver.solve(&m, &mut x),
        Err(DynamicsError::NotFinite { .. })
    ));
    let other = model(&Shape::new(4, bases()), Terms::NONE);
    assert!(matches!(
        solver.solve(&other, &mut vec![0.0; other.n_dof()]),
        Err(DynamicsError::WorkspaceMismatch { .. })
    ));
}
