//! Tests of `contact.rs` (a file of their own: the layout test's length bound).

// Test code only (the layout test reads no further than this marker).
#[cfg(test)]
use super::*;
use crate::algorithms::contact_force;
use crate::algorithms::frames::frame_pose;
use crate::{Attachment, BodySpec, Joint, JointKind, Rod, commit_contact};
use nalgebra::DVector;
use softrod_kinematics::Strain;
use softrod_mechanics::Material;
use softrod_mechanics::contact::{ContactSettings, Obstacle, Shape};

/// A tree with every kind of contact force: an arm on a hinge lying on
/// a table (fixed obstacle), a twig hanging inside the arm's middle
/// piece (D62) lying on it too, a free ball carrying a sphere that
/// presses on the arm (an obstacle on a body), and a free rod crossing
/// over the arm (a rod pair); friction anchors committed a moment
/// before, so that the forces have tangential parts.
fn scene() -> (Model, Vec<f64>, Vec<f64>) {
    let r = 0.01;
    let silicone = Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .build()
        .unwrap();
    let along_y = Mat3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    let rod = |name: &str, length: f64, pieces: usize, base: Pose| {
        Rod::builder(length)
            .name(name)
            .pieces(pieces)
            .strains(Strain::ALL)
            .base(base)
            .circle(r)
            .material(silicone)
    };
    let mut ball = BodySpec::principal("ball", 0.05, [1e-5, 1e-5, 1e-5]);
    ball.base = Pose::new(Mat3::identity(), Vec3::new(0.25, 0.0, r + 0.02 - 3e-4));
    let model = Model::builder()
        .rod_on(
            rod("arm", 0.3, 3, Pose::identity()),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .rod_on(
            rod("twig", 0.1, 2, Pose::new(along_y, Vec3::zeros())),
            Attachment::to("arm", Joint::revolute([0.0, 0.0, 1.0])).at(0.15),
        )
        .rod_on(
            rod(
                "b",
                0.2,
                2,
                Pose::new(along_y, Vec3::new(0.05, -0.1, 2.0 * r - 5e-4)),
            ),
            Attachment::world_joint(Joint::new(JointKind::Free)),
        )
        .body(ball, Attachment::world_joint(Joint::new(JointKind::Free)))
        .gravity([0.0, 0.0, -9.81])
        .obstacle(
            Obstacle::new(
                "table",
                Shape::Plane {
                    point: Vec3::new(0.0, 0.0, -0.995 * r),
                    normal: Vec3::z(),
                },
            )
            .friction(0.5),
        )
        .obstacle(
            Obstacle::new(
                "sphere",
                Shape::Sphere {
                    center: Vec3::zeros(),
                    radius: 0.02,
                },
            )
            .on("ball")
            .friction(0.3),
        )
        .contact(ContactSettings {
            rods: true,
            self_contact: true,
            friction: 0.4,
            ..Default::default()
        })
        .build()
        .unwrap();
    let n = model.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 1e-5 * ((i as f64) * 1.3).sin()).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.01 * ((i as f64) * 0.7).cos()).collect();
    (model, q, qd)
}

/// The pose-only sample position of the obstacle pre-test and the rod
/// pairs ([`frame_pose`]) is [`frame_state`]'s pose: to the bit without
/// rates (the same exponential and compositions: what keeps the pairs'
/// outputs unchanged), and within far less than the pre-test's 1e-9 m
/// slack with them (another series evaluation of the same map), at
/// every contact sample of every rod of the tree scene, bent.
#[test]
fn the_pose_only_frame_is_the_frame_states_pose() {
    let (model, q0, qd) = scene();
    let tree = model.tree.as_ref().unwrap();
    let q: Vec<f64> = q0
        .iter()
        .enumerate()
        .map(|(i, v)| v + 0.3 * ((i as f64) * 0.9).sin())
        .collect();
    let mut data = Data::new(&model);
    outward(
        &model,
        tree,
        &mut data,
        Motion::at_rest(&q),
        Pass::Inverse,
        Forces::ALL,
    );
    let mut checked = 0;
    for (r, samples) in model.contact.samples.iter().enumerate() {
        for smp in samples {
            let frame = rod_frame(&model, r, smp.s);
            let pose = frame_pose(&model, &data, &frame, &q);
            let full = frame_state(&model, tree, &data, &frame, &q, None).pose;
            assert_eq!(pose.translation, full.translation, "rod {r}, s {}", smp.s);
            assert_eq!(pose.rotation, full.rotation, "rod {r}, s {}", smp.s);
            let rated = frame_state(&model, tree, &data, &frame, &q, Some(&qd)).pose;
            assert!((pose.translation - rated.translation).norm() < 1e-14);
            checked += 1;
        }
    }
    assert!(checked > 10, "{checked} samples");
}

/// The per-evaluation sample poses and piece stretches (one strain and
/// one `PieceMaps` per piece) are the per-point recomputation's to the
/// bit: each point's pose is `frame_pose` at `locate(s)` (the piece and
/// abscissa the model fixed are `locate`'s), each piece's stretch the
/// norm of its strain's `ν`, and each segment's piece `locate` of its
/// midpoint — at every contact point of every rod of the tree scene,
/// bent, and again at a second state (nothing kept from the first).
#[test]
fn the_shared_sample_poses_are_the_per_point_ones() {
    let (model, q0, _) = scene();
    let tree = model.tree.as_ref().unwrap();
    let mut data = Data::new(&model);
    let mut work = ContactWork::new(&model);
    let mut checked = 0;
    for amp in [0.3, -0.7] {
        let q: Vec<f64> = q0
            .iter()
            .enumerate()
            .map(|(i, v)| v + amp * ((i as f64) * 0.9).sin())
            .collect();
        outward(
            &model,
            tree,
            &mut data,
            Motion::at_rest(&q),
            Pass::Inverse,
            Forces::ALL,
        );
        sample_poses(&model, &data, &mut work, &q);
        for (r, samples) in model.contact.samples.iter().enumerate() {
            let g = &model.rods[r].spec.geometry;
            for (i, smp) in samples.iter().enumerate() {
                let (piece, x) = g.locate(smp.s).unwrap();
                assert_eq!((smp.piece, smp.x), (piece, x), "rod {r}, s {}", smp.s);
                if i + 1 < samples.len() {
                    let mid = 0.5 * (smp.s + samples[i + 1].s);
                    assert_eq!(smp.segment_piece, g.locate(mid).unwrap().0);
                }
                let frame = rod_frame(&model, r, smp.s);
                let pose = frame_pose(&model, &data, &frame, &q);
                assert_eq!(work.poses[r][i].translation, pose.translation);
                assert_eq!(work.poses[r][i].rotation, pose.rotation);
                checked += 1;
            }
            for (n, pc) in g.pieces().iter().enumerate() {
                let xi = g.strain(n, &q[model.rods[r].dofs()]);
                let nu = Vec3::new(xi[3], xi[4], xi[5]).norm();
                assert_eq!(work.stretch[r][n], nu);
                assert!(nu > 0.0 && pc.length > 0.0);
            }
        }
    }
    assert!(checked > 20, "{checked} samples");
}

/// The material points `(rod, s, obstacle's body, force on the rod)` of
/// the last evaluation's contacts, a pair's rod `b` with the opposite.
type Points = Vec<(usize, f64, Option<usize>, Vec3)>;

/// `Σ J_relᵀ f` by the dense point Jacobians.
fn dense_route(model: &Model, data: &Data, q: &[f64], points: &Points) -> DVector<f64> {
    let n = model.n_dof();
    let mut jrel = DMatrix::zeros(3, n);
    let mut dense = DVector::<f64>::zeros(n);
    for &(rod, s, body, f) in points {
        tree_point_jacobian(model, data, q, rod, s, body, &mut jrel);
        dense += jrel.transpose() * f;
    }
    dense
}

/// The generalized contact force of the inward sweep (CT28) against
/// the dense route `Σ J_relᵀ f` of the point Jacobians, and both
/// against central differences of the forces' virtual work
/// `Σ f · δp` (the forces held, the material points moved by `q`):
/// positions only, independent of either Jacobian.
#[test]
fn the_inward_sweep_equals_dense_point_jacobians_and_the_virtual_work() {
    let (model, q, qd) = scene();
    let tree = model.tree.as_ref().unwrap();
    let n = model.n_dof();
    let mut data = Data::new(&model);
    let q_before: Vec<f64> = q
        .iter()
        .enumerate()
        .map(|(i, v)| v - 1e-5 * ((i as f64) * 2.1).cos())
        .collect();
    commit_contact(&model, &mut data, 0.0, &q_before, &qd).unwrap();
    assert!(contact_force(
        &model,
        &mut data,
        Forces::ALL,
        0.0,
        &q,
        Some(&qd)
    ));
    let work = data.contact.take().unwrap();
    let tau = work.tau.clone();
    let pairs = &work.pairs.as_ref().unwrap().active;
    let twig = model
        .rods
        .iter()
        .position(|r| r.spec.name == "twig")
        .unwrap();
    let on = |o: usize| work.active.iter().filter(|a| a.obstacle == o).count();
    assert!(
        on(0) >= 4 && on(1) >= 1,
        "table {}, sphere {}",
        on(0),
        on(1)
    );
    assert!(work.active.iter().any(|a| a.rod == twig));
    assert!(!pairs.is_empty());
    assert!(
        work.active
            .iter()
            .any(|a| a.force.cross(&a.normal).norm() > 1e-3 * a.force.norm())
    );
    // The material points and the sign of each force on them.
    let mut points: Points = Vec::new();
    for a in &work.active {
        let s = model.contact.samples[a.rod][a.sample].s;
        points.push((a.rod, s, model.contact.parents[a.obstacle], a.force));
    }
    for c in pairs {
        points.push((c.a, c.sa, None, c.force));
        points.push((c.b, c.sb, None, -c.force));
    }
    let dense = dense_route(&model, &data, &q, &points);
    let scale = dense.norm();
    let diff = (&tau - &dense).norm();
    eprintln!(
        "{} points: |τ| {scale:.3e}, sweep − dense {diff:.3e}",
        points.len()
    );
    assert!(diff <= 1e-13 * scale, "{diff:.3e} of {scale:.3e}");
    // Central differences of the virtual work.
    let place = |data: &mut Data, qq: &[f64]| -> Vec<Vec3> {
        outward(
            &model,
            tree,
            data,
            Motion::at_rest(qq),
            Pass::Inverse,
            Forces::ALL,
        );
        points
            .iter()
            .map(|&(rod, s, _, _)| {
                frame_state(&model, tree, data, &rod_frame(&model, rod, s), qq, None)
                    .pose
                    .translation
            })
            .collect()
    };
    let body_poses = |data: &Data| -> Vec<Option<Pose>> {
        points
            .iter()
            .map(|&(_, _, b, _)| b.map(|b| data.nodes[tree.body_nodes[b]].base_world))
            .collect()
    };
    let p0 = place(&mut data, &q);
    let b0 = body_poses(&data);
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for l in 0..n {
        let mut work_of = |sign: f64| -> f64 {
            let mut qq = q.clone();
            qq[l] += sign * h;
            let p = place(&mut data, &qq);
            let bp = body_poses(&data);
            let mut w = 0.0;
            for (k, &(_, _, _, f)) in points.iter().enumerate() {
                w += f.dot(&p[k]);
                // The body's material point where the rod point was.
                if let (Some(g0), Some(g)) = (b0[k], bp[k]) {
                    w -= f.dot(&g.compose(&g0.inverse()).transform_point(&p0[k]));
                }
            }
            w
        };
        let fd = (work_of(1.0) - work_of(-1.0)) / (2.0 * h);
        worst = worst.max((fd - tau[l]).abs());
    }
    eprintln!("virtual work: worst |Δτ| {worst:.3e} of |τ| {scale:.3e}");
    assert!(worst <= 1e-7 * scale, "{worst:.3e} of {scale:.3e}");
    data.contact = Some(work);
}
