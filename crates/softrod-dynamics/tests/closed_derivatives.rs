//! The derivatives of the constrained forward dynamics of closed models
//! (docs/theory-derivatives.md (CD1)–(CD4)) against central differences
//! of the production constrained `q̈` (`forward_dynamics`, D67–D68): a
//! four-bar-like loop, a pinned–pinned rod (the catenary), a weld to the
//! world, a slider, a redundant pair of closures, and closures on a
//! prescribed joint at two times; a state off the constraint manifold so
//! the Baumgarte terms count.

mod common;

use common::{soft_rod as rod, wavy};

use nalgebra::DMatrix;
use softrod_dynamics::{
    Attachment, ClosedDerivatives, Closure, ClosureFrame, ClosureKind, Curve, Data, Joint, Model,
    Prescribed, closed_dynamics_derivatives, forward_dynamics,
};
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::Drag;

fn rot(a: f64, b: f64, c: f64) -> Mat3 {
    *nalgebra::Rotation3::from_euler_angles(a, b, c).matrix()
}

fn at(p: [f64; 3]) -> Pose {
    Pose::new(Mat3::identity(), Vec3::from(p))
}

const DRAG: Drag = Drag {
    translational: 0.3,
    rotational: 1e-4,
};

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
    let model = Model::builder()
        .rod_on(
            rod("a", 0.3, 3).drag(DRAG),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.1])),
        )
        .rod_on(
            rod("b", 0.25, 2).base(at([0.2, 0.0, 0.0])),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .gravity([0.0, 0.0, -9.81])
        .closure(Closure::new(
            "coupler",
            ClosureKind::Ball,
            ClosureFrame::on("a", None, at([0.0, 0.0, 0.02])),
            ClosureFrame::on("b", Some(0.25), Pose::identity()),
        ))
        .build()
        .unwrap();
    let (q, qd) = state(&model, 0.2);
    check("four-bar", &model, 0.0, &q, &qd);
}

#[test]
fn pinned_pinned_rod() {
    // The catenary: a spherical joint at the base, a ball to the world at
    // the tip.
    let model = Model::builder()
        .rod_on(
            rod("cable", 0.5, 6).drag(DRAG),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity([0.0, 0.0, -9.81])
        .closure(Closure::new(
            "pin",
            ClosureKind::Ball,
            ClosureFrame::on("cable", None, Pose::identity()),
            ClosureFrame::world(at([0.45, 0.0, 0.0])),
        ))
        .build()
        .unwrap();
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
        let model = Model::builder()
            .rod(rod("a", 0.3, 3).drag(DRAG))
            .rod_on(
                rod("b", 0.2, 2).base(at([0.0, 0.2, 0.0])),
                Attachment::world_joint(Joint::free()),
            )
            .gravity([0.2, 0.0, -9.81])
            .closure(Closure::new(
                "c",
                kind.clone(),
                ClosureFrame::on(
                    "a",
                    Some(0.21),
                    Pose::new(rot(0.1, 0.2, 0.3), Vec3::zeros()),
                ),
                ClosureFrame::on("b", None, Pose::new(rot(-0.2, 0.0, 0.1), Vec3::zeros())),
            ))
            .closure(Closure::new(
                "ground",
                kind.clone(),
                ClosureFrame::on("b", Some(0.1), Pose::identity()),
                ClosureFrame::world(at([0.1, 0.3, 0.0])),
            ))
            .build()
            .unwrap();
        let (q, qd) = state(&model, 1.3);
        check(&format!("{kind:?}"), &model, 0.0, &q, &qd);
    }
}

#[test]
fn redundant_closures() {
    // A weld and a ball on the same frames: three redundant rows, which
    // the forward solve gives λ = 0 (D68).
    let weld = |kind| {
        Closure::new(
            "c",
            kind,
            ClosureFrame::on("a", None, Pose::identity()),
            ClosureFrame::world(at([0.28, 0.0, 0.05])),
        )
    };
    let mut ball = weld(ClosureKind::Ball);
    ball.name = "c2".into();
    let model = Model::builder()
        .rod_on(
            rod("a", 0.3, 3).drag(DRAG),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity([0.0, 0.0, -9.81])
        .closure(weld(ClosureKind::Weld))
        .closure(ball)
        .build()
        .unwrap();
    let (q, qd) = state(&model, 2.1);
    check("redundant", &model, 0.0, &q, &qd);
}

#[test]
fn closures_on_a_prescribed_joint() {
    // Like cosseratbench's twist: a rod hangs from a prescribed free joint
    // (rotation and motion) and is welded to the world at its tip, and a
    // second rod is held to it by a ball.
    let drive = Prescribed::new(
        (0..6)
            .map(|c| Curve::Sine {
                amplitude: 0.05 + 0.01 * c as f64,
                frequency: 0.7 + 0.1 * c as f64,
                phase: 0.3 * c as f64,
                offset: 0.0,
            })
            .collect(),
    );
    let model = Model::builder()
        .rod_on(
            rod("a", 0.3, 3).drag(DRAG),
            Attachment::world_joint(Joint::free().with_prescribed(drive)),
        )
        .rod_on(
            rod("b", 0.2, 2).base(at([0.0, 0.1, 0.0])),
            Attachment::world_joint(Joint::revolute([1.0, 0.0, 0.0])),
        )
        .gravity([0.0, 0.0, -9.81])
        .closure(Closure::new(
            "tip",
            ClosureKind::Weld,
            ClosureFrame::on("a", None, Pose::identity()),
            ClosureFrame::world(at([0.3, 0.0, 0.0])),
        ))
        .closure(Closure::new(
            "link",
            ClosureKind::Ball,
            ClosureFrame::on("a", Some(0.15), Pose::identity()),
            ClosureFrame::on("b", None, Pose::identity()),
        ))
        .build()
        .unwrap();
    let (q, qd) = state(&model, 0.4);
    for t in [0.0, 0.37] {
        check(&format!("prescribed t = {t}"), &model, t, &q, &qd);
    }
}
