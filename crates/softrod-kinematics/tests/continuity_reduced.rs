//! Continuity across piece boundaries, and reduced strain bases against the
//! full basis with the unused strains held at their rest values.

mod common;

use common::*;
use nalgebra::{DMatrix, DVector, Matrix6xX, Vector6};
use softrod_kinematics::{Basis, Frame, PieceSpec, RodGeometry, RodKinematics, Strain, straight};
use softrod_lie::Pose;

fn pose_diff(a: &Pose, b: &Pose) -> f64 {
    (a.rotation - b.rotation)
        .amax()
        .max((a.translation - b.translation).amax())
}

#[test]
fn locate_semantics() {
    let rod = RodGeometry::with_lengths(
        &[0.25, 0.5, 0.25],
        Basis::all(),
        straight(),
        Pose::identity(),
    )
    .unwrap();
    assert_eq!(rod.locate(0.0).unwrap(), (0, 0.0));
    assert_eq!(rod.locate(0.25).unwrap(), (0, 0.25));
    assert_eq!(rod.locate(0.75).unwrap(), (1, 0.5));
    assert_eq!(rod.locate(1.0).unwrap(), (2, 0.25));
    let (n, x) = rod.locate(0.25 + 1e-13).unwrap();
    assert_eq!(n, 1);
    assert!((x - 1e-13).abs() < 1e-16);
    // Within 1e-12·L outside the rod: clamped to the ends.
    assert_eq!(rod.locate(-1e-13).unwrap(), (0, 0.0));
    assert_eq!(rod.locate(1.0 + 1e-13).unwrap(), (2, 0.25));
}

#[test]
#[allow(clippy::needless_range_loop)] // b indexes pieces, boundaries and poses alike
fn pose_velocity_jacobian_continuous_across_boundaries() {
    let mut rng = Rng::new(41);
    let mut worst = 0.0f64;
    for n in [2, 3, 7] {
        for trial in 0..4 {
            let base = random_pose(&mut rng);
            let lengths: Vec<f64> = (0..n).map(|_| rng.range(0.05, 0.4)).collect();
            let basis = if trial % 2 == 0 {
                Basis::all()
            } else {
                Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap()
            };
            let rod = RodGeometry::with_lengths(&lengths, basis, straight(), base).unwrap();
            let nd = rod.n_dof();
            let q = rng.vec(nd, -3.0, 3.0);
            let qd = rng.vec(nd, -1.0, 1.0);
            let qdd = rng.vec(nd, -1.0, 1.0);
            let mut kin = RodKinematics::new(&rod);
            kin.update(&rod, &q, Some(&qd), Some(&qdd)).unwrap();
            let bp = kin.boundary_poses().to_vec();
            assert_eq!(bp.len(), n + 1);
            assert_eq!(bp[0], base);
            assert_eq!(&bp[n], kin.tip_pose());
            for b in 1..n {
                let lb = rod.pieces()[b].start;
                assert_eq!(rod.pieces()[b - 1].end(), lb);
                // From the left: s = L_b belongs to piece b−1 (x = ℓ).
                let left = kin.pose_at(&rod, lb).unwrap();
                let right = kin.pose_in_piece(b, 0.0);
                let e = pose_diff(&left, &bp[b]).max(pose_diff(&right, &bp[b]));
                let e2 = pose_diff(
                    &kin.pose_in_piece(b - 1, rod.pieces()[b - 1].length),
                    &bp[b],
                );
                assert!(
                    e < 1e-15 && e2 < 1e-15,
                    "N = {n}, boundary {b}: {e:.3e} {e2:.3e}"
                );
                // From the right: a hair past the boundary is in piece b.
                let sr = lb + 1e-13;
                assert_eq!(rod.locate(sr).unwrap().0, b);
                let e3 = pose_diff(&kin.pose_at(&rod, sr).unwrap(), &bp[b]);
                assert!(e3 < 1e-12, "pose jump {e3:.3e}");
                worst = worst.max(e).max(e2).max(e3);
                for frame in [Frame::Body, Frame::Spatial, Frame::Mixed] {
                    let vl = kin.velocity_at(&rod, lb, frame).unwrap();
                    let vr = kin.velocity_at(&rod, sr, frame).unwrap();
                    let al = kin.acceleration_at(&rod, lb, frame).unwrap();
                    let ar = kin.acceleration_at(&rod, sr, frame).unwrap();
                    let jl = jac(&kin, &rod, lb, frame);
                    let jr = jac(&kin, &rod, sr, frame);
                    let dl = jac_dot(&kin, &rod, lb, frame);
                    let dr = jac_dot(&kin, &rod, sr, frame);
                    let ev = (vl - vr).amax() / 1.0f64.max(vl.amax());
                    let ea = (al - ar).amax() / 1.0f64.max(al.amax());
                    let ej = (&jl - &jr).amax() / 1.0f64.max(jl.amax());
                    let ed = (&dl - &dr).amax() / 1.0f64.max(dl.amax());
                    assert!(
                        ev < 1e-11 && ea < 1e-11 && ej < 1e-11 && ed < 1e-11,
                        "N = {n}, boundary {b}, {frame:?}: η {ev:.3e}, η̇ {ea:.3e}, J {ej:.3e}, J̇ {ed:.3e}"
                    );
                    worst = worst.max(ev).max(ea).max(ej).max(ed);
                    // The columns of piece b vanish at its base (S_b(0) = 0).
                    for c in rod.pieces()[b].dofs() {
                        assert!(jr.column(c).amax() < 1e-12 && dr.column(c).amax() < 1e-12);
                        assert!(jl.column(c).iter().all(|v| *v == 0.0));
                    }
                }
            }
        }
    }
    println!("continuity: worst jump {worst:.3e}");
}

/// Block-diagonal embedding E with q_full = E q_red for pieces of basis `b`.
fn embedding(b: &Matrix6xX<f64>, n: usize) -> DMatrix<f64> {
    let k = b.ncols();
    let mut e = DMatrix::zeros(6 * n, k * n);
    for p in 0..n {
        for r in 0..6 {
            for c in 0..k {
                e[(6 * p + r, k * p + c)] = b[(r, c)];
            }
        }
    }
    e
}

#[test]
fn reduced_bases_equal_full_basis_with_fixed_strains() {
    let mut rng = Rng::new(42);
    let general = Matrix6xX::from_column_slice(&[
        0.3, 1.0, -0.2, 0.1, 0.0, 0.05, //
        -0.4, 0.2, 0.9, 0.0, 0.3, -0.1,
    ]);
    let bases = [
        selection(&[1]),
        selection(&[1, 3, 5]),
        selection(&[2, 3, 4]),
        selection(&[0, 1, 2]),
        selection(&[5, 0, 3]), // unsorted order
        general,
    ];
    let mut worst = 0.0f64;
    for n in [1, 3, 7] {
        for b in &bases {
            for precurved in [false, true] {
                let rest = if precurved {
                    Vector6::new(0.3, -1.2, 0.8, 1.1, 0.05, -0.02)
                } else {
                    straight()
                };
                let base = random_pose(&mut rng);
                let lengths: Vec<f64> = (0..n).map(|_| rng.range(0.1, 0.3)).collect();
                let mk = |basis: Basis| {
                    RodGeometry::from_pieces(
                        lengths
                            .iter()
                            .map(|&length| PieceSpec {
                                length,
                                basis: basis.clone(),
                                rest_strain: rest,
                            })
                            .collect(),
                        base,
                    )
                    .unwrap()
                };
                let red = mk(Basis::from_matrix(b.clone()).unwrap());
                let full = mk(Basis::all());
                let e = embedding(b, n);
                let k = b.ncols() * n;
                let qr = DVector::from_vec(rng.vec(k, -3.0, 3.0));
                let qdr = DVector::from_vec(rng.vec(k, -1.0, 1.0));
                let qddr = DVector::from_vec(rng.vec(k, -1.0, 1.0));
                let (qf, qdf, qddf) = (&e * &qr, &e * &qdr, &e * &qddr);
                let mut kr = RodKinematics::new(&red);
                let mut kf = RodKinematics::new(&full);
                kr.update(
                    &red,
                    qr.as_slice(),
                    Some(qdr.as_slice()),
                    Some(qddr.as_slice()),
                )
                .unwrap();
                kf.update(
                    &full,
                    qf.as_slice(),
                    Some(qdf.as_slice()),
                    Some(qddf.as_slice()),
                )
                .unwrap();
                let l = red.length();
                for i in 0..=13 {
                    let s = l * i as f64 / 13.0;
                    let ep = pose_diff(
                        &kr.pose_at(&red, s).unwrap(),
                        &kf.pose_at(&full, s).unwrap(),
                    );
                    assert!(ep < 1e-13, "pose {ep:.3e}");
                    worst = worst.max(ep);
                    for frame in [Frame::Body, Frame::Spatial, Frame::Mixed] {
                        let v = (kr.velocity_at(&red, s, frame).unwrap()
                            - kf.velocity_at(&full, s, frame).unwrap())
                        .amax();
                        let a = (kr.acceleration_at(&red, s, frame).unwrap()
                            - kf.acceleration_at(&full, s, frame).unwrap())
                        .amax();
                        let jr = jac(&kr, &red, s, frame);
                        let jf = jac(&kf, &full, s, frame);
                        let dr = jac_dot(&kr, &red, s, frame);
                        let df = jac_dot(&kf, &full, s, frame);
                        let jfe = DMatrix::from_column_slice(6, jf.ncols(), jf.as_slice()) * &e;
                        let dfe = DMatrix::from_column_slice(6, df.ncols(), df.as_slice()) * &e;
                        let ej = (DMatrix::from_column_slice(6, k, jr.as_slice()) - jfe).amax();
                        let ed = (DMatrix::from_column_slice(6, k, dr.as_slice()) - dfe).amax();
                        assert!(
                            v < 1e-12 && a < 1e-12 && ej < 1e-12 && ed < 1e-12,
                            "N = {n}, s = {s}, {frame:?}: η {v:.3e} η̇ {a:.3e} J {ej:.3e} J̇ {ed:.3e}"
                        );
                        worst = worst.max(v).max(a).max(ej).max(ed);
                    }
                }
            }
        }
    }
    println!("reduced vs full basis: worst {worst:.3e}");
}

#[test]
fn poses_along_equals_pose_at() {
    use softrod_kinematics::{Basis, GaussLegendre, RodGeometry, RodKinematics, straight};
    use softrod_lie::{Pose, Vec6};
    let rod = RodGeometry::uniform(0.7, 5, Basis::all(), straight(), Pose::identity()).unwrap();
    let q: Vec<f64> = (0..rod.n_dof())
        .map(|i| 0.3 * ((i * 5 % 7) as f64 - 3.0))
        .collect();
    let mut kin = RodKinematics::new(&rod);
    kin.update(&rod, &q, None, None).unwrap();
    let rule = GaussLegendre::new(4);
    let mut fr = rule.nodes.clone();
    fr.push(1.0);
    let mut out = vec![Pose::identity(); fr.len() * rod.n_pieces()];
    kin.poses_along(&rod, &fr, &mut out).unwrap();
    for (n, piece) in rod.pieces().iter().enumerate() {
        for (j, f) in fr.iter().enumerate() {
            let g = kin.pose_at(&rod, piece.start + f * piece.length).unwrap();
            let h = out[n * fr.len() + j];
            assert!((g.rotation - h.rotation).amax() < 1e-14);
            assert!((g.translation - h.translation).amax() < 1e-14);
        }
    }
    assert!(kin.poses_along(&rod, &[1.5], &mut out[..5]).is_err());
    let _ = Vec6::zeros();
}
