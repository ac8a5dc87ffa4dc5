//! The derivatives of the constrained forward dynamics of closed models
//! (docs/theory-derivatives.md (CD1)–(CD4)) against central differences
//! of the production constrained `q̈` (`forward_dynamics`, D67–D68): a
//! four-bar-like loop, a pinned–pinned rod (the catenary), a weld to the
//! world, a slider, a redundant pair of closures, and closures on a
//! prescribed joint at two times; a state off the constraint manifold so
//! the Baumgarte terms count. With contact (docs/theory-contact.md CT16):
//! a pinned rope on a table with friction, two crossing pinned ropes with
//! rod–rod friction.

mod common;

use common::closed::{DRAG, at, catenary, driven, four_bar, redundant, rot, two_closures};
use common::{soft_rod as rod, wavy};

use nalgebra::DMatrix;
use softrod_dynamics::{
    Attachment, ClosedDerivatives, Closure, ClosureFrame, ClosureKind, Data, Joint, Model,
    closed_dynamics_derivatives, commit_contact, forward_dynamics,
};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::contact::{ContactSettings, Obstacle, Shape};

/// Central differences of the constrained `q̈` in `q` (step `1e-6`
/// relative) and `q̇` against the analytic result, relative to the largest
/// entry of each. `q̈` is quadratic in `q̇` (Coriolis and centrifugal forces,
/// `J̇q̇`; drag and damping are linear), so the differences in `q̇` are
/// exact at any step: a long one (0.05) keeps rounding out of them.
fn check(name: &str, model: &Model, t: f64, q: &[f64], qd: &[f64]) {
    let n = model.n_dof();
    let mut data = Data::new(model);
    let mut work = ClosedDerivatives::new(model);
    let d = closed_dynamics_derivatives(model, &mut data, &mut work, t, q, qd, None).unwrap();
    let qdd = forward_dynamics(model, &mut data, t, q, qd, None)
        .unwrap()
        .clone();
    assert!((&d.qdd - &qdd).amax() <= 1e-12 * qdd.amax().max(1.0));
    let mut fd = |wrt_q: bool| {
        let mut out = DMatrix::zeros(n, n);
        for j in 0..n {
            let base = if wrt_q { q[j] } else { qd[j] };
            let h = if wrt_q { 1e-6 } else { 0.05 } * base.abs().max(1.0);
            let mut cols = [qdd.clone(), qdd.clone()];
            for (c, s) in cols.iter_mut().zip([1.0, -1.0]) {
                let (mut qx, mut qdx) = (q.to_vec(), qd.to_vec());
                if wrt_q {
                    qx[j] += s * h;
                } else {
                    qdx[j] += s * h;
                }
                c.copy_from(forward_dynamics(model, &mut data, t, &qx, &qdx, None).unwrap());
            }
            out.set_column(j, &((&cols[0] - &cols[1]) / (2.0 * h)));
        }
        out
    };
    for (what, got, want) in [
        ("dqdd/dq", &d.dqdd_dq, fd(true)),
        ("dqdd/dqdot", &d.dqdd_dqd, fd(false)),
    ] {
        let scale = want.amax();
        let diff = got - &want;
        let err = diff.amax();
        assert!(scale > 0.0, "{name} {what}: zero");
        assert!(
            err <= 2e-6 * scale,
            "{name} {what}: error {err:e} of {scale:e}"
        );
    }
}

/// A state off the manifold (the Baumgarte terms act), moving.
fn state(model: &Model, seed: f64) -> (Vec<f64>, Vec<f64>) {
    let n = model.n_dof();
    (wavy(n, 0.3, seed), wavy(n, 0.8, seed + 1.0))
}

#[test]
fn four_bar_loop() {
    // Two rods on revolute joints to the world, their tips held by a ball:
    // with the ground, a four-bar of flexible links.
    let model = four_bar();
    let (q, qd) = state(&model, 0.2);
    check("four-bar", &model, 0.0, &q, &qd);
}

#[test]
fn pinned_pinned_rod() {
    // The catenary: a spherical joint at the base, a ball to the world at
    // the tip.
    let model = catenary(6);
    let (q, qd) = state(&model, 0.7);
    check("catenary", &model, 0.0, &q, &qd);
}

#[test]
fn weld_and_slider_closures() {
    for kind in [
        ClosureKind::Weld,
        ClosureKind::Slider {
            axis: Vec3::new(0.3, 1.0, -0.2),
        },
    ] {
        let model = two_closures(kind.clone());
        let (q, qd) = state(&model, 1.3);
        check(&format!("{kind:?}"), &model, 0.0, &q, &qd);
    }
}

#[test]
fn redundant_closures() {
    // A weld and a ball on the same frames: three redundant rows, which
    // the forward solve gives λ = 0 (D68).
    let model = redundant();
    let (q, qd) = state(&model, 2.1);
    check("redundant", &model, 0.0, &q, &qd);
}

#[test]
fn closures_on_a_prescribed_joint() {
    // Like cosseratbench's twist: a rod hangs from a prescribed free joint
    // (rotation and motion) and is welded to the world at its tip, and a
    // second rod is held to it by a ball.
    let model = driven();
    let (q, qd) = state(&model, 0.4);
    for t in [0.0, 0.37] {
        check(&format!("prescribed t = {t}"), &model, t, &q, &qd);
    }
}

/// Central differences of the constrained `q̈` of a model with contact
/// (docs/theory-contact.md CT16) against the analytic derivatives, column
/// by column, with the contact state committed in `data` (anchors). The
/// stiff contact makes `q̈` curve fast in `q` (a truncation error `∝ h²`
/// that reaches 1e-5 of a column at `h = 1e-6`) while its size (|q̈| to
/// 1e5) leaves round-off `ε|q̈|/h` at small steps: Richardson's
/// extrapolation of the steps `h` and `h/2` removes the `h²` term
/// (`h = 2e-6` in `q`; `3e-3` in `q̇`, where `q̈` is quadratic but for the
/// slip direction and the law's switches: 1e-4 meets round-off, 3e-5 of
/// a column, 1e-2 steps over a switch of the rope's damping); each column
/// within `1e-5 (|col| + 1)`.
fn check_contact(name: &str, model: &Model, data: &mut Data, q: &[f64], qd: &[f64]) {
    let n = model.n_dof();
    let mut work = ClosedDerivatives::new(model);
    let d = closed_dynamics_derivatives(model, data, &mut work, 0.0, q, qd, None).unwrap();
    let (dq, dqd) = (d.dqdd_dq.clone(), d.dqdd_dqd.clone());
    let qdd = forward_dynamics(model, data, 0.0, q, qd, None)
        .unwrap()
        .clone();
    assert!((&d.qdd - &qdd).amax() <= 1e-12 * qdd.amax().max(1.0));
    let mut worst: f64 = 0.0;
    for l in 0..n {
        for (which, analytic) in [(0, &dq), (1, &dqd)] {
            let mut diff = |h: f64| {
                let (mut a, mut b) = ((q.to_vec(), qd.to_vec()), (q.to_vec(), qd.to_vec()));
                if which == 0 {
                    a.0[l] += h;
                    b.0[l] -= h;
                } else {
                    a.1[l] += h;
                    b.1[l] -= h;
                }
                let plus = forward_dynamics(model, data, 0.0, &a.0, &a.1, None)
                    .unwrap()
                    .clone();
                let minus = forward_dynamics(model, data, 0.0, &b.0, &b.1, None)
                    .unwrap()
                    .clone();
                (plus - minus) / (2.0 * h)
            };
            let h = if which == 0 { 2e-6 } else { 3e-3 };
            let fd = (diff(h / 2.0) * 4.0 - diff(h)) / 3.0;
            let col = analytic.column(l);
            let err = (&fd - col).norm() / (col.norm() + 1.0);
            worst = worst.max(err);
            assert!(err < 1e-5, "{name}: column {l} of d/d{which}: {err:.3e}");
        }
    }
    eprintln!("{name}: worst relative column error {worst:.3e}");
}

/// The contacts at `(q, q̇)` in the contact state of `data`: how many,
/// and how many stick.
fn touching(model: &Model, data: &mut Data, q: &[f64], qd: &[f64]) -> (usize, usize) {
    let c = model.contacts_with(data, 0.0, q, qd).unwrap();
    (c.len(), c.iter().filter(|c| c.sticking).count())
}

#[test]
fn pinned_rope_pressed_on_a_table_with_friction() {
    // The catenary of `pinned_pinned_rod` lying into a tilted table with
    // friction, and a ball below it: sticking and sliding contacts on a
    // closed chain.
    let table = Obstacle::new(
        "table",
        Shape::Plane {
            point: Vec3::new(0.0, 0.0, -0.0097),
            normal: Vec3::new(0.03, 0.02, 1.0).normalize(),
        },
    )
    .friction(0.4)
    .restitution(0.3);
    let ball = Obstacle::new(
        "ball",
        Shape::Sphere {
            center: Vec3::new(0.3, 0.0, 0.1097),
            radius: 0.1,
        },
    )
    .friction(0.6);
    let model = Model::builder()
        .rod_on(
            rod("cable", 0.5, 5).drag(DRAG),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity([0.0, 0.0, -9.81])
        .closure(Closure::new(
            "pin",
            ClosureKind::Ball,
            ClosureFrame::on("cable", None, Pose::identity()),
            ClosureFrame::world(at([0.499, 0.001, 0.0])),
        ))
        .obstacle(table)
        .obstacle(ball)
        .build()
        .unwrap();
    let n = model.n_dof();
    let q = wavy(n, 1e-3, 0.4);
    let qd = wavy(n, 0.05, 1.1);
    let mut data = Data::new(&model);
    // Anchors where the rope was a moment ago: some contacts stick, some
    // slide.
    let before: Vec<f64> = q
        .iter()
        .zip(wavy(n, 2e-4, 2.0))
        .map(|(a, b)| a - b)
        .collect();
    commit_contact(&model, &mut data, 0.0, &before, &qd).unwrap();
    let (touch, stick) = touching(&model, &mut data, &q, &qd);
    assert!(touch >= 3 && stick > 0 && stick < touch, "{touch} {stick}");
    check_contact("rope on a table", &model, &mut data, &q, &qd);
}

#[test]
fn crossing_pinned_ropes_with_rod_friction() {
    // cosseratbench's crossing: two ropes pinned at both ends, one
    // across the other, pressed together (1 mm interference), rod–rod
    // friction, moving.
    let (r, l) = (0.01, 0.4);
    let across = Pose::new(rot(0.0, 0.0, std::f64::consts::FRAC_PI_2), Vec3::zeros());
    let b_base = Pose::new(across.rotation, Vec3::new(0.2, -0.2, 2.0 * r - 0.001));
    let model = Model::builder()
        .rod_on(
            rod("lower", l, 4),
            Attachment::world_joint(Joint::spherical()),
        )
        .rod_on(
            rod("upper", l, 4).base(b_base),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity([0.0, 0.0, -9.81])
        .closure(Closure::new(
            "lower pin",
            ClosureKind::Ball,
            ClosureFrame::on("lower", None, Pose::identity()),
            ClosureFrame::world(at([l, 0.0, 0.0])),
        ))
        .closure(Closure::new(
            "upper pin",
            ClosureKind::Ball,
            ClosureFrame::on("upper", None, Pose::identity()),
            ClosureFrame::world(at([0.2, 0.2, 2.0 * r - 0.001])),
        ))
        .contact(ContactSettings {
            rods: true,
            friction: 0.5,
            ..Default::default()
        })
        .build()
        .unwrap();
    let n = model.n_dof();
    let mut data = Data::new(&model);
    for (name, shift) in [("sticking", 1e-6), ("sliding", 3e-4)] {
        let q = wavy(n, 1e-3, 0.9);
        let qd = wavy(n, 0.05, 0.3);
        let before: Vec<f64> = q
            .iter()
            .zip(wavy(n, shift, 2.5))
            .map(|(a, b)| a - b)
            .collect();
        data.reset_contact();
        commit_contact(&model, &mut data, 0.0, &before, &qd).unwrap();
        let (touch, stick) = touching(&model, &mut data, &q, &qd);
        assert_eq!(touch, 1, "{name}");
        assert_eq!(stick == 1, name == "sticking", "{name}");
        check_contact(
            &format!("crossing ropes, {name}"),
            &model,
            &mut data,
            &q,
            &qd,
        );
    }
}
