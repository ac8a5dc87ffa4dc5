//! The geometric Jacobian `J(s)` (D11) against central differences of an
//! independent pose (products of nalgebra `expm`) with respect to `q`:
//! column j ≈ vee(g⁻¹ (g(q + h e_j) − g(q − h e_j)) / 2h), body frame.
//!
//! Error budget with h = 1e-6: truncation ~h²/6·|∂³g| ≲ 1e-12·(θL)³ and
//! rounding ~ε·|g|/h ≈ 2e-10·max(1, |p|); both ≲ 1e-8 relative to
//! max(1, |J|) even for θ·L ≈ 20 (measured: ≤ 4e-10, 2e-9 curled). We
//! assert 1e-8 relative.

mod common;

use common::*;
use nalgebra::{Matrix6xX, Vector6};
use softrod_kinematics::{Frame, RodKinematics};

const H: f64 = 1e-6;

fn bases() -> Vec<(&'static str, Matrix6xX<f64>)> {
    let general = Matrix6xX::from_column_slice(&[
        0.3, 1.0, -0.2, 0.1, 0.0, 0.05, //
        -0.4, 0.2, 0.9, 0.0, 0.3, -0.1,
    ]);
    vec![
        ("all", selection(&[0, 1, 2, 3, 4, 5])),
        ("[ky]", selection(&[1])),
        ("[ky qx qz]", selection(&[1, 3, 5])),
        ("[kz qx qy]", selection(&[2, 3, 4])),
        ("general 6x2", general),
    ]
}

fn make_ref(rng: &mut Rng, n: usize, basis: &Matrix6xX<f64>, rest_kind: usize) -> RefRod {
    let base = if rest_kind == 0 {
        nalgebra::Matrix4::identity()
    } else {
        homog(&random_pose(rng))
    };
    let l = rng.range(0.4, 1.6);
    let raw: Vec<f64> = (0..n).map(|_| rng.range(0.6, 1.4)).collect();
    let sum: f64 = raw.iter().sum();
    let rest = if rest_kind == 2 {
        // Precurved, sheared rest strain.
        Vector6::new(0.4, -0.7, 1.1, 1.05, 0.02, -0.03)
    } else {
        straight()
    };
    RefRod {
        base,
        lengths: raw.iter().map(|x| x * l / sum).collect(),
        bases: vec![basis.clone(); n],
        rest: vec![rest; n],
    }
}

/// Worst relative error of the body Jacobian against the FD reference over
/// all evaluation points.
fn check(r: &RefRod, q: &[f64], tol: f64, label: &str) -> f64 {
    let rod = r.rod();
    let mut kin = RodKinematics::new(&rod);
    kin.update(&rod, q, None, None).unwrap();
    let pts = eval_points(r);
    let at: Vec<(usize, f64)> = pts.iter().map(|&(n, x, _)| (n, x)).collect();
    let g0 = r.poses_local(q, &at);
    let nd = r.n_dof();
    let mut fd = vec![Matrix6xX::<f64>::zeros(nd); pts.len()];
    for j in 0..nd {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[j] += H;
        qm[j] -= H;
        let gp = r.poses_local(&qp, &at);
        let gm = r.poses_local(&qm, &at);
        for (k, fdk) in fd.iter_mut().enumerate() {
            let d = homog_inv(&g0[k]) * (gp[k] - gm[k]) / (2.0 * H);
            fdk.set_column(j, &vee4(&d));
        }
    }
    let mut worst = 0.0f64;
    for (k, &(_, _, s)) in pts.iter().enumerate() {
        let j = jac(&kin, &rod, s, Frame::Body);
        let scale = 1.0f64.max(j.amax());
        let e = (&j - &fd[k]).amax() / scale;
        assert!(
            e < tol,
            "{label}: s = {s}, rel error {e:.3e}\nJ = {j}\nFD = {}",
            fd[k]
        );
        worst = worst.max(e);
    }
    worst
}

#[test]
fn jacobian_matches_finite_differences() {
    let mut rng = Rng::new(21);
    let mut worst = std::collections::BTreeMap::<String, f64>::new();
    for n in [1, 3, 7] {
        for (bname, b) in bases() {
            for kind in ["moderate", "straight", "curled"] {
                for rest_kind in 0..3 {
                    let r = make_ref(&mut rng, n, &b, rest_kind);
                    let q = random_q(&mut rng, &r, kind);
                    let tol = 1e-8;
                    let label = format!("N = {n}, basis {bname}, {kind}, rest {rest_kind}");
                    let e = check(&r, &q, tol, &label);
                    let w = worst.entry(kind.to_string()).or_insert(0.0);
                    *w = w.max(e);
                }
            }
        }
    }
    println!("J vs FD, worst relative error per configuration kind: {worst:?}");
}

#[test]
fn jacobian_frames_are_adjoint_transforms_of_the_body_jacobian() {
    let mut rng = Rng::new(22);
    let mut worst = 0.0f64;
    for n in [1, 3, 7] {
        for (_, b) in bases() {
            let r = make_ref(&mut rng, n, &b, 1);
            let q = random_q(&mut rng, &r, "moderate");
            let rod = r.rod();
            let mut kin = RodKinematics::new(&rod);
            kin.update(&rod, &q, None, None).unwrap();
            let pts = eval_points(&r);
            let at: Vec<(usize, f64)> = pts.iter().map(|&(n, x, _)| (n, x)).collect();
            let g = r.poses_local(&q, &at);
            for (k, &(_, _, s)) in pts.iter().enumerate() {
                let jb = jac(&kin, &rod, s, Frame::Body);
                let js = jac(&kin, &rod, s, Frame::Spatial);
                let jm = jac(&kin, &rod, s, Frame::Mixed);
                let scale = 1.0f64.max(jb.amax()) * 1.0f64.max(g[k].amax());
                let es = (&js - ad_mat(&g[k]) * &jb).amax() / scale;
                let em = (&jm - rr_mat(&g[k]) * &jb).amax() / scale;
                assert!(es < 1e-13 && em < 1e-13, "s = {s}: {es:.3e} {em:.3e}");
                worst = worst.max(es).max(em);
            }
        }
    }
    println!("J frames vs Ad_g / diag(R,R): worst {worst:.3e}");
}

#[test]
fn jacobian_columns_of_later_pieces_are_zero() {
    let mut rng = Rng::new(23);
    let r = make_ref(&mut rng, 5, &selection(&[0, 1, 2, 3, 4, 5]), 1);
    let q = random_q(&mut rng, &r, "moderate");
    let rod = r.rod();
    let mut kin = RodKinematics::new(&rod);
    kin.update(&rod, &q, None, None).unwrap();
    for &(n, _, s) in &eval_points(&r) {
        for frame in [Frame::Body, Frame::Spatial, Frame::Mixed] {
            let j = jac(&kin, &rod, s, frame);
            for c in 6 * (n + 1)..rod.n_dof() {
                assert!(j.column(c).iter().all(|v| *v == 0.0), "s = {s}, col {c}");
            }
        }
    }
    // At s = 0 the whole Jacobian vanishes (clamped base).
    assert!(jac(&kin, &rod, 0.0, Frame::Body).iter().all(|v| *v == 0.0));
}
