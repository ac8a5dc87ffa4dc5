//! The inertia products (`inverse_dynamics_inertia_vjp`,
//! docs/theory-derivatives.md D85) against differences of the inverse
//! dynamics itself: `τ` is affine in each rod's density and each body's
//! screw inertia (at fixed `q, q̇, q̈`), so `zᵀ(τ(ρ + Δ) − τ(ρ))/Δ` of the
//! model rebuilt with the moved value is the exact derivative up to the
//! round-off of the difference. On a six-strain chain with every force term
//! (drag and distributed loads: the inertial sums apart), two rods with
//! mixed bases, trees with joints, bodies and loads, and a tree with an
//! inside branch and a prescribed joint.

mod common;

use common::{Lcg, Shape, Terms, driven_tree, model, robot, state, two_rods};
use nalgebra::DVector;
use softrod_dynamics::*;
use softrod_kinematics::Basis;
use softrod_lie::Mat6;
use softrod_mechanics::{Material, RodProperties};

/// The model with rod `r`'s density doubled.
fn denser(m: &Model, r: usize) -> Model {
    let mut spec = m.rods()[r].spec.clone();
    let mat = spec.properties.material();
    let b = Material::builder()
        .density(2.0 * mat.density())
        .young(mat.young())
        .viscosity(mat.viscosity());
    let mat = match mat.specified_poisson() {
        Some(nu) => b.poisson(nu),
        None => b.shear_modulus(mat.shear_modulus()),
    }
    .build()
    .unwrap();
    spec.properties =
        RodProperties::new(*spec.properties.section(), mat, spec.properties.length()).unwrap();
    m.clone().with_rod_spec(r, spec).unwrap()
}

/// The largest error of the products relative to `Σ|z||τ|` of the part
/// they differentiate, over the rods' densities and the bodies' masses.
fn inertia_error(m: &Model, t: f64, q: &[f64], qd: &[f64], qdd: &[f64], rng: &mut Lcg) -> f64 {
    let n = m.n_dof();
    let z = DVector::from_vec(rng.vec(n, 1.0));
    let mut work = IdDerivatives::for_products(m);
    inverse_dynamics_linearization_with(m, &mut work, Forces::ALL, t, q, qd, qdd).unwrap();
    let (mut rods, mut bodies) = (
        vec![0.0; m.rods().len()],
        vec![Mat6::zeros(); m.bodies().len()],
    );
    inverse_dynamics_inertia_vjp(m, &mut work, z.as_slice(), &mut rods, &mut bodies).unwrap();
    let mut data = Data::new(m);
    let tau = inverse_dynamics(m, &mut data, t, q, qd, qdd)
        .unwrap()
        .clone();
    let mut worst: f64 = 0.0;
    let mut check = |moved: &Model, got: f64| {
        let mut d = Data::new(moved);
        let t2 = inverse_dynamics(moved, &mut d, t, q, qd, qdd)
            .unwrap()
            .clone();
        let diff = &t2 - &tau;
        let reference = z.dot(&diff);
        let scale = z.abs().dot(&(t2.abs() + tau.abs()));
        assert!(diff.amax() > 0.0, "the parameter moves tau");
        worst = worst.max((got - reference).abs() / scale);
    };
    for (r, &got) in rods.iter().enumerate() {
        // Doubled density: Δρ = ρ, s_r from 1 to 2.
        check(&denser(m, r), got);
    }
    for (b, g) in bodies.iter().enumerate() {
        let mut spec = m.bodies()[b].spec.clone();
        spec.mass *= 1.7;
        let moved = m.clone().with_body_spec(b, spec).unwrap();
        let dm = moved.bodies()[b].inertia - m.bodies()[b].inertia;
        check(&moved, g.component_mul(&dm).sum());
    }
    worst
}

/// Measured ≤ 1e-16 on every model below.
const TOL: f64 = 1e-13;

#[test]
fn chains_with_every_term() {
    let mut rng = Lcg(5);
    for pieces in [1, 5] {
        let m = model(&Shape::new(pieces, vec![Basis::all()]), Terms::ALL);
        let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.8, 2.0, 5.0);
        let e = inertia_error(&m, 0.3, &q, &qd, &qdd, &mut rng);
        println!("six strains, every term, {pieces} pieces: {e:.1e}");
        assert!(e < TOL, "{pieces} pieces: {e:e}");
    }
    let m = two_rods(3, Terms::NONE, 2e6);
    let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.8, 2.0, 5.0);
    let e = inertia_error(&m, 0.1, &q, &qd, &qdd, &mut rng);
    println!("two rods, mixed bases: {e:.1e}");
    assert!(e < TOL, "two rods: {e:e}");
}

#[test]
fn trees_with_joints_bodies_and_branches() {
    let mut rng = Lcg(31);
    for (gravity, damping, tree, loads) in [(true, true, true, true), (true, false, false, false)] {
        let m = robot(gravity, damping, tree, loads);
        assert!(!m.bodies().is_empty());
        let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.4, 1.5, 3.0);
        let e = inertia_error(&m, 0.0, &q, &qd, &qdd, &mut rng);
        println!("robot g{gravity} d{damping} tree{tree} loads{loads}: {e:.1e}");
        assert!(e < TOL, "robot: {e:e}");
    }
    let m = driven_tree();
    for t in [0.0, 0.37] {
        let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.3, 1.0, 2.0);
        let e = inertia_error(&m, t, &q, &qd, &qdd, &mut rng);
        println!("driven tree, t = {t}: {e:.1e}");
        assert!(e < TOL, "driven tree, t = {t}: {e:e}");
    }
}

#[test]
fn misuse_is_an_error() {
    let m = robot(true, true, true, true);
    let n = m.n_dof();
    let mut work = IdDerivatives::for_products(&m);
    let z = vec![1.0; n];
    let (mut rods, mut bodies) = (
        vec![0.0; m.rods().len()],
        vec![Mat6::zeros(); m.bodies().len()],
    );
    assert!(matches!(
        inverse_dynamics_inertia_vjp(&m, &mut work, &z, &mut rods, &mut bodies),
        Err(DynamicsError::NotLinearized { .. })
    ));
    let x = vec![0.0; n];
    inverse_dynamics_linearization_with(&m, &mut work, Forces::ALL, 0.0, &x, &x, &x).unwrap();
    let mut short = vec![0.0; m.rods().len() - 1];
    assert!(matches!(
        inverse_dynamics_inertia_vjp(&m, &mut work, &z, &mut short, &mut bodies),
        Err(DynamicsError::SizeMismatch { .. })
    ));
    let bad = vec![f64::NAN; n];
    assert!(inverse_dynamics_inertia_vjp(&m, &mut work, &bad, &mut rods, &mut bodies).is_err());
}
