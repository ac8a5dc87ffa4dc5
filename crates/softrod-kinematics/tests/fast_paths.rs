//! The specialised paths of the sweep against the general ones, on random
//! configurations from near-straight (θ ~ 1e-9) to strongly curled
//! (θ·ℓ ~ 20 per piece):
//! - `B = I₆` (block products, no `S` columns stored) against the general
//!   basis `B = 2·I₆` (one product per column, `S` columns stored) at `q/2`;
//! - selection bases (columns read from `T₋`) against the matching columns of
//!   the full basis with the unused strains held in the rest strain;
//! - `poses_along` (per-piece products hoisted) against `pose_at`.

mod common;

use common::*;
use nalgebra::{Matrix6, Matrix6xX};
use softrod_kinematics::{Basis, Frame, GaussLegendre, PieceSpec, RodGeometry, RodKinematics};
use softrod_lie::{Pose, Vec6};

/// A strain with curvature of magnitude `theta` in a random direction.
fn strain(rng: &mut Rng, theta: f64) -> Vec6 {
    let k = rng.unit_vec3() * theta;
    Vec6::new(
        k[0],
        k[1],
        k[2],
        rng.range(0.5, 1.5),
        rng.range(-0.3, 0.3),
        rng.range(-0.3, 0.3),
    )
}

/// Per-piece strains for one trial: all tiny, all huge, or mixed.
fn strains(rng: &mut Rng, n: usize, len: f64, trial: usize) -> Vec<Vec6> {
    (0..n)
        .map(|i| {
            let theta = match (trial + i) % 4 {
                0 => 1e-9,
                1 => 20.0 / len,
                2 => rng.range(0.0, 3.0),
                _ => 1e-5,
            };
            strain(rng, theta)
        })
        .collect()
}

fn scale(m: &Matrix6xX<f64>) -> f64 {
    1.0 + m.amax()
}

const FRAMES: [Frame; 3] = [Frame::Body, Frame::Spatial, Frame::Mixed];

#[test]
fn identity_basis_matches_general_basis() {
    let mut rng = Rng::new(7);
    let two = Basis::from_matrix(Matrix6xX::from_diagonal_element_generic(
        nalgebra::Const::<6>,
        nalgebra::Dyn(6),
        2.0,
    ))
    .unwrap();
    assert!(two.selection().is_none());
    assert!(Basis::all().is_identity());
    for trial in 0..8 {
        let n = 1 + trial % 5;
        let len = rng.range(0.05, 0.5);
        let base = random_pose(&mut rng);
        let xis = strains(&mut rng, n, len, trial);
        let full =
            RodGeometry::uniform(len * n as f64, n, Basis::all(), Vec6::zeros(), base).unwrap();
        let general =
            RodGeometry::uniform(len * n as f64, n, two.clone(), Vec6::zeros(), base).unwrap();
        let q: Vec<f64> = xis.iter().flat_map(|x| x.iter().copied()).collect();
        let qd = rng.vec(6 * n, -1.0, 1.0);
        let half = |v: &[f64]| v.iter().map(|x| 0.5 * x).collect::<Vec<_>>();
        let mut kf = RodKinematics::new(&full);
        let mut kg = RodKinematics::new(&general);
        kf.update(&full, &q, Some(&qd), None).unwrap();
        kg.update(&general, &half(&q), Some(&half(&qd)), None)
            .unwrap();
        let mut jf = Matrix6xX::zeros(6 * n);
        let mut jg = Matrix6xX::zeros(6 * n);
        let l = full.length();
        for s in [l, 0.37 * l, len, 0.0] {
            for frame in FRAMES {
                kf.jacobian_at(&full, s, frame, &mut jf).unwrap();
                kg.jacobian_at(&general, s, frame, &mut jg).unwrap();
                let err = (&jf * 2.0 - &jg).amax();
                assert!(err <= 1e-13 * scale(&jg), "J trial {trial} s {s}: {err:e}");
                kf.jacobian_dot_at(&full, s, frame, &mut jf).unwrap();
                kg.jacobian_dot_at(&general, s, frame, &mut jg).unwrap();
                let err = (&jf * 2.0 - &jg).amax();
                assert!(err <= 1e-12 * scale(&jg), "J̇ trial {trial} s {s}: {err:e}");
            }
        }
    }
}

#[test]
fn selection_bases_match_full_basis_columns() {
    let mut rng = Rng::new(11);
    let selections: [&[usize]; 5] = [&[1], &[0, 1, 2], &[2, 3, 4], &[5, 0], &[4, 3, 1, 2]];
    for trial in 0..10 {
        let sel = selections[trial % selections.len()];
        let n = 1 + trial % 4;
        let len = rng.range(0.05, 0.5);
        let base = random_pose(&mut rng);
        let xis = strains(&mut rng, n, len, trial);
        let specs = |basis: Basis, rest: &dyn Fn(&Vec6) -> Vec6| {
            xis.iter()
                .map(|x| PieceSpec {
                    length: len,
                    basis: basis.clone(),
                    rest_strain: rest(x),
                })
                .collect::<Vec<_>>()
        };
        let full = RodGeometry::from_pieces(specs(Basis::all(), &|_| Vec6::zeros()), base).unwrap();
        let red_basis = Basis::from_indices(sel).unwrap();
        let hold = |x: &Vec6| Vec6::from_fn(|i, _| if sel.contains(&i) { 0.0 } else { x[i] });
        let red = RodGeometry::from_pieces(specs(red_basis, &hold), base).unwrap();
        let q: Vec<f64> = xis.iter().flat_map(|x| x.iter().copied()).collect();
        let qr: Vec<f64> = xis.iter().flat_map(|x| sel.iter().map(|&i| x[i])).collect();
        let qd = rng.vec(6 * n, -1.0, 1.0);
        // Only the selected rates move; the full rod sees zero elsewhere.
        let qd_full: Vec<f64> = (0..6 * n)
            .map(|c| if sel.contains(&(c % 6)) { qd[c] } else { 0.0 })
            .collect();
        let qdr: Vec<f64> = (0..n)
            .flat_map(|p| sel.iter().map(move |&i| 6 * p + i))
            .map(|c| qd[c])
            .collect();
        let mut kf = RodKinematics::new(&full);
        let mut kr = RodKinematics::new(&red);
        kf.update(&full, &q, Some(&qd_full), None).unwrap();
        kr.update(&red, &qr, Some(&qdr), None).unwrap();
        let mut jf = Matrix6xX::zeros(6 * n);
        let mut jr = Matrix6xX::zeros(red.n_dof());
        let l = full.length();
        for s in [l, 0.61 * l, len, 0.0] {
            for frame in FRAMES {
                for dot in [false, true] {
                    if dot {
                        kf.jacobian_dot_at(&full, s, frame, &mut jf).unwrap();
                        kr.jacobian_dot_at(&red, s, frame, &mut jr).unwrap();
                    } else {
                        kf.jacobian_at(&full, s, frame, &mut jf).unwrap();
                        kr.jacobian_at(&red, s, frame, &mut jr).unwrap();
                    }
                    for p in 0..n {
                        for (c, &i) in sel.iter().enumerate() {
                            let a = jf.column(6 * p + i);
                            let b = jr.column(sel.len() * p + c);
                            let err = (a - b).amax();
                            assert!(
                                err <= 1e-12 * scale(&jf),
                                "trial {trial} sel {sel:?} s {s} dot {dot}: {err:e}"
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn poses_along_matches_pose_at() {
    let mut rng = Rng::new(5);
    let rule = GaussLegendre::new(4);
    let mut fractions = rule.nodes.clone();
    fractions.extend([0.0, 1.0]);
    for trial in 0..8 {
        let n = 1 + trial % 6;
        let len = rng.range(0.05, 0.5);
        let base = random_pose(&mut rng);
        let xis = strains(&mut rng, n, len, trial);
        let rod =
            RodGeometry::uniform(len * n as f64, n, Basis::all(), Vec6::zeros(), base).unwrap();
        let q: Vec<f64> = xis.iter().flat_map(|x| x.iter().copied()).collect();
        let mut kin = RodKinematics::new(&rod);
        kin.update(&rod, &q, None, None).unwrap();
        let m = fractions.len();
        let mut out = vec![Pose::identity(); m * n];
        kin.poses_along(&rod, &fractions, &mut out).unwrap();
        for (p, piece) in rod.pieces().iter().enumerate() {
            for (j, f) in fractions.iter().enumerate() {
                let g = kin.pose_in_piece(p, f * piece.length);
                let a = &out[p * m + j];
                let err = (a.rotation - g.rotation)
                    .amax()
                    .max((a.translation - g.translation).amax());
                let tol = 1e-14 * (1.0 + g.translation.amax());
                assert!(err <= tol, "trial {trial} piece {p} f {f}: {err:e}");
            }
        }
    }
    // No fractions: nothing to write, no panic.
    let rod = RodGeometry::uniform(1.0, 3, Basis::all(), Vec6::zeros(), Pose::identity()).unwrap();
    let kin = RodKinematics::new(&rod);
    kin.poses_along(&rod, &[], &mut []).unwrap();
}

#[test]
fn block_product_matches_dense() {
    // The identity-basis path forms C·T₋ as one block product; check the
    // block algebra itself against the dense 6×6 product.
    let mut rng = Rng::new(3);
    for _ in 0..20 {
        let theta = rng.range(0.0, 30.0);
        let xi = strain(&mut rng, theta);
        let x = rng.range(0.0, 1.0);
        let (g, t) = softrod_lie::exp_and_tangent_minus(x, &xi);
        let c = g.ad_inv();
        let dense: Matrix6<f64> = c.to_mat6() * t.to_mat6();
        let err = ((c * t).to_mat6() - dense).amax();
        assert!(err <= 1e-14 * (1.0 + dense.amax()), "{err:e}");
    }
}
