//! The force a prescribed joint reports (docs/theory.md D59–D60) with
//! contact (docs/theory-contact.md CT18): at a static equilibrium the
//! drive holds the rod against gravity *and* the obstacles, so its moment
//! balances the moment of the weight and of the table's forces about the
//! joint's axis — rigid statics of the whole rod, independent of the
//! recursion that computes the drive's force. Open and closed models.

use softrod_dynamics::{
    Attachment, BodySpec, Closure, ClosureFrame, ClosureKind, Curve, Data, Joint, Model,
    Prescribed, Rod, RodBuilder, StaticsOptions, closure_statics, forward_dynamics,
    inverse_dynamics, section_jacobian, statics,
};
use softrod_kinematics::Strain;
use softrod_lie::{Pose, Vec3, Vec6, exp_twist};
use softrod_mechanics::Material;
use softrod_mechanics::contact::{Obstacle, Shape};

const L: f64 = 0.3;
const R: f64 = 0.01;
const RHO: f64 = 1000.0;
const G: f64 = 9.81;
/// The drive's angle about y: the arm points down by THETA.
const THETA: f64 = 0.1;

fn material() -> Material {
    Material::builder()
        .density(RHO)
        .young(1e7)
        .poisson(0.5)
        .build()
        .unwrap()
}

/// A hinge about y held at `THETA` by its drive (a constant curve).
fn held_hinge() -> Joint {
    Joint::revolute([0.0, 1.0, 0.0]).with_prescribed(Prescribed::new(vec![Curve::Sine {
        amplitude: 0.0,
        frequency: 1.0,
        phase: 0.0,
        offset: THETA,
    }]))
}

fn arm() -> RodBuilder {
    Rod::builder(L)
        .name("arm")
        .pieces(8)
        .strains([Strain::Ky])
        .circle(R)
        .material(material())
}

/// The table stops the straight arm's tip half way down its drop.
fn table() -> Obstacle {
    Obstacle::new(
        "table",
        Shape::Plane {
            point: Vec3::new(0.0, 0.0, -0.5 * L * THETA.sin() - R),
            normal: Vec3::z(),
        },
    )
}

/// `∫ x dm` of the arm at `q` (Simpson, 200 intervals) \[kg m\].
fn first_moment(model: &Model, q: &[f64]) -> f64 {
    let mut data = Data::new(model);
    let n = 200;
    let mass = RHO * std::f64::consts::PI * R * R * L;
    (0..=n)
        .map(|i| {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let s = L * i as f64 / n as f64;
            w * section_jacobian(model, &mut data, q, 0, s)
                .unwrap()
                .0
                .translation
                .x
        })
        .sum::<f64>()
        / (3.0 * n as f64)
        * mass
}

/// The moment about the hinge's y axis (at the origin) the drive must
/// exert to hold the arm at `q`: minus the moments of the weight
/// (`+g ∫x dm`) and of the table's forces (`−Σ x f_z`), and of `extra`
/// (a world force at a world point); the table's force and moment sum.
/// The contact forces are those of `data`, with the stiffness statics
/// left in it (CT15).
fn hand_balance(
    model: &Model,
    data: &mut Data,
    q: &[f64],
    extra: Option<(Vec3, Vec3)>,
) -> (f64, f64, f64) {
    let zero = vec![0.0; q.len()];
    let contacts = model.contacts_with(data, 0.0, q, &zero).unwrap();
    assert!(!contacts.is_empty(), "the arm rests on the table");
    let table: f64 = contacts.iter().map(|c| -c.point.x * c.force.z).sum();
    let lift: f64 = contacts.iter().map(|c| c.force.z).sum();
    let mut external = G * first_moment(model, q) + table;
    if let Some((p, f)) = extra {
        external += p.cross(&f).y;
    }
    (-external, table, lift)
}

#[test]
fn a_held_arm_resting_on_a_table_reports_the_moment_of_weight_and_table() {
    let model = Model::builder()
        .rod_on(arm(), Attachment::world_joint(held_hinge()))
        .gravity([0.0, 0.0, -G])
        .obstacle(table())
        .build()
        .unwrap();
    assert_eq!(model.n_prescribed(), 1);
    let mut data = Data::new(&model);
    let rest = vec![0.0; model.n_dof()];
    let res = statics(&model, &mut data, &rest, &StaticsOptions::default()).unwrap();
    let q = res.q.as_slice();
    let zero = vec![0.0; q.len()];
    let (want, table, lift) = hand_balance(&model, &mut data, q, None);
    let weight = RHO * std::f64::consts::PI * R * R * L * G;
    eprintln!(
        "want {want:.6e} N m, the table's moment {table:.3e} N m, lift {lift:.3e} N of weight {weight:.3e} N"
    );
    // The table carries a good part of the weight: leaving it out would
    // be far off.
    // The table carries a good part of the weight's moment (leaving it
    // out would be far off).
    let scale = (want + table).abs();
    assert!(table.abs() > 0.1 * scale, "{table} vs {scale}");
    // The drive's moment from the forward dynamics (q̈ = 0 at the
    // equilibrium) and from the inverse dynamics at q̈ = 0.
    let qdd = forward_dynamics(&model, &mut data, 0.0, q, &zero, None)
        .unwrap()
        .amax();
    let fd = data.prescribed_force[0];
    inverse_dynamics(&model, &mut data, 0.0, q, &zero, &zero).unwrap();
    let id = data.prescribed_force[0];
    eprintln!("forward {fd:.9e}, inverse {id:.9e} (|q̈| {qdd:.1e})");
    for got in [fd, id] {
        assert!((got - want).abs() < 1e-6 * scale, "{got} vs {want}");
    }
}

/// The same arm with a body welded to its tip, the body hanging from the
/// world by a free joint (a loop: the weld carries the body's weight into
/// the arm, so the closure's multipliers enter the drive's force through
/// `J_pᵀλ`): the drive's moment balances the weights, the body's at the
/// tip, and the table.
#[test]
fn a_held_arm_closed_on_a_free_body_reports_the_moment_of_weights_and_table() {
    let tip_rotation = exp_twist(1.0, &Vec6::new(0.0, THETA, 0.0, 0.0, 0.0, 0.0)).rotation;
    let tip = Pose::new(tip_rotation, tip_rotation * Vec3::new(L, 0.0, 0.0));
    let body_mass = 0.02;
    let mut body = BodySpec::principal("weight", body_mass, [1e-6, 1e-6, 1e-6]);
    body.base = tip;
    let model = Model::builder()
        .rod_on(arm(), Attachment::world_joint(held_hinge()))
        .body(body, Attachment::world_joint(Joint::free()))
        .gravity([0.0, 0.0, -G])
        .obstacle(table())
        .closure(Closure::new(
            "weld",
            ClosureKind::Weld,
            ClosureFrame::on("arm", None, Pose::identity()),
            ClosureFrame::on("weight", None, Pose::identity()),
        ))
        .build()
        .unwrap();
    let mut data = Data::new(&model);
    let rest = vec![0.0; model.n_dof()];
    let (res, _) = closure_statics(&model, &mut data, &rest, &StaticsOptions::default()).unwrap();
    let q = res.q.as_slice();
    let zero = vec![0.0; q.len()];
    let p_tip = section_jacobian(&model, &mut Data::new(&model), q, 0, L)
        .unwrap()
        .0
        .translation;
    let weight = Vec3::new(0.0, 0.0, -body_mass * G);
    let (want, table, _) = hand_balance(&model, &mut data, q, Some((p_tip, weight)));
    let scale = (want + table).abs();
    assert!(table.abs() > 0.1 * scale, "{table} vs {scale}");
    forward_dynamics(&model, &mut data, 0.0, q, &zero, None).unwrap();
    let fd = data.prescribed_force[0];
    eprintln!("forward {fd:.9e}, want {want:.9e} (table {table:.3e})");
    assert!((fd - want).abs() < 1e-6 * scale, "{fd} vs {want}");
}

/// The table carried by a body (a tray) on a vertical slide held still by
/// its drive, the arm clamped to the world resting on it: the drive holds
/// the tray's weight and the push of the arm, `F = m g + Σ f_z` — the
/// contact force acts on the obstacle's body with the opposite sign.
#[test]
fn a_held_tray_under_a_resting_arm_reports_its_weight_and_the_arms_push() {
    let tilt = exp_twist(1.0, &Vec6::new(0.0, THETA, 0.0, 0.0, 0.0, 0.0)).rotation;
    let tray_mass = 0.5;
    let slide =
        Joint::prismatic([0.0, 0.0, 1.0]).with_prescribed(Prescribed::new(vec![Curve::Sine {
            amplitude: 0.0,
            frequency: 1.0,
            phase: 0.0,
            offset: 0.0,
        }]));
    let model = Model::builder()
        .rod_on(
            arm().base(Pose::new(tilt, Vec3::zeros())),
            Attachment::world_joint(Joint::fixed()),
        )
        .body(
            BodySpec::principal("tray", tray_mass, [1e-3, 1e-3, 1e-3]),
            Attachment::world_joint(slide),
        )
        .gravity([0.0, 0.0, -G])
        .obstacle(table().on("tray"))
        .build()
        .unwrap();
    let mut data = Data::new(&model);
    let rest = vec![0.0; model.n_dof()];
    let res = statics(&model, &mut data, &rest, &StaticsOptions::default()).unwrap();
    let q = res.q.as_slice();
    let zero = vec![0.0; q.len()];
    let (_, _, lift) = hand_balance(&model, &mut data, q, None);
    forward_dynamics(&model, &mut data, 0.0, q, &zero, None).unwrap();
    let fd = data.prescribed_force[0];
    let want = tray_mass * G + lift;
    eprintln!("forward {fd:.9e} N, want {want:.9e} N (the arm's push {lift:.3e} N)");
    assert!(lift > 0.05 * want, "{lift}");
    assert!((fd - want).abs() < 1e-9 * want, "{fd} vs {want}");
}
