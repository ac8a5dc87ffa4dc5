//! Refining a rod (`RodGeometry::subdivided`) keeps its geometry: a piece of
//! constant strain cut in parts with the same strain is the same curve.

use softrod_kinematics::{Basis, PieceSpec, RodGeometry, RodKinematics, Strain, straight};
use softrod_lie::{Pose, Vec6};

/// Round-off of composing up to 12 exponentials instead of 4.
const POSE_TOL: f64 = 1e-13;

#[test]
fn subdivided_rod_has_the_same_shape() {
    let ky = Basis::select(&[Strain::Ky, Strain::Qx]).unwrap();
    let rod = RodGeometry::from_pieces(
        vec![
            PieceSpec {
                length: 0.1,
                basis: Basis::all(),
                rest_strain: straight(),
            },
            PieceSpec {
                length: 0.3,
                basis: ky.clone(),
                rest_strain: Vec6::new(0.0, 2.0, 0.0, 1.0, 0.0, 0.0),
            },
        ],
        Pose::identity(),
    )
    .unwrap();
    assert_eq!(rod.uniform_basis(), None);
    let fine = rod.subdivided(3).unwrap();
    assert_eq!(fine.n_pieces(), 6);
    assert_eq!(fine.n_dof(), 3 * 6 + 3 * 2);
    let lengths: Vec<f64> = fine.piece_lengths().collect();
    assert!((lengths[0] - 0.1 / 3.0).abs() < 1e-17 && (lengths[5] - 0.1).abs() < 1e-16);
    // The coarse coordinates, each piece's repeated three times.
    let q = [0.3, -0.2, 0.5, 0.01, 0.02, -0.03, 1.5, 0.05];
    let mut qf = Vec::new();
    for _ in 0..3 {
        qf.extend_from_slice(&q[..6]);
    }
    for _ in 0..3 {
        qf.extend_from_slice(&q[6..]);
    }
    let mut k = RodKinematics::new(&rod);
    k.update(&rod, &q, None, None).unwrap();
    let mut kf = RodKinematics::new(&fine);
    kf.update(&fine, &qf, None, None).unwrap();
    for s in [0.0, 0.05, 0.1, 0.23, 0.4] {
        let (a, b) = (k.pose_at(&rod, s).unwrap(), kf.pose_at(&fine, s).unwrap());
        assert!((a.translation - b.translation).amax() < POSE_TOL, "s = {s}");
        assert!((a.rotation - b.rotation).amax() < POSE_TOL, "s = {s}");
    }
    let uniform = RodGeometry::uniform(0.4, 4, ky.clone(), straight(), Pose::identity()).unwrap();
    assert_eq!(uniform.uniform_basis(), Some(&ky));
}
