//! Closed models shared by the tests of the closed-chain derivatives
//! (CD1–CD4) and of the structured closed Newton solve (CD5–CD8): a
//! four-bar of soft links, a pinned–pinned rod (the catenary), two
//! closures of one kind (weld, slider), a rod on a prescribed free joint
//! welded at its tip with a second rod on a ball, and redundant closures.

use super::soft_rod as rod;
use softrod_dynamics::{
    Attachment, Closure, ClosureFrame, ClosureKind, Curve, Joint, Model, Prescribed,
};
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::Drag;

pub fn rot(a: f64, b: f64, c: f64) -> Mat3 {
    *nalgebra::Rotation3::from_euler_angles(a, b, c).matrix()
}

pub fn at(p: [f64; 3]) -> Pose {
    Pose::new(Mat3::identity(), Vec3::from(p))
}

pub const DRAG: Drag = Drag {
    translational: 0.3,
    rotational: 1e-4,
};

pub fn four_bar() -> Model {
    Model::builder()
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
        .unwrap()
}

pub fn catenary(pieces: usize) -> Model {
    Model::builder()
        .rod_on(
            rod("cable", 0.5, pieces).drag(DRAG),
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
        .unwrap()
}

pub fn two_closures(kind: ClosureKind) -> Model {
    Model::builder()
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
            kind,
            ClosureFrame::on("b", Some(0.1), Pose::identity()),
            ClosureFrame::world(at([0.1, 0.3, 0.0])),
        ))
        .build()
        .unwrap()
}

pub fn driven() -> Model {
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
    Model::builder()
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
        .unwrap()
}

pub fn redundant() -> Model {
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
    Model::builder()
        .rod_on(
            rod("a", 0.3, 3).drag(DRAG),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity([0.0, 0.0, -9.81])
        .closure(weld(ClosureKind::Weld))
        .closure(ball)
        .build()
        .unwrap()
}
