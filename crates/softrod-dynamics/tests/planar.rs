//! The planar (se(2)) path of the forward and inverse dynamics (and of the
//! bias and gravity forces built on the latter) against the general se(3)
//! path on the same model (docs/theory.md §13): every force term, the
//! three bending planes, strain subsets, tapered sections, straight and
//! wound-up states, and hundreds of pieces.

mod common;

use common::{Lcg, Shape, Terms, gravity, rod_spec, state, tilted_base};
use softrod_dynamics::{
    Data, Model, bias_force, energies, forward_dynamics, generalized_gravity, inverse_dynamics,
};
use softrod_kinematics::{Basis, Strain};
use softrod_lie::Vec6;

/// The largest of max |x_planar − x_3D| / max |x_3D| over the forward
/// dynamics `q̈`, the inverse dynamics `τ` (at a varied `q̈`), the bias `b`
/// the generalized gravity and the energies (kinetic, elastic,
/// gravitational; relative to the largest of the three) at `(q, q̇)`,
/// after checking that the
/// first model really runs every planar rod on the planar path and the
/// second does not.
fn compare(model: &Model, q: &[f64], qd: &[f64]) -> f64 {
    let general = model.clone().with_planar_path(false);
    let planar_rods: Vec<usize> = (0..model.rods().len())
        .filter(|&r| model.rods()[r].is_planar())
        .collect();
    assert!(!planar_rods.is_empty(), "no planar rod in the test model");
    for &r in &planar_rods {
        assert!(model.uses_planar_path(r) && !general.uses_planar_path(r));
    }
    let mut d1 = Data::new(model);
    let mut d2 = Data::new(&general);
    let rel = |a: nalgebra::DVector<f64>, b: nalgebra::DVector<f64>| (a - &b).amax() / b.amax();
    let qdd: Vec<f64> = (0..q.len())
        .map(|i| 40.0 * (1.3 * i as f64).sin())
        .collect();
    let t = 0.3;
    let fd = rel(
        forward_dynamics(model, &mut d1, t, q, qd, None)
            .unwrap()
            .clone(),
        forward_dynamics(&general, &mut d2, t, q, qd, None)
            .unwrap()
            .clone(),
    );
    let id = rel(
        inverse_dynamics(model, &mut d1, t, q, qd, &qdd)
            .unwrap()
            .clone(),
        inverse_dynamics(&general, &mut d2, t, q, qd, &qdd)
            .unwrap()
            .clone(),
    );
    let bias = rel(
        bias_force(model, &mut d1, t, q, qd).unwrap().clone(),
        bias_force(&general, &mut d2, t, q, qd).unwrap().clone(),
    );
    let grav = if model.gravity().is_some() {
        rel(
            generalized_gravity(model, &mut d1, q).unwrap(),
            generalized_gravity(&general, &mut d2, q).unwrap(),
        )
    } else {
        0.0
    };
    let (e1, e2) = (
        energies(model, &mut d1, q, qd).unwrap(),
        energies(&general, &mut d2, q, qd).unwrap(),
    );
    let scale = [e2.kinetic, e2.elastic, e2.gravitational]
        .map(f64::abs)
        .into_iter()
        .fold(f64::MIN_POSITIVE, f64::max);
    let energy = [
        e1.kinetic - e2.kinetic,
        e1.elastic - e2.elastic,
        e1.gravitational - e2.gravitational,
    ]
    .map(f64::abs)
    .into_iter()
    .fold(0.0, f64::max)
        / scale;
    fd.max(id).max(bias).max(grav).max(energy)
}

fn select(s: &[Strain]) -> Basis {
    Basis::select(s).unwrap()
}

/// Planar bases and a planar precurved rest strain for bending axis
/// `axis` (`(a, b, c)` cyclic): `(κ_a, q_b, q_c)`, stretch along the
/// rod's axis `x` for `a = y, z`, along `y` for `a = x`.
fn plane(axis: usize) -> (Vec<Basis>, Vec6) {
    use Strain::*;
    match axis {
        0 => (
            vec![select(&[Kx, Qy, Qz]), select(&[Kx]), select(&[Qz, Kx])],
            Vec6::new(0.8, 0.0, 0.0, 0.0, 1.0, 0.1),
        ),
        1 => (
            vec![select(&[Ky, Qx, Qz]), select(&[Ky]), select(&[Qx, Ky])],
            Vec6::new(0.0, 0.8, 0.0, 1.0, 0.0, 0.1),
        ),
        _ => (
            vec![select(&[Kz, Qx, Qy]), select(&[Kz]), select(&[Qy, Kz])],
            Vec6::new(0.0, 0.0, -0.8, 1.0, 0.1, 0.0),
        ),
    }
}

#[test]
fn every_plane_and_every_term_matches_the_general_path() {
    let mut rng = Lcg(7);
    for axis in 0..3 {
        let (bases, rest) = plane(axis);
        // Stiff (elasticity dominates τ) and nearly elastic-free (inertia,
        // gyroscopic and load terms do), so that the inverse dynamics is
        // compared on every part.
        for (terms, tapered, young) in [
            (Terms::NONE, false, 2e6),
            (Terms::ALL, false, 2e6),
            (Terms::ALL, true, 2e6),
            (Terms::NONE, true, 1.0),
            (Terms::ALL, false, 1.0),
            (Terms::ALL, true, 1.0),
        ] {
            {
                let mut shape = Shape::new(7, bases.clone());
                shape.rest = rest;
                shape.tapered = tapered;
                shape.young = young;
                let model = Model::new(
                    vec![rod_spec("arm", &shape, terms, tilted_base())],
                    gravity(terms),
                    4,
                )
                .unwrap();
                let n = model.n_dof();
                let (q, qd, _) = state(&mut rng, n, 3.0, 5.0, 0.0);
                let e = compare(&model, &q, &qd);
                assert!(
                    e < 1e-11,
                    "axis {axis}, terms {terms:?}, tapered {tapered}, E {young}: {e:e}"
                );
            }
        }
    }
}

/// Straight (θ = 0 exactly), barely curved, and wound up several turns per
/// piece, at rest and moving fast: both branches of the coefficients.
#[test]
fn curvature_extremes_match() {
    use Strain::*;
    let shape = |rest: Vec6| {
        let mut s = Shape::new(5, vec![select(&[Ky, Qx, Qz])]);
        s.rest = rest;
        s.young = 10.0;
        s
    };
    for (k, scale) in [(0.0, 0.0), (1e-9, 1e-9), (1e-4, 1e-3), (40.0, 30.0)] {
        let model = Model::new(
            vec![rod_spec(
                "arm",
                &shape(Vec6::new(0.0, k, 0.0, 1.0, 0.0, 0.0)),
                Terms::ALL,
                tilted_base(),
            )],
            gravity(Terms::ALL),
            4,
        )
        .unwrap();
        let n = model.n_dof();
        let mut rng = Lcg(11);
        let q: Vec<f64> = rng.vec(n, scale);
        for qd_scale in [0.0, 50.0] {
            let qd = rng.vec(n, qd_scale);
            let e = compare(&model, &q, &qd);
            assert!(e < 1e-11, "curvature {k}, rates {qd_scale}: {e:e}");
        }
    }
}

/// Several rods, planar and not, in one model; 300 pieces on one of them.
#[test]
fn mixed_models_and_long_rods_match() {
    use Strain::*;
    let (bases, rest) = plane(1);
    let mut planar = Shape::new(300, bases);
    planar.rest = rest;
    planar.young = 10.0;
    let general = Shape::new(4, vec![Basis::all()]);
    let mut sparse = Shape::new(6, vec![select(&[Kz, Qx, Qy])]);
    sparse.rest = Vec6::new(0.0, 0.0, 0.4, 1.0, 0.0, 0.0);
    let model = Model::new(
        vec![
            rod_spec("long", &planar, Terms::ALL, tilted_base()),
            rod_spec("general", &general, Terms::ALL, tilted_base()),
            rod_spec("other_plane", &sparse, Terms::ALL, tilted_base()),
        ],
        gravity(Terms::ALL),
        3,
    )
    .unwrap();
    assert!(!model.rods()[1].is_planar());
    let n = model.n_dof();
    let mut rng = Lcg(3);
    let (q, qd, _) = state(&mut rng, n, 0.5, 10.0, 0.0);
    let e = compare(&model, &q, &qd);
    assert!(e < 1e-10, "{e:e}");
}

/// What is not planar stays on the general path: an off-plane rest strain,
/// a strain outside the plane, a general (non-selection) basis.
#[test]
fn non_planar_rods_are_not_detected() {
    use Strain::*;
    let cases = [
        (
            select(&[Ky, Qx, Qz]),
            Vec6::new(0.1, 0.0, 0.0, 1.0, 0.0, 0.0),
        ),
        (
            select(&[Ky, Qx, Qy]),
            Vec6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0),
        ),
        (Basis::all(), Vec6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0)),
    ];
    for (basis, rest) in cases {
        let mut shape = Shape::new(3, vec![basis.clone()]);
        shape.rest = rest;
        let model = Model::new(
            vec![rod_spec("arm", &shape, Terms::NONE, tilted_base())],
            None,
            4,
        )
        .unwrap();
        assert!(!model.rods()[0].is_planar(), "{basis:?}, {rest:?}");
    }
}

/// The largest relative difference between the planar (se(2), D95–D98)
/// and the general linearization of the inverse dynamics on `model`: the
/// dense `τ`, `∂τ/∂q`, `∂τ/∂q̇`, and the O(N) products of the linearization
/// without them (`uᵀ∂τ`, `∂τ·(a, b)`, `M v`, the inertia products), each
/// relative to the largest entry of the general path's result.
fn compare_linearization(model: &Model, q: &[f64], qd: &[f64], qdd: &[f64], rng: &mut Lcg) -> f64 {
    use nalgebra::DVector;
    use softrod_dynamics::{
        Forces, IdDerivatives, inverse_dynamics_derivatives_with, inverse_dynamics_inertia_vjp,
        inverse_dynamics_jvp, inverse_dynamics_linearization_with, inverse_dynamics_mass_product,
        inverse_dynamics_vjp,
    };
    let general = model.clone().with_planar_path(false);
    let n = model.n_dof();
    let t = 0.3;
    let rel = |a: &[f64], b: &[f64]| {
        let (a, b) = (DVector::from_column_slice(a), DVector::from_column_slice(b));
        (a - &b).amax() / b.amax().max(f64::MIN_POSITIVE)
    };
    let mut worst: f64 = 0.0;
    let (mut w1, mut w2) = (IdDerivatives::new(model), IdDerivatives::new(&general));
    let d1 = inverse_dynamics_derivatives_with(model, &mut w1, Forces::ALL, t, q, qd, qdd).unwrap();
    let d2 =
        inverse_dynamics_derivatives_with(&general, &mut w2, Forces::ALL, t, q, qd, qdd).unwrap();
    worst = worst
        .max(rel(d1.tau.as_slice(), d2.tau.as_slice()))
        .max(rel(d1.dtau_dq.as_slice(), d2.dtau_dq.as_slice()))
        .max(rel(d1.dtau_dqd.as_slice(), d2.dtau_dqd.as_slice()));
    let (mut p1, mut p2) = (
        IdDerivatives::for_products(model),
        IdDerivatives::for_products(&general),
    );
    inverse_dynamics_linearization_with(model, &mut p1, Forces::ALL, t, q, qd, qdd).unwrap();
    inverse_dynamics_linearization_with(&general, &mut p2, Forces::ALL, t, q, qd, qdd).unwrap();
    worst = worst.max(rel(p1.tau.as_slice(), p2.tau.as_slice()));
    let (u, a, b) = (rng.vec(n, 1.0), rng.vec(n, 1.0), rng.vec(n, 1.0));
    // uᵀ∂τ/∂q, uᵀ∂τ/∂q̇, ∂τ/∂q·a + ∂τ/∂q̇·b, M a, the inertia products.
    let products = |m: &Model, p: &mut IdDerivatives| {
        let mut out = vec![vec![0.0; n]; 4];
        let [oq, ov, j, mv] = &mut out[..] else {
            unreachable!()
        };
        inverse_dynamics_vjp(m, p, &u, oq, ov).unwrap();
        inverse_dynamics_jvp(m, p, &a, &b, j).unwrap();
        inverse_dynamics_mass_product(m, p, &a, mv).unwrap();
        let mut rods = vec![0.0; m.rods().len()];
        inverse_dynamics_inertia_vjp(m, p, &u, &mut rods, &mut []).unwrap();
        out.push(rods);
        out
    };
    let (x1, x2) = (products(model, &mut p1), products(&general, &mut p2));
    for (a, b) in x1.iter().zip(&x2) {
        worst = worst.max(rel(a, b));
    }
    worst
}

/// The linearization of planar rods on se(2) (D95–D98) against the
/// general path (six strain directions, 6×6 blocks) on the same model:
/// the three bending planes, strain subsets, every force term (oblique
/// gravity and world loads with out-of-plane parts, which the planar path
/// drops), straight, barely curved and wound-up pieces, at rest and moving
/// fast, one to twelve pieces.
#[test]
fn linearization_matches_the_general_path() {
    let mut rng = Lcg(41);
    for axis in 0..3 {
        let (bases, rest) = plane(axis);
        for (pieces, terms, young) in [
            (1, Terms::NONE, 2e6),
            (3, Terms::ALL, 2e6),
            (5, Terms::ALL, 1.0),
            (12, Terms::NONE, 10.0),
        ] {
            let mut shape = Shape::new(pieces, bases.clone());
            shape.rest = rest;
            shape.young = young;
            let model = Model::new(
                vec![rod_spec("arm", &shape, terms, tilted_base())],
                gravity(terms),
                4,
            )
            .unwrap();
            assert!(model.uses_planar_path(0));
            let n = model.n_dof();
            for (q_scale, qd_scale) in [(0.0, 0.0), (3.0, 5.0)] {
                let (q, qd, qdd) = state(&mut rng, n, q_scale, qd_scale, 20.0);
                let e = compare_linearization(&model, &q, &qd, &qdd, &mut rng);
                println!("axis {axis}, {pieces} pieces, q ±{q_scale}: {e:.1e}");
                assert!(
                    e < 1e-12,
                    "axis {axis}, {pieces} pieces, {terms:?}, E {young}, q ±{q_scale}: {e:e}"
                );
            }
        }
    }
    // Curvature from exactly zero to several turns per piece (both
    // branches of the coefficient series).
    use Strain::*;
    for (k, scale) in [
        (0.0, 0.0),
        (1e-9, 1e-9),
        (1e-4, 1e-3),
        (2.0, 1.0),
        (40.0, 30.0),
    ] {
        let mut shape = Shape::new(4, vec![select(&[Ky, Qx, Qz])]);
        shape.rest = Vec6::new(0.0, k, 0.0, 1.0, 0.0, 0.0);
        shape.young = 10.0;
        let model = Model::new(
            vec![rod_spec("arm", &shape, Terms::ALL, tilted_base())],
            gravity(Terms::ALL),
            4,
        )
        .unwrap();
        let n = model.n_dof();
        let q = rng.vec(n, scale);
        for qd_scale in [0.0, 50.0] {
            let qd = rng.vec(n, qd_scale);
            let qdd = rng.vec(n, 10.0);
            let e = compare_linearization(&model, &q, &qd, &qdd, &mut rng);
            println!("curvature {k}, rates {qd_scale}: {e:.1e}");
            assert!(e < 1e-12, "curvature {k}, rates {qd_scale}: {e:e}");
        }
    }
}
