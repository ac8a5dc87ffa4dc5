//! Constant-strain rods against closed-form geometry: circle arcs, helices
//! and straight lines, written out here independently of the code under test.

mod common;

use common::*;
use nalgebra::{Matrix3, Vector3, Vector6};
use softrod_kinematics::{Basis, RodGeometry, RodKinematics, Strain, straight};
use softrod_lie::{Pose, Vec6};

/// Worst error of `pose` against `(r, p)`: rotation in max-abs entries,
/// translation relative to `scale` (a length of the problem).
fn pose_err(pose: &Pose, r: &Matrix3<f64>, p: &Vector3<f64>, scale: f64) -> f64 {
    let er = (pose.rotation - r).amax();
    let ep = (pose.translation - p).amax() / scale;
    er.max(ep)
}

/// Abscissae to check: ends, interior, and the piece boundaries of `n` pieces.
fn abscissae(l: f64, n: usize) -> Vec<f64> {
    let mut s: Vec<f64> = (0..=20).map(|i| l * i as f64 / 20.0).collect();
    s.extend((0..=n).map(|i| l * i as f64 / n as f64));
    s.push(l * 0.123_456_7);
    s
}

/// Bending about local y with curvature κ and extension e: a circle of
/// radius e/κ in the x–z plane, `R = R_y(κs)`,
/// `p = (e sin(κs)/κ, 0, −e(1 − cos(κs))/κ)`.
fn arc_y(kappa: f64, e: f64, s: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let (sn, cs) = (kappa * s).sin_cos();
    // 1 − cos(κs) = 2 sin²(κs/2), free of cancellation for small κs.
    let vers = 2.0 * (0.5 * kappa * s).sin().powi(2);
    (
        Matrix3::new(cs, 0.0, sn, 0.0, 1.0, 0.0, -sn, 0.0, cs),
        Vector3::new(e * sn / kappa, 0.0, -e * vers / kappa),
    )
}

/// Bending about local z: circle in the x–y plane, `R = R_z(κs)`,
/// `p = (e sin(κs)/κ, e(1 − cos(κs))/κ, 0)`.
fn arc_z(kappa: f64, e: f64, s: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let (sn, cs) = (kappa * s).sin_cos();
    let vers = 2.0 * (0.5 * kappa * s).sin().powi(2);
    (
        Matrix3::new(cs, -sn, 0.0, sn, cs, 0.0, 0.0, 0.0, 1.0),
        Vector3::new(e * sn / kappa, e * vers / kappa, 0.0),
    )
}

/// Screw motion of the constant twist ξ = (k, q) over arc length s (k ≠ 0):
/// rotation about the fixed unit axis u = k/|k| by |k|s, and translation
/// `p = (I − R)(u × q)/|k| + (u·q) u s` (axis through the point
/// `u × q/|k|`, pitch `2π (u·q)/|k|` per turn).
fn helix(k: &Vector3<f64>, q: &Vector3<f64>, s: f64) -> (Matrix3<f64>, Vector3<f64>) {
    let th = k.norm();
    let u = k / th;
    let r = axis_angle(&u, th * s);
    let p = (Matrix3::identity() - r) * u.cross(q) / th + u * u.dot(q) * s;
    (r, p)
}

fn check_rod(
    rod: &RodGeometry,
    q: &[f64],
    base: &Pose,
    exact: impl Fn(f64) -> (Matrix3<f64>, Vector3<f64>),
    scale: f64,
    tol: f64,
    label: &str,
) -> f64 {
    let mut kin = RodKinematics::new(rod);
    kin.update(rod, q, None, None).unwrap();
    let mut worst = 0.0f64;
    let n = rod.n_pieces();
    for s in abscissae(rod.length(), n) {
        let (r, p) = exact(s);
        let (r, p) = (base.rotation * r, base.rotation * p + base.translation);
        let g = kin.pose_at(rod, s).unwrap();
        let e = pose_err(&g, &r, &p, scale);
        assert!(e < tol, "{label}: s = {s}, error {e:.3e}");
        worst = worst.max(e);
    }
    // The boundary poses are the same arc at L_n.
    for (i, g) in kin.boundary_poses().iter().enumerate() {
        let s = rod.pieces().get(i).map_or(rod.length(), |p| p.start);
        let (r, p) = exact(s);
        let (r, p) = (base.rotation * r, base.rotation * p + base.translation);
        let e = pose_err(g, &r, &p, scale);
        assert!(e < tol, "{label}: boundary {i}, error {e:.3e}");
        worst = worst.max(e);
    }
    let (r, p) = exact(rod.length());
    let (r, p) = (base.rotation * r, base.rotation * p + base.translation);
    let e = pose_err(kin.tip_pose(), &r, &p, scale);
    assert!(e < tol, "{label}: tip, error {e:.3e}");
    worst.max(e)
}

#[test]
fn single_piece_arc_is_a_circle() {
    let mut worst = 0.0f64;
    let l = 0.7;
    let all = RodGeometry::uniform(l, 1, Basis::all(), straight(), Pose::identity()).unwrap();
    // Curvatures from nearly straight (series side of the switch) to many turns.
    for kappa in [1e-3, 0.5, 2.0, 3.5, 5.0, 10.0, 40.0, -7.0] {
        for e in [1.0, 1.2, 0.8] {
            // Full basis: q = ξ − ξ̄.
            let q = [0.0, kappa, 0.0, e - 1.0, 0.0, 0.0];
            let tol = 1e-12;
            worst = worst.max(check_rod(
                &all,
                &q,
                &Pose::identity(),
                |s| arc_y(kappa, e, s),
                l,
                tol,
                &format!("ky = {kappa}, e = {e}"),
            ));
            let q = [0.0, 0.0, kappa, e - 1.0, 0.0, 0.0];
            worst = worst.max(check_rod(
                &all,
                &q,
                &Pose::identity(),
                |s| arc_z(kappa, e, s),
                l,
                tol,
                &format!("kz = {kappa}, e = {e}"),
            ));
        }
        // Reduced basis [ky] (qx fixed at its rest value 1).
        let ky = RodGeometry::uniform(
            l,
            1,
            Basis::select(&[Strain::Ky]).unwrap(),
            straight(),
            Pose::identity(),
        )
        .unwrap();
        worst = worst.max(check_rod(
            &ky,
            &[kappa],
            &Pose::identity(),
            |s| arc_y(kappa, 1.0, s),
            l,
            1e-12,
            &format!("[ky] basis, ky = {kappa}"),
        ));
    }
    println!("arc: worst error {worst:.3e}");
}

#[test]
fn multi_piece_arc_with_base_pose() {
    let mut rng = Rng::new(11);
    let mut worst = 0.0f64;
    for n in [1, 3, 7, 25] {
        for _ in 0..3 {
            let base = random_pose(&mut rng);
            let l = rng.range(0.2, 2.0);
            let kappa = rng.range(-12.0, 12.0);
            let e = rng.range(0.8, 1.2);
            // Unequal piece lengths: the arc must not care where the cuts are.
            let raw: Vec<f64> = (0..n).map(|_| rng.range(0.5, 1.5)).collect();
            let sum: f64 = raw.iter().sum();
            let lengths: Vec<f64> = raw.iter().map(|x| x * l / sum).collect();
            let rod = RodGeometry::with_lengths(&lengths, Basis::all(), straight(), base).unwrap();
            let mut q = Vec::new();
            for _ in 0..n {
                q.extend([0.0, kappa, 0.0, e - 1.0, 0.0, 0.0]);
            }
            worst = worst.max(check_rod(
                &rod,
                &q,
                &base,
                |s| arc_y(kappa, e, s),
                l,
                1e-12,
                &format!("N = {n}, κ = {kappa}"),
            ));
            // Same arc with a precurved rest strain and the basis [qx] only.
            let rest = Vec6::new(0.0, 0.0, kappa, 1.0, 0.0, 0.0);
            let rod = RodGeometry::with_lengths(
                &lengths,
                Basis::select(&[Strain::Qx]).unwrap(),
                rest,
                base,
            )
            .unwrap();
            let q = vec![e - 1.0; n];
            worst = worst.max(check_rod(
                &rod,
                &q,
                &base,
                |s| arc_z(kappa, e, s),
                l,
                1e-12,
                &format!("precurved [qx], N = {n}, κ = {kappa}"),
            ));
        }
    }
    println!("multi-piece arc: worst error {worst:.3e}");
}

#[test]
fn torsion_and_bending_is_a_helix() {
    let mut rng = Rng::new(12);
    let mut worst = 0.0f64;
    for n in [1, 2, 5, 16] {
        for trial in 0..6 {
            let base = if trial % 2 == 0 {
                Pose::identity()
            } else {
                random_pose(&mut rng)
            };
            let l = rng.range(0.3, 1.5);
            // (kx, ky) torsion + bending with qx = 1 as in the brief, then a
            // fully general constant twist (k, q).
            let (k, qv) = if trial < 3 {
                (
                    Vector3::new(rng.range(-8.0, 8.0), rng.range(-8.0, 8.0), 0.0),
                    Vector3::new(1.0, 0.0, 0.0),
                )
            } else {
                (
                    rng.unit_vec3() * rng.range(0.5, 20.0),
                    Vector3::new(
                        rng.range(0.7, 1.3),
                        rng.range(-0.3, 0.3),
                        rng.range(-0.3, 0.3),
                    ),
                )
            };
            let xi = Vector6::new(k[0], k[1], k[2], qv[0], qv[1], qv[2]);
            let rod = RodGeometry::uniform(l, n, Basis::all(), straight(), base).unwrap();
            let qn = xi - straight();
            let q: Vec<f64> = (0..n).flat_map(|_| qn.iter().copied()).collect();
            worst = worst.max(check_rod(
                &rod,
                &q,
                &base,
                |s| helix(&k, &qv, s),
                l,
                1e-12,
                &format!("helix N = {n}, k = {k:?}, q = {qv:?}"),
            ));
        }
    }
    println!("helix: worst error {worst:.3e}");
}

#[test]
fn helix_formula_matches_circle_formula() {
    // Sanity check of the two independent references against each other.
    let (r1, p1) = helix(
        &Vector3::new(0.0, 3.0, 0.0),
        &Vector3::new(1.1, 0.0, 0.0),
        0.8,
    );
    let (r2, p2) = arc_y(3.0, 1.1, 0.8);
    assert!((r1 - r2).amax() < 1e-15 && (p1 - p2).amax() < 1e-15);
}

#[test]
fn zero_curvature_is_a_straight_line() {
    let mut rng = Rng::new(13);
    let mut worst = 0.0f64;
    for n in [1, 4, 9] {
        for trial in 0..4 {
            let base = if trial == 0 {
                Pose::identity()
            } else {
                random_pose(&mut rng)
            };
            let l = rng.range(0.1, 3.0);
            let qv = Vector3::new(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            );
            let rod = RodGeometry::uniform(l, n, Basis::all(), straight(), base).unwrap();
            let qn = [0.0, 0.0, 0.0, qv[0] - 1.0, qv[1], qv[2]];
            let q: Vec<f64> = (0..n).flat_map(|_| qn).collect();
            worst = worst.max(check_rod(
                &rod,
                &q,
                &base,
                |s| (Matrix3::identity(), qv * s),
                l,
                1e-14,
                &format!("straight N = {n}, q = {qv:?}"),
            ));
            // Reduced shear/extension basis.
            let rod = RodGeometry::uniform(
                l,
                n,
                Basis::select(&[Strain::Qx, Strain::Qy, Strain::Qz]).unwrap(),
                straight(),
                base,
            )
            .unwrap();
            let qn = [qv[0] - 1.0, qv[1], qv[2]];
            let q: Vec<f64> = (0..n).flat_map(|_| qn).collect();
            worst = worst.max(check_rod(
                &rod,
                &q,
                &base,
                |s| (Matrix3::identity(), qv * s),
                l,
                1e-14,
                "straight, [qx qy qz]",
            ));
        }
    }
    println!("straight line: worst error {worst:.3e}");
}

#[test]
fn rest_configuration_is_the_base_x_axis() {
    let mut rng = Rng::new(14);
    let base = random_pose(&mut rng);
    let rod = RodGeometry::uniform(0.9, 6, Basis::kirchhoff(), straight(), base).unwrap();
    let mut kin = RodKinematics::new(&rod);
    kin.update(&rod, rod.rest_q().as_slice(), None, None)
        .unwrap();
    for s in abscissae(0.9, 6) {
        let g = kin.pose_at(&rod, s).unwrap();
        let p = base.rotation * Vector3::new(s, 0.0, 0.0) + base.translation;
        assert!((g.rotation - base.rotation).amax() < 1e-15);
        assert!((g.translation - p).amax() < 1e-15);
    }
}

#[test]
fn poses_at_and_pose_in_piece_agree_with_pose_at() {
    let mut rng = Rng::new(15);
    let rod =
        RodGeometry::uniform(1.3, 5, Basis::all(), straight(), random_pose(&mut rng)).unwrap();
    let q = rng.vec(rod.n_dof(), -2.0, 2.0);
    let mut kin = RodKinematics::new(&rod);
    kin.update(&rod, &q, None, None).unwrap();
    let s: Vec<f64> = (0..40).map(|_| rng.range(0.0, 1.3)).collect();
    let mut out = vec![Pose::identity(); s.len()];
    kin.poses_at(&rod, &s, &mut out).unwrap();
    for (si, g) in s.iter().zip(&out) {
        assert_eq!(*g, kin.pose_at(&rod, *si).unwrap());
        let (n, x) = rod.locate(*si).unwrap();
        let h = kin.pose_in_piece(n, x);
        assert!((h.rotation - g.rotation).amax() < 1e-15);
        assert!((h.translation - g.translation).amax() < 1e-15);
    }
}
