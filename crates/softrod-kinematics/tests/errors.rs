//! Invalid rod descriptions and queries give the right `KinematicsError`,
//! never a panic.

use nalgebra::Matrix6xX;
use softrod_kinematics::{
    Basis, Frame, KinematicsError, LengthOf, PieceSpec, RodGeometry, RodKinematics, Strain,
    straight,
};
use softrod_lie::{Pose, Vec6};

fn id() -> Pose {
    Pose::identity()
}

#[test]
fn bad_lengths() {
    for l in [0.0, -1.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let e = RodGeometry::uniform(l, 3, Basis::all(), straight(), id()).unwrap_err();
        assert!(
            matches!(
                e,
                KinematicsError::BadLength {
                    what: LengthOf::RodGeometry,
                    ..
                }
            ),
            "uniform({l}): {e:?}"
        );
        let e =
            RodGeometry::with_lengths(&[0.2, l, 0.3], Basis::all(), straight(), id()).unwrap_err();
        match e {
            KinematicsError::BadLength { what, value } => {
                assert_eq!(what, LengthOf::Piece(1), "names piece 1: {what}");
                assert!(value.to_bits() == l.to_bits() || (value.is_nan() && l.is_nan()));
            }
            other => panic!("with_lengths({l}): {other:?}"),
        }
    }
}

#[test]
fn no_pieces() {
    assert_eq!(
        RodGeometry::uniform(1.0, 0, Basis::all(), straight(), id()).unwrap_err(),
        KinematicsError::NoPieces
    );
    assert_eq!(
        RodGeometry::with_lengths(&[], Basis::all(), straight(), id()).unwrap_err(),
        KinematicsError::NoPieces
    );
    assert_eq!(
        RodGeometry::from_pieces(vec![], id()).unwrap_err(),
        KinematicsError::NoPieces
    );
}

#[test]
fn bad_bases() {
    let is_bad = |r: Result<Basis, KinematicsError>| {
        matches!(
            r,
            Err(KinematicsError::BasisColumns { .. }
                | KinematicsError::StrainIndex { .. }
                | KinematicsError::DuplicateStrain { .. }
                | KinematicsError::BasisNotFinite
                | KinematicsError::RankDeficient { .. })
        )
    };
    // Duplicate strain.
    assert_eq!(
        Basis::select(&[Strain::Ky, Strain::Qx, Strain::Ky]),
        Err(KinematicsError::DuplicateStrain { strain: Strain::Ky })
    );
    assert_eq!(
        Basis::from_indices(&[3, 3]),
        Err(KinematicsError::DuplicateStrain { strain: Strain::Qx })
    );
    // Index out of range, empty, too many.
    assert_eq!(
        Basis::from_indices(&[6]),
        Err(KinematicsError::StrainIndex { index: 6 })
    );
    assert_eq!(
        Basis::from_indices(&[]),
        Err(KinematicsError::BasisColumns { columns: 0 })
    );
    assert_eq!(
        Basis::from_indices(&[0, 1, 2, 3, 4, 5, 0]),
        Err(KinematicsError::BasisColumns { columns: 7 })
    );
    // Rank-deficient matrices: parallel columns, a zero column, all zero.
    let c = [0.3, 1.0, -0.2, 0.1, 0.0, 0.05];
    let par: Vec<f64> = c
        .iter()
        .chain(c.iter().map(|v| v * -2.0).collect::<Vec<_>>().iter())
        .copied()
        .collect();
    assert!(is_bad(Basis::from_matrix(Matrix6xX::from_column_slice(
        &par
    ))));
    let mut z = c.to_vec();
    z.extend([0.0; 6]);
    assert!(is_bad(Basis::from_matrix(Matrix6xX::from_column_slice(&z))));
    assert!(is_bad(Basis::from_matrix(Matrix6xX::zeros(2))));
    // Nearly dependent (below the 1e-10 relative threshold).
    let mut near = c.to_vec();
    near.extend(
        c.iter()
            .enumerate()
            .map(|(i, v)| v + if i == 0 { 1e-13 } else { 0.0 }),
    );
    assert!(is_bad(Basis::from_matrix(Matrix6xX::from_column_slice(
        &near
    ))));
    // Wrong shapes and non-finite entries.
    assert!(is_bad(Basis::from_matrix(Matrix6xX::zeros(0))));
    assert!(is_bad(Basis::from_matrix(Matrix6xX::from_fn(
        7,
        |r, c| (r == c) as u8 as f64
    ))));
    let mut nan = c.to_vec();
    nan[2] = f64::NAN;
    assert!(is_bad(Basis::from_matrix(Matrix6xX::from_column_slice(
        &nan
    ))));
    // A valid general basis and a selection matrix (recognised as such).
    let ok = Basis::from_matrix(Matrix6xX::from_column_slice(&c)).unwrap();
    assert_eq!(ok.selection(), None);
    let mut sel = Matrix6xX::zeros(2);
    sel[(4, 0)] = 1.0;
    sel[(1, 1)] = 1.0;
    let s = Basis::from_matrix(sel).unwrap();
    assert_eq!(s.selection(), Some(&[4usize, 1][..]));
    assert_eq!(s.strains(), Some(vec![Strain::Qy, Strain::Ky]));
    assert_eq!(s.to_string(), "qy, ky");
    assert_eq!(ok.strains(), None);
    assert_eq!(ok.to_string(), "general 6×1 basis");
}

#[test]
fn non_finite_rod_data() {
    let mut rest = straight();
    rest[1] = f64::NAN;
    let e = RodGeometry::uniform(1.0, 2, Basis::all(), rest, id()).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::RestStrainNotFinite {
                piece: 0,
                component: Strain::Ky,
                ..
            }
        ),
        "{e:?}"
    );
    let mut base = id();
    base.translation[2] = f64::INFINITY;
    let e = RodGeometry::uniform(1.0, 2, Basis::all(), straight(), base).unwrap_err();
    assert!(matches!(e, KinematicsError::BaseNotFinite { .. }), "{e:?}");
    let e = RodGeometry::from_pieces(
        vec![PieceSpec {
            length: 1.0,
            basis: Basis::kirchhoff(),
            rest_strain: Vec6::repeat(f64::NEG_INFINITY),
        }],
        id(),
    )
    .unwrap_err();
    assert!(
        matches!(e, KinematicsError::RestStrainNotFinite { .. }),
        "{e:?}"
    );
}

fn rod() -> RodGeometry {
    RodGeometry::uniform(
        0.8,
        3,
        Basis::select(&[Strain::Ky, Strain::Qx]).unwrap(),
        straight(),
        id(),
    )
    .unwrap()
}

#[test]
fn wrong_coordinate_vectors() {
    let rod = rod();
    let mut kin = RodKinematics::new(&rod);
    let q = vec![0.1; 6];
    for bad in [vec![0.0; 5], vec![0.0; 7], vec![]] {
        let e = kin.update(&rod, &bad, None, None).unwrap_err();
        assert!(
            matches!(e, KinematicsError::SizeMismatch { got, expected: 6, .. } if got == bad.len()),
            "{e:?}"
        );
        let e = kin.update(&rod, &q, Some(&bad), None).unwrap_err();
        assert!(matches!(e, KinematicsError::SizeMismatch { .. }), "{e:?}");
        let e = kin.update(&rod, &q, Some(&q), Some(&bad)).unwrap_err();
        assert!(matches!(e, KinematicsError::SizeMismatch { .. }), "{e:?}");
    }
    for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut b = q.clone();
        b[4] = v;
        let e = kin.update(&rod, &b, None, None).unwrap_err();
        assert!(matches!(e, KinematicsError::NotFinite { .. }), "{e:?}");
        let e = kin.update(&rod, &q, Some(&b), None).unwrap_err();
        assert!(matches!(e, KinematicsError::NotFinite { .. }), "{e:?}");
        let e = kin.update(&rod, &q, None, Some(&b)).unwrap_err();
        assert!(matches!(e, KinematicsError::NotFinite { .. }), "{e:?}");
    }
    kin.update(&rod, &q, Some(&q), Some(&q)).unwrap();
    // Output buffers of the wrong size.
    let mut j = Matrix6xX::zeros(5);
    let e = kin.jacobian_at(&rod, 0.3, Frame::Body, &mut j).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::SizeMismatch {
                got: 5,
                expected: 6,
                ..
            }
        ),
        "{e:?}"
    );
    let e = kin
        .jacobian_dot_at(&rod, 0.3, Frame::Body, &mut j)
        .unwrap_err();
    assert!(matches!(e, KinematicsError::SizeMismatch { .. }), "{e:?}");
    let mut out = vec![Pose::identity(); 2];
    let e = kin.poses_at(&rod, &[0.1, 0.2, 0.3], &mut out).unwrap_err();
    assert!(
        matches!(
            e,
            KinematicsError::SizeMismatch {
                got: 2,
                expected: 3,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn abscissa_outside_the_rod() {
    let rod = rod();
    let mut kin = RodKinematics::new(&rod);
    kin.update(&rod, &[0.5; 6], Some(&[0.1; 6]), None).unwrap();
    let mut j = Matrix6xX::zeros(6);
    for s in [
        -1e-3,
        -1e-9,
        0.8 + 1e-9,
        0.8001,
        5.0,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ] {
        let oor = |e: KinematicsError| matches!(e, KinematicsError::OutOfRod { length, .. } if length == 0.8);
        assert!(oor(rod.locate(s).unwrap_err()), "s = {s}");
        assert!(oor(kin.pose_at(&rod, s).unwrap_err()));
        assert!(oor(kin
            .poses_at(&rod, &[0.1, s], &mut [Pose::identity(); 2])
            .unwrap_err()));
        for frame in [Frame::Body, Frame::Spatial, Frame::Mixed] {
            assert!(oor(kin.velocity_at(&rod, s, frame).unwrap_err()));
            assert!(oor(kin.acceleration_at(&rod, s, frame).unwrap_err()));
            assert!(oor(kin.jacobian_at(&rod, s, frame, &mut j).unwrap_err()));
            assert!(oor(kin
                .jacobian_dot_at(&rod, s, frame, &mut j)
                .unwrap_err()));
        }
    }
    // The ends themselves (and round-off beyond them) are fine.
    for s in [0.0, 0.8, 0.8 * (1.0 + 1e-14), -1e-14] {
        kin.pose_at(&rod, s).unwrap();
        kin.jacobian_at(&rod, s, Frame::Mixed, &mut j).unwrap();
    }
}

#[test]
fn errors_display() {
    let e = RodGeometry::uniform(-2.0, 1, Basis::all(), straight(), id()).unwrap_err();
    assert!(e.to_string().contains("-2"), "{e}");
    let e = Basis::select(&[Strain::Kz, Strain::Kz]).unwrap_err();
    assert!(e.to_string().contains("kz"), "{e}");
}

#[test]
fn base_must_be_a_rotation() {
    let mut scaled = id();
    scaled.rotation[(1, 1)] = 2.0;
    match RodGeometry::uniform(1.0, 2, Basis::all(), straight(), scaled).unwrap_err() {
        KinematicsError::BaseNotRotation {
            deviation,
            determinant,
            ..
        } => {
            // R Rᵀ − I has the entry 2² − 1 = 3; det = 2.
            assert_eq!((deviation, determinant), (3.0, 2.0));
        }
        other => panic!("{other:?}"),
    }
    let mut reflection = id();
    reflection.rotation[(2, 2)] = -1.0;
    let e = RodGeometry::uniform(1.0, 2, Basis::all(), straight(), reflection).unwrap_err();
    assert!(e.to_string().contains("det R = -1"), "{e}");
    // Seven significant digits of cos/sin 30° pass.
    let mut rounded = id();
    rounded.rotation[(0, 0)] = 0.8660254;
    rounded.rotation[(1, 1)] = 0.8660254;
    rounded.rotation[(0, 1)] = -0.5;
    rounded.rotation[(1, 0)] = 0.5;
    RodGeometry::uniform(1.0, 2, Basis::all(), straight(), rounded).unwrap();
}

#[test]
fn too_many_pieces() {
    let n = RodGeometry::MAX_PIECES + 1;
    assert_eq!(
        RodGeometry::uniform(1.0, n, Basis::all(), straight(), id()).unwrap_err(),
        KinematicsError::TooManyPieces {
            pieces: n,
            max: RodGeometry::MAX_PIECES
        }
    );
}

#[test]
fn strain_names_parse_and_display() {
    for s in Strain::ALL {
        assert_eq!(s.name().parse::<Strain>(), Ok(s));
        assert_eq!(s.to_string(), s.name());
        assert_eq!(Strain::ALL[s.index()], s);
    }
    assert_eq!(
        "kw".parse::<Strain>(),
        Err(KinematicsError::UnknownStrain { name: "kw".into() })
    );
    let names: Vec<&str> = Strain::ALL.iter().map(|s| s.name()).collect();
    assert_eq!(names, ["kx", "ky", "kz", "qx", "qy", "qz"]);
}
