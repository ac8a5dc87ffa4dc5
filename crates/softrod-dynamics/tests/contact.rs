//! Contact of rods with obstacles (docs/theory-contact.md): the model's
//! checks, the analytic contact Jacobians against central differences of
//! the dynamics, and a propped cantilever against linear beam theory.

use nalgebra::DVector;
use softrod_dynamics::{
    Attachment, BodySpec, Data, DynamicsError, FdDerivatives, Joint, JointKind, Model, Rod,
    StaticsOptions, commit_contact, forward_dynamics, forward_dynamics_derivatives, statics,
};
use softrod_kinematics::Strain;
use softrod_lie::{Pose, Vec3, exp_twist};
use softrod_mechanics::contact::{ContactSettings, Contactee, Obstacle, Shape};
use softrod_mechanics::{Material, Section};

fn silicone() -> Material {
    Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .build()
        .unwrap()
}

fn plane(z: f64) -> Shape {
    Shape::Plane {
        point: Vec3::new(0.0, 0.0, z),
        normal: Vec3::z(),
    }
}

#[test]
fn obstacles_are_checked_and_parents_resolved() {
    let rod = || {
        Rod::builder(0.3)
            .pieces(3)
            .circle(0.01)
            .material(silicone())
    };
    let bad = Obstacle::new(
        "ball",
        Shape::Sphere {
            center: Vec3::zeros(),
            radius: -1.0,
        },
    );
    let err = Model::builder()
        .rod(rod())
        .obstacle(Obstacle::new("table", plane(-1.0)))
        .obstacle(bad)
        .build()
        .unwrap_err();
    assert!(
        matches!(&err, DynamicsError::Obstacle { index: 1, name, .. } if name == "ball"),
        "{err}"
    );
    assert!(std::error::Error::source(&err).is_some());
    let err = Model::builder()
        .rod(rod())
        .body(
            BodySpec::principal("cube", 1.0, [0.1, 0.1, 0.1]),
            Attachment::world_joint(Joint::new(JointKind::Free)),
        )
        .obstacle(Obstacle::new("pad", plane(0.0)).on("cub"))
        .build()
        .unwrap_err();
    let text = err.to_string();
    assert!(text.contains("'cub'") && text.contains("cube"), "{text}");
    let model = Model::builder().rod(rod()).build().unwrap();
    assert!(!model.has_contact());
    assert!(
        model
            .contacts(0.0, &[0.0; 9], &[0.0; 9])
            .unwrap()
            .is_empty()
    );
    let settings = ContactSettings {
        friction: -1.0,
        ..Default::default()
    };
    assert!(model.clone().with_contact(Vec::new(), settings).is_err());
    assert!(
        Model::builder()
            .rod(rod().contact_radius(0.0))
            .build()
            .is_err()
    );
}

#[test]
fn a_rod_that_starts_inside_an_obstacle_is_refused() {
    let model = Model::builder()
        .rod(
            Rod::builder(0.3)
                .pieces(3)
                .circle(0.01)
                .material(silicone()),
        )
        .obstacle(Obstacle::new("table", plane(-0.009)))
        .build()
        .unwrap();
    let q = vec![0.0; model.n_dof()];
    // 1 mm deep along the whole rod: 10 % of the radius, over the 1 %.
    let err = model.check_initial_contact(&q).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("'table'") && text.contains("1.000e-3"),
        "{text}"
    );
    assert!((model.max_penetration(0.0, &q).unwrap() - 1e-3).abs() < 1e-12);
    let c = &model.contacts(0.0, &q, &q).unwrap()[0];
    assert_eq!(c.b, Contactee::Obstacle(0));
    assert!((c.normal - Vec3::z()).norm() < 1e-15);
    // Within the allowed penetration: accepted.
    let model = Model::builder()
        .rod(
            Rod::builder(0.3)
                .pieces(3)
                .circle(0.01)
                .material(silicone()),
        )
        .obstacle(Obstacle::new("table", plane(-0.00995)))
        .build()
        .unwrap();
    model.check_initial_contact(&q).unwrap();
}

/// A clamped 3-D rod (all six strains) pressed into every kind of
/// obstacle, moving, with friction anchors committed at a nearby state so
/// that some contacts stick and some slide: the analytic `∂q̈/∂q`,
/// `∂q̈/∂q̇` (with the contact terms of CT6) against central differences of
/// the forward dynamics.
#[test]
fn contact_jacobians_match_central_differences() {
    let axis = Vec3::new(0.0, 1.0, 0.2).normalize();
    let obstacles = vec![
        Obstacle::new(
            "slope",
            Shape::Plane {
                point: Vec3::new(0.0, 0.0, -0.0095),
                normal: Vec3::new(0.05, 0.02, 1.0).normalize(),
            },
        )
        .friction(0.4)
        .restitution(0.3),
        Obstacle::new(
            "ball",
            Shape::Sphere {
                center: Vec3::new(0.25, 0.0, 0.1095),
                radius: 0.1,
            },
        )
        .friction(0.8),
        Obstacle::new(
            "pole",
            Shape::Cylinder {
                point: Vec3::new(0.15, 0.0, 0.0),
                axis: Vec3::new(0.1, 0.0, 1.0).normalize(),
                radius: 0.02,
            },
        ),
        Obstacle::new(
            "bar",
            Shape::Capsule {
                center: Vec3::new(0.33, -0.02, -0.028),
                axis,
                length: 0.1,
                radius: 0.02,
            },
        )
        .friction(0.3),
        Obstacle::new(
            "crate",
            Shape::Box {
                center: Vec3::new(0.41, 0.0, 0.0497),
                rotation: exp_twist(1.0, &softrod_lie::Vec6::new(0.0, 0.0, 0.3, 0.0, 0.0, 0.0))
                    .rotation,
                half_extents: Vec3::new(0.03, 0.05, 0.04),
            },
        )
        .friction(0.5),
    ];
    let model = Model::builder()
        .rod(
            Rod::builder(0.45)
                .pieces(4)
                .strains(Strain::ALL)
                .circle(0.01)
                .material(silicone()),
        )
        .gravity([0.0, 0.0, -9.81])
        .build()
        .unwrap()
        .with_contact(obstacles, ContactSettings::default())
        .unwrap();
    let n = model.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 1e-3 * ((i as f64) * 1.3).sin()).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.05 * ((i as f64) * 0.7).cos()).collect();
    let mut data = Data::new(&model);
    // Anchors where the rod was a moment ago.
    let q_before: Vec<f64> = q
        .iter()
        .enumerate()
        .map(|(i, v)| v - 2e-4 * ((i as f64) * 2.1).cos())
        .collect();
    commit_contact(&model, &mut data, 0.0, &q_before, &qd).unwrap();
    let contacts = model.contacts_with(&mut data, 0.0, &q, &qd).unwrap();
    let kinds: std::collections::BTreeSet<_> = contacts
        .iter()
        .map(|c| match c.b {
            Contactee::Obstacle(o) => o,
            Contactee::Rod { .. } => usize::MAX,
        })
        .collect();
    assert_eq!(kinds.len(), 5, "every obstacle touches: {contacts:?}");
    assert!(contacts.iter().any(|c| c.sticking));
    let mut work = FdDerivatives::new(&model);
    let j = forward_dynamics_derivatives(&model, &mut data, &mut work, 0.0, &q, &qd, None).unwrap();
    let (dq, dqd) = (j.dqdd_dq.clone(), j.dqdd_dqd.clone());
    let mut acc = |q: &[f64], qd: &[f64]| -> DVector<f64> {
        forward_dynamics(&model, &mut data, 0.0, q, qd, None)
            .unwrap()
            .clone()
    };
    let h = 1e-7;
    let mut worst: f64 = 0.0;
    for l in 0..n {
        for (which, analytic) in [(0, &dq), (1, &dqd)] {
            let (mut a, mut b) = ((q.clone(), qd.clone()), (q.clone(), qd.clone()));
            if which == 0 {
                a.0[l] += h;
                b.0[l] -= h;
            } else {
                a.1[l] += h;
                b.1[l] -= h;
            }
            let fd = (acc(&a.0, &a.1) - acc(&b.0, &b.1)) / (2.0 * h);
            let col = analytic.column(l);
            let err = (&fd - col).norm() / (col.norm() + 1.0);
            worst = worst.max(err);
            assert!(err < 1e-5, "column {l} of d/d{which}: {err:.3e}");
        }
    }
    eprintln!("worst relative column error {worst:.3e}");
}

/// A cantilever tilted down by θ whose tip rests on a frictionless table
/// at a height above the straight rod's tip (no gravity): the table holds
/// the tip with the force of linear beam theory, `R = 3EI δ / L³` for the
/// tip deflection `δ` it imposes, and statics finds it from the rest shape.
#[test]
fn propped_cantilever_tip_force_follows_beam_theory() {
    let (l, r, theta) = (0.5, 0.01, 0.01);
    let tilt = Pose::new(
        exp_twist(1.0, &softrod_lie::Vec6::new(0.0, theta, 0.0, 0.0, 0.0, 0.0)).rotation,
        Vec3::zeros(),
    );
    let drop = l * theta.sin();
    // The table stops the tip half way down.
    let table = -0.5 * drop - r;
    let model = Model::builder()
        .rod(
            Rod::builder(l)
                .pieces(20)
                .strains([Strain::Ky])
                .base(tilt)
                .circle(r)
                .material(silicone()),
        )
        .obstacle(Obstacle::new("table", plane(table)))
        .build()
        .unwrap();
    let res = statics(&model, None, &StaticsOptions::default()).unwrap();
    assert!(res.converged);
    let q = res.q.as_slice();
    let contacts = model.contacts(0.0, q, &vec![0.0; q.len()]).unwrap();
    let force: Vec3 = contacts.iter().map(|c| c.force).sum();
    let tip = contacts.iter().map(|c| c.s).fold(0.0, f64::max);
    assert!((tip - l).abs() < 1e-12, "the tip touches, nothing else");
    // δ: how far the table holds the tip above where it would be.
    let z_tip = contacts
        .iter()
        .find(|c| c.s == tip)
        .map(|c| c.point.z + r)
        .unwrap();
    let delta = z_tip + drop;
    let ei = silicone().young() * std::f64::consts::PI * r.powi(4) / 4.0;
    let expected = 3.0 * ei * delta / l.powi(3);
    let rel = (force.z - expected).abs() / expected;
    eprintln!(
        "R = {:.6e} N, beam theory {expected:.6e} N ({rel:.2e})",
        force.z
    );
    assert!(rel < 5e-3, "{rel}");
    // Penetration within the 1 % bound.
    assert!(model.max_penetration(0.0, q).unwrap() < 0.01 * r);
}
