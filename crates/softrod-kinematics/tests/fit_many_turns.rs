//! The centreline fit finds shapes the rod can take exactly, however many
//! turns they make (issue 26, D04: a 20-turn coil of 40 pieces was fitted
//! to a piece at stretch −3215). The points come from an independent
//! forward map — nalgebra's matrix exponential of `x·ξ̂`, piece after piece
//! (`common`) — and the fit must pass through them to round-off.

mod common;

use common::{Rng, hat4, homog};
use nalgebra::{Matrix4, Vector6};
use softrod_kinematics::{Basis, PieceSpec, RodGeometry, Strain, fit_centerline, straight};
use softrod_lie::{Pose, Vec3};

/// Round-off of positions of a rod of length L after many turns: a few
/// hundred ulps of L (the matrix exponentials compose 40+ rotations).
const EXACT: f64 = 1e-11;

fn rod(lengths: &[f64], strains: &[Strain], base: Pose) -> RodGeometry {
    let basis = Basis::select(strains).unwrap();
    let specs = lengths
        .iter()
        .map(|&length| PieceSpec {
            length,
            basis: basis.clone(),
            rest_strain: straight(),
        })
        .collect();
    RodGeometry::from_pieces(specs, base).unwrap()
}

/// The full strains of piece `n` for coordinates `q` of a selection basis.
fn strains_of(rod: &RodGeometry, q: &[f64]) -> Vec<Vector6<f64>> {
    rod.pieces()
        .iter()
        .map(|p| {
            let mut xi = Vector6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0);
            for (c, &i) in p.basis.selection().unwrap().iter().enumerate() {
                xi[i] += q[p.dof_offset + c];
            }
            xi
        })
        .collect()
}

/// Independent positions at `s` values: products of matrix exponentials.
fn points(rod: &RodGeometry, q: &[f64], s: &[f64]) -> Vec<(f64, Vec3)> {
    let xis = strains_of(rod, q);
    s.iter()
        .map(|&s| {
            let mut g: Matrix4<f64> = homog(rod.base());
            for (p, xi) in rod.pieces().iter().zip(&xis) {
                let x = (s - p.start).clamp(0.0, p.length);
                if x > 0.0 {
                    g *= (hat4(xi) * x).exp();
                }
                if s <= p.end() {
                    break;
                }
            }
            (s, Vec3::new(g[(0, 3)], g[(1, 3)], g[(2, 3)]))
        })
        .collect()
}

fn spaced(length: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|i| length * i as f64 / n as f64).collect()
}

/// Fits `truth`'s shape from the straight guess; returns the fit, after
/// checking it passes through every point to round-off, and the largest
/// distance between the two shapes half-way between the points.
fn recovered(
    rod: &RodGeometry,
    truth: &[f64],
    s: &[f64],
) -> (softrod_kinematics::CenterlineFit, f64) {
    let pts = points(rod, truth, s);
    let fit = fit_centerline(rod, &pts, &vec![0.0; rod.n_dof()]).unwrap();
    assert!(fit.max < EXACT * rod.length(), "max {:e}: {fit:?}", fit.max);
    // The fitted shape, by the same independent map, at points in between.
    let mid: Vec<f64> = s.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    let (a, b) = (points(rod, &fit.q, &mid), points(rod, truth, &mid));
    let between = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x.1 - y.1).norm())
        .fold(0.0, f64::max);
    (fit, between)
}

/// The coil: 20 turns of radius 2.39 mm in 40 pieces of 7.5 mm,
/// each a half turn (κ_y·ℓ = π): every piece's curvature and stretch back.
#[test]
fn a_twenty_turn_coil_is_recovered() {
    let l = 0.3;
    let r = rod(
        &[l / 40.0; 40],
        &[Strain::Ky, Strain::Kz, Strain::Qx],
        Pose::identity(),
    );
    let k = 2.0 * std::f64::consts::PI * 20.0 / l;
    let truth: Vec<f64> = (0..40).flat_map(|_| [k, 0.0, 0.0]).collect();
    let (fit, between) = recovered(&r, &truth, &spaced(l, 400));
    assert!(between < EXACT * l, "{between:e}");
    for (a, b) in fit.q.iter().zip(&truth) {
        assert!((a - b).abs() < 1e-8 * k, "{a} vs {b}");
    }
}

/// The repro scene's own points (written with 17 digits, planar coil in
/// x–z): the fit passes within round-off of the written digits.
#[test]
fn the_repro_coil_points_are_fitted() {
    let text = include_str!("fixtures/D04_coil_points.txt");
    let pts: Vec<Vec3> = text
        .split("], [")
        .map(|row| {
            let v: Vec<f64> = row
                .trim_matches(|c| c == '[' || c == ']' || c == '\n')
                .split(',')
                .map(|x| x.trim().parse().unwrap())
                .collect();
            Vec3::new(v[0], v[1], v[2])
        })
        .collect();
    assert_eq!(pts.len(), 401);
    let l = 0.3;
    let targets: Vec<(f64, Vec3)> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| (l * i as f64 / 400.0, *p))
        .collect();
    let r = rod(
        &[l / 40.0; 40],
        &[Strain::Ky, Strain::Kz, Strain::Qx],
        Pose::identity(),
    );
    let fit = fit_centerline(&r, &targets, &[0.0; 120]).unwrap();
    assert!(fit.max < 1e-12, "{fit:?}");
    // Every piece: stretch 1, a half turn about ±y.
    let k = 2.0 * std::f64::consts::PI * 20.0 / l;
    for p in 0..40 {
        assert!(
            (fit.q[3 * p].abs() - k).abs() < 1e-6 * k,
            "{:?}",
            &fit.q[3 * p..3 * p + 3]
        );
        assert!(
            fit.q[3 * p + 2].abs() < 1e-9,
            "{:?}",
            &fit.q[3 * p..3 * p + 3]
        );
    }
}

/// Helices: torsion, both bendings and stretch the same in every piece,
/// each piece turning by up to 4 rad, 15 turns in all, on a tilted base.
#[test]
fn helices_of_many_turns_are_recovered() {
    let mut rng = Rng::new(7);
    for _ in 0..5 {
        let pieces = 24;
        let l = 0.4;
        let strains = [Strain::Kx, Strain::Ky, Strain::Kz, Strain::Qx];
        let base = common::random_pose(&mut rng);
        let r = rod(&vec![l / pieces as f64; pieces], &strains, base);
        let turn = rng.range(2.0, 4.0) / (l / pieces as f64);
        let dir = Vec3::new(
            rng.range(-0.3, 0.3),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize();
        let stretch = rng.range(-0.2, 0.3);
        let one = [turn * dir.x, turn * dir.y, turn * dir.z, stretch];
        let truth: Vec<f64> = (0..pieces).flat_map(|_| one).collect();
        let (fit, between) = recovered(&r, &truth, &spaced(l, 8 * pieces));
        assert!(between < EXACT * l, "{between:e}");
        for (a, b) in fit.q.iter().zip(&truth) {
            assert!((a - b).abs() < 1e-7 * turn, "{a} vs {b}");
        }
    }
}

/// Mixed strains: every piece its own bending (up to 3 rad per piece) and
/// stretch, unequal pieces, points not on the piece boundaries.
#[test]
fn mixed_strains_are_recovered() {
    let mut rng = Rng::new(11);
    for _ in 0..40 {
        let pieces = 12;
        let lengths: Vec<f64> = (0..pieces).map(|_| rng.range(0.01, 0.04)).collect();
        let l: f64 = lengths.iter().sum();
        let r = rod(
            &lengths,
            &[Strain::Ky, Strain::Kz, Strain::Qx],
            Pose::identity(),
        );
        let truth: Vec<f64> = lengths
            .iter()
            .flat_map(|&len| {
                let bend = rng.range(0.0, 3.0) / len;
                let a = rng.range(0.0, std::f64::consts::TAU);
                [bend * a.cos(), bend * a.sin(), rng.range(-0.3, 0.3)]
            })
            .collect();
        let s: Vec<f64> = (0..=97).map(|i| l * (i as f64 / 97.0).powf(1.1)).collect();
        let (fit, between) = recovered(&r, &truth, &s);
        assert!(between < EXACT * l, "{between:e}");
        for (a, b) in fit.q.iter().zip(&truth) {
            assert!((a - b).abs() < 1e-7 * (1.0 + b.abs()), "{a} vs {b}");
        }
    }
}

/// All six strains: positions fix only part of them (twist and shear
/// trade with bending), but the shape through the points is exact.
#[test]
fn all_six_strains_pass_through_the_points() {
    let mut rng = Rng::new(3);
    let pieces = 10;
    let l = 0.25;
    let all = [
        Strain::Kx,
        Strain::Ky,
        Strain::Kz,
        Strain::Qx,
        Strain::Qy,
        Strain::Qz,
    ];
    let r = rod(&vec![l / pieces as f64; pieces], &all, Pose::identity());
    let truth: Vec<f64> = (0..pieces)
        .flat_map(|_| {
            let b = 60.0;
            [
                rng.range(-b, b),
                rng.range(-b, b),
                rng.range(-b, b),
                rng.range(-0.2, 0.2),
                rng.range(-0.1, 0.1),
                rng.range(-0.1, 0.1),
            ]
        })
        .collect();
    let (_, between) = recovered(&r, &truth, &spaced(l, 6 * pieces));
    assert!(between < EXACT * l, "{between:e}");
}

/// One point per piece end, three strains per piece: as many equations as
/// unknowns. The shape passes through every point; up to 2.5 rad per piece.
#[test]
fn one_point_per_piece_is_enough() {
    let mut rng = Rng::new(5);
    for _ in 0..20 {
        let pieces = 16;
        let l = 0.32;
        let len = l / pieces as f64;
        let r = rod(
            &vec![len; pieces],
            &[Strain::Ky, Strain::Kz, Strain::Qx],
            Pose::identity(),
        );
        let truth: Vec<f64> = (0..pieces)
            .flat_map(|_| {
                let bend = rng.range(0.0, 2.5) / len;
                let a = rng.range(0.0, std::f64::consts::TAU);
                [bend * a.cos(), bend * a.sin(), rng.range(-0.2, 0.2)]
            })
            .collect();
        recovered(&r, &truth, &spaced(l, pieces));
    }
}
