//! Cable-tension inputs `u` (`Data::set_cable_tensions`) are the same as
//! cables whose schedules hold those tensions: checked against a second
//! model built with `Tension::Constant(u_c)`, for the forward dynamics and
//! its derivatives, and the input matrix `B` against differences in `u`.

use softrod_dynamics::*;
use softrod_lie::Vec3;
use softrod_mechanics::{Cable, Material, Routing, Tension};

fn model(tensions: [Tension; 3]) -> Model {
    let material = Material::builder()
        .density(1100.0)
        .young(2e6)
        .poisson(0.45)
        .viscosity(5.0)
        .build()
        .unwrap();
    let [a, b, c] = tensions;
    let arm = |name: &str| {
        Rod::builder(0.3)
            .name(name)
            .pieces(3)
            .circle(0.01)
            .material(material)
    };
    Model::builder()
        .rod(
            arm("left")
                .cable(Cable::new(Routing::Offset { y: 0.006, z: 0.0 }, a))
                .cable(
                    Cable::new(
                        Routing::Offset {
                            y: -0.004,
                            z: 0.005,
                        },
                        b,
                    )
                    .between(0.0, 0.2),
                ),
        )
        .rod(arm("right").cable(Cable::new(Routing::Offset { y: 0.0, z: 0.007 }, c)))
        .gravity(Vec3::new(0.0, 0.0, -9.81))
        .build()
        .unwrap()
}

fn state(n: usize) -> (Vec<f64>, Vec<f64>) {
    let q = (0..n).map(|i| 0.4 * (1.3 * i as f64).sin()).collect();
    let qd = (0..n).map(|i| 0.7 * (0.9 * i as f64 + 0.2).cos()).collect();
    (q, qd)
}

const U: [f64; 3] = [1.5, 0.4, 2.25];

/// The schedules' tensions at t = 0.3 are not U (a table and constants of
/// other values): the inputs must win over them.
fn scheduled() -> Model {
    model([
        Tension::Table {
            times: vec![0.0, 1.0],
            values: vec![0.0, 9.0],
        },
        Tension::Constant(7.0),
        Tension::Constant(0.0),
    ])
}

fn held() -> Model {
    model(U.map(Tension::Constant))
}

#[test]
fn inputs_replace_the_schedules() {
    // Same arithmetic in the same order: identical to round-off.
    const SAME_TOL: f64 = 1e-12;
    let (with_inputs, reference) = (scheduled(), held());
    let (q, qd) = state(with_inputs.n_dof());
    let mut d = Data::new(&with_inputs);
    d.set_cable_tensions(&with_inputs, Some(&U)).unwrap();
    assert_eq!(d.cable_tensions(), Some(&U[..]));
    let a = forward_dynamics(&with_inputs, &mut d, 0.3, &q, &qd, None)
        .unwrap()
        .clone();
    let mut dr = Data::new(&reference);
    let b = forward_dynamics(&reference, &mut dr, 0.3, &q, &qd, None)
        .unwrap()
        .clone();
    assert!(
        (&a - &b).amax() < SAME_TOL * b.amax(),
        "{}",
        (&a - &b).amax()
    );
    // Back to the schedules: a different answer.
    d.set_cable_tensions(&with_inputs, None).unwrap();
    let c = forward_dynamics(&with_inputs, &mut d, 0.3, &q, &qd, None).unwrap();
    assert!((c - &b).amax() > 1e-3 * b.amax());

    let mut w = FdDerivatives::new(&with_inputs);
    let mut wr = FdDerivatives::new(&reference);
    d.set_cable_tensions(&with_inputs, Some(&U)).unwrap();
    forward_dynamics_derivatives(&with_inputs, &mut d, &mut w, 0.3, &q, &qd, None).unwrap();
    forward_dynamics_derivatives(&reference, &mut dr, &mut wr, 0.3, &q, &qd, None).unwrap();
    for (x, y) in [
        (&w.dqdd_dq, &wr.dqdd_dq),
        (&w.dqdd_dqd, &wr.dqdd_dqd),
        (&w.dqdd_du, &wr.dqdd_du),
    ] {
        assert!((x - y).amax() < SAME_TOL * y.amax().max(1.0));
    }
    let lin = linearize(&with_inputs, &mut d, &mut w, 0.3, &q, &qd, None).unwrap();
    assert_eq!(lin.u.as_slice(), &U);
}

/// `B = ∂ẋ/∂u` against differences of the forward dynamics in u.
#[test]
fn input_matrix_matches_differences_in_u() {
    // q̈ is affine in u, so a forward difference with a large step (1 N)
    // is exact up to the round-off of q̈ itself: the stiff shear modes make
    // |q̈| large and M ill-conditioned, ~1e-12 of |q̈| here.
    const FD_TOL: f64 = 1e-9;
    let m = scheduled();
    let n = m.n_dof();
    let (q, qd) = state(n);
    let mut d = Data::new(&m);
    let mut w = FdDerivatives::new(&m);
    d.set_cable_tensions(&m, Some(&U)).unwrap();
    let lin = linearize(&m, &mut d, &mut w, 0.3, &q, &qd, None).unwrap();
    let base = forward_dynamics(&m, &mut d, 0.3, &q, &qd, None)
        .unwrap()
        .clone();
    for c in 0..3 {
        let mut u = U;
        u[c] += 1.0;
        d.set_cable_tensions(&m, Some(&u)).unwrap();
        let fd = forward_dynamics(&m, &mut d, 0.3, &q, &qd, None).unwrap() - &base;
        let col = lin.b.column(c).rows(n, n).into_owned();
        let scale = base.amax().max(fd.amax());
        assert!(
            (&fd - &col).amax() < FD_TOL * scale,
            "cable {c}: {:e} of {scale:e}",
            (&fd - &col).amax()
        );
        // The upper half of B (∂q̇/∂u) is zero.
        assert!(lin.b.column(c).rows(0, n).iter().all(|v| *v == 0.0));
    }
}

#[test]
fn bad_inputs_are_errors() {
    let m = held();
    let mut d = Data::new(&m);
    assert!(matches!(
        d.set_cable_tensions(&m, Some(&[1.0, 2.0])),
        Err(DynamicsError::TensionCount {
            got: 2,
            expected: 3
        })
    ));
    assert!(matches!(
        d.set_cable_tensions(&m, Some(&[1.0, -2.0, 0.0])),
        Err(DynamicsError::InvalidTension { index: 1, .. })
    ));
    assert!(matches!(
        d.set_cable_tensions(&m, Some(&[1.0, f64::NAN, 0.0])),
        Err(DynamicsError::InvalidTension { index: 1, .. })
    ));
    assert_eq!(d.cable_tensions(), None);
}
