//! `section_jacobian` against central differences of the world pose that
//! `frames` and the rod kinematics give (`rod_to_world · g_local(s)`, the
//! path the outputs use): on a clamped rod, and on robots with every joint
//! type, bodies between rods, children inside pieces and a prescribed
//! joint, at piece boundaries and inside pieces; `body_jacobian` the same
//! way against the body poses of `frames`.

mod common;

use common::{Lcg, robot, soft_rod as rod};
use nalgebra::{Matrix3, Matrix6xX};
use softrod_dynamics::{
    Attachment, BodySpec, Curve, Data, DynamicsError, Joint, Model, Prescribed, body_jacobian,
    frames, section_jacobian,
};
use softrod_kinematics::RodKinematics;
use softrod_lie::{Pose, Vec3};

/// The world pose of rod `r` at `s`, by `frames` and the rod kinematics.
fn world_pose(model: &Model, q: &[f64], r: usize, s: f64) -> Pose {
    let mut data = Data::new(model);
    model.set_time(&mut data, 0.3);
    frames(model, &mut data, q).unwrap();
    let rm = &model.rods()[r];
    let mut kin = RodKinematics::new(&rm.spec.geometry);
    kin.update(&rm.spec.geometry, &q[rm.dofs()], None, None)
        .unwrap();
    data.rod_to_world(model, r)
        .compose(&kin.pose_at(&rm.spec.geometry, s).unwrap())
}

/// Column `j` of the spatial Jacobian from central differences of the
/// pose: `ω̂ = Ṙ Rᵀ`, `v = ṗ − ω × p` (the velocity of the world point at
/// the origin).
fn differences(model: &Model, q: &[f64], r: usize, s: f64) -> Matrix6xX<f64> {
    pose_differences(q, |q| world_pose(model, q, r, s))
}

/// The world pose of body `b`'s frame, by `frames`.
fn body_pose(model: &Model, q: &[f64], b: usize) -> Pose {
    let mut data = Data::new(model);
    model.set_time(&mut data, 0.3);
    frames(model, &mut data, q).unwrap();
    data.body_poses[b]
}

/// The spatial Jacobian of the pose `pose(q)` by central differences, as
/// [`differences`].
fn pose_differences(q: &[f64], pose: impl Fn(&[f64]) -> Pose) -> Matrix6xX<f64> {
    let n = q.len();
    let g = pose(q);
    let mut j = Matrix6xX::zeros(n);
    let h = 1e-6;
    for c in 0..n {
        let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
        qp[c] += h;
        qm[c] -= h;
        let (gp, gm) = (pose(&qp), pose(&qm));
        let rdot: Matrix3<f64> = (gp.rotation - gm.rotation) / (2.0 * h);
        let w = rdot * g.rotation.transpose();
        let omega = Vec3::new(
            0.5 * (w[(2, 1)] - w[(1, 2)]),
            0.5 * (w[(0, 2)] - w[(2, 0)]),
            0.5 * (w[(1, 0)] - w[(0, 1)]),
        );
        let pdot = (gp.translation - gm.translation) / (2.0 * h);
        let v = pdot - omega.cross(&g.translation);
        for k in 0..3 {
            j[(k, c)] = omega[k];
            j[(3 + k, c)] = v[k];
        }
    }
    j
}

fn check(model: &Model, q: &[f64], r: usize, s: f64, label: &str) {
    let mut data = Data::new(model);
    model.set_time(&mut data, 0.3);
    let (g, j) = section_jacobian(model, &mut data, q, r, s).unwrap();
    let g_ref = world_pose(model, q, r, s);
    assert!(
        (g.translation - g_ref.translation).amax() < 1e-12
            && (g.rotation - g_ref.rotation).amax() < 1e-12,
        "{label}: pose"
    );
    let fd = differences(model, q, r, s);
    let e = (&j - &fd).amax() / fd.amax().max(1.0);
    // Central differences with h = 1e-6 on O(1) poses: truncation ~1e-12,
    // round-off ~1e-10 (entries are O(1): lengths of a metre or less; the
    // root section of a clamped rod has none).
    assert!(e < 1e-7, "{label}: {e:e}");
}

#[test]
fn clamped_rod_and_robots() {
    let mut rng = Lcg(31);
    let chain = Model::builder().rod(rod("arm", 0.4, 3)).build().unwrap();
    let q = rng.vec(chain.n_dof(), 0.5);
    for s in [0.0, 0.1, 0.4] {
        check(&chain, &q, 0, s, &format!("clamped, s = {s}"));
    }
    let m = robot(true, true, true, true);
    let q = rng.vec(m.n_dof(), 0.4);
    for (r, rm) in m.rods().iter().enumerate() {
        let l = rm.spec.geometry.length();
        for s in [0.0, 0.37 * l, l] {
            check(
                &m,
                &q,
                r,
                s,
                &format!("robot rod {}, s = {s}", rm.spec.name),
            );
        }
    }
}

/// Children inside pieces, a body between rods and a prescribed joint
/// (its coordinate is not a column: it moves with time, not with q).
#[test]
fn inside_attachments_and_a_prescribed_joint() {
    let drive =
        Joint::prismatic([0.0, 0.0, 1.0]).with_prescribed(Prescribed::new(vec![Curve::Sine {
            amplitude: 0.05,
            frequency: 1.0,
            phase: 0.3,
            offset: 0.0,
        }]));
    let m = Model::builder()
        .rod_on(rod("trunk", 0.4, 3), Attachment::world_joint(drive))
        .body(
            BodySpec::principal("hub", 0.02, [1e-6, 2e-6, 3e-6]),
            Attachment::to("trunk", Joint::revolute([0.0, 1.0, 0.3])).at(0.21),
        )
        .rod_on(
            rod("finger", 0.2, 2),
            Attachment::to("hub", Joint::universal([0.0, 0.0, 1.0], [0.0, 1.0, 0.0])),
        )
        .rod_on(
            rod("branch", 0.2, 1),
            Attachment::to("trunk", Joint::spherical()).at(0.05),
        )
        .build()
        .unwrap();
    let q = Lcg(8).vec(m.n_dof(), 0.4);
    for (r, rm) in m.rods().iter().enumerate() {
        let l = rm.spec.geometry.length();
        for s in [0.0, 0.55 * l, l] {
            check(&m, &q, r, s, &format!("rod {}, s = {s}", rm.spec.name));
        }
    }
}

#[test]
fn bad_arguments_are_errors() {
    let m = robot(false, false, false, false);
    let mut data = Data::new(&m);
    let q = vec![0.0; m.n_dof()];
    let e = section_jacobian(&m, &mut data, &q, 99, 0.0).unwrap_err();
    assert!(
        matches!(e, DynamicsError::RodIndex { index: 99, .. }),
        "{e}"
    );
    let e = section_jacobian(&m, &mut data, &q, 0, 5.0).unwrap_err();
    assert!(matches!(e, DynamicsError::Kinematics { rod: 0, .. }), "{e}");
    let e = section_jacobian(&m, &mut data, &q[1..], 0, 0.0).unwrap_err();
    assert!(matches!(e, DynamicsError::SizeMismatch { .. }), "{e}");
}

/// `body_jacobian` (the closures' frame machinery, exposed) against
/// central differences of the body poses `frames` writes: the hand of the
/// robot fixture (a body on a rod's tip through joints) and a hub on a
/// revolute joint inside a rod piece with a rod hanging from it.
#[test]
fn body_jacobians_match_differences() {
    let m = robot(true, true, true, true);
    let hub = Model::builder()
        .rod(rod("trunk", 0.4, 3))
        .body(
            BodySpec::principal("hub", 0.02, [1e-6, 2e-6, 3e-6]),
            Attachment::to("trunk", Joint::revolute([0.0, 1.0, 0.3])).at(0.21),
        )
        .rod_on(
            rod("finger", 0.2, 2),
            Attachment::to("hub", Joint::universal([0.0, 0.0, 1.0], [0.0, 1.0, 0.0])),
        )
        .build()
        .unwrap();
    let mut rng = Lcg(17);
    for model in [&m, &hub] {
        let q = rng.vec(model.n_dof(), 0.4);
        assert!(!model.bodies().is_empty());
        for b in 0..model.bodies().len() {
            let label = &model.bodies()[b].spec.name;
            let mut data = Data::new(model);
            model.set_time(&mut data, 0.3);
            let (g, j) = body_jacobian(model, &mut data, &q, b).unwrap();
            let g_ref = body_pose(model, &q, b);
            assert!(
                (g.translation - g_ref.translation).amax() < 1e-12
                    && (g.rotation - g_ref.rotation).amax() < 1e-12,
                "{label}: pose"
            );
            let fd = pose_differences(&q, |q| body_pose(model, q, b));
            // As for sections: truncation ~1e-12, round-off ~1e-10.
            let e = (&j - &fd).amax() / fd.amax().max(1.0);
            assert!(e < 1e-7, "{label}: {e:e}");
            // Every column the body depends on is there (not an all-zero J).
            assert!(fd.amax() > 1e-3, "{label}: the pose does not move");
        }
    }
    let mut data = Data::new(&m);
    let q = vec![0.0; m.n_dof()];
    let count = m.bodies().len();
    let e = body_jacobian(&m, &mut data, &q, count).unwrap_err();
    assert!(
        matches!(e, DynamicsError::BodyIndex { index, count: c } if index == count && c == count),
        "{e}"
    );
    let chain = Model::builder().rod(rod("arm", 0.4, 3)).build().unwrap();
    let mut data = Data::new(&chain);
    let e = body_jacobian(&chain, &mut data, &vec![0.0; chain.n_dof()], 0).unwrap_err();
    assert!(
        matches!(e, DynamicsError::BodyIndex { count: 0, .. }),
        "{e}"
    );
}
