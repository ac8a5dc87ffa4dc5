//! Velocities, accelerations and `J̇` along smooth paths
//! `q(t) = q0 + t·v + t²·a` (so `q̇(0) = v`, `q̈(0) = 2a`), against
//! 4th-order central differences in time:
//! `f′(0) ≈ (f(−2h) − 8f(−h) + 8f(h) − f(2h)) / 12h`, h = 1e-3:
//! truncation h⁴/30·|f⁽⁵⁾| ≈ 3e-14·|f| for O(1) rates and lengths,
//! rounding ≈ 1.5 ε|f|/h ≈ 3e-13·|f|; we assert 1e-9 relative (the curled
//! rods have |f⁽⁵⁾| up to (θL)⁵-times larger, still far below).

mod common;

use common::*;
use nalgebra::{DVector, Matrix4, Matrix6xX, Vector3, Vector6};
use softrod_kinematics::{Frame, RodGeometry, RodKinematics};

const HT: f64 = 1e-3;

fn d4<T>(f: impl Fn(f64) -> T) -> T
where
    T: std::ops::Sub<Output = T> + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    let (m2, m1, p1, p2) = (f(-2.0 * HT), f(-HT), f(HT), f(2.0 * HT));
    (m2 - p2 + (p1 - m1) * 8.0) * (1.0 / (12.0 * HT))
}

struct Case {
    r: RefRod,
    rod: RodGeometry,
    q0: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    label: String,
}

impl Case {
    fn q_at(&self, t: f64) -> Vec<f64> {
        self.q0
            .iter()
            .zip(&self.v)
            .zip(&self.a)
            .map(|((q, v), a)| q + t * v + t * t * a)
            .collect()
    }
    fn qd_at(&self, t: f64) -> Vec<f64> {
        self.v
            .iter()
            .zip(&self.a)
            .map(|(v, a)| v + 2.0 * t * a)
            .collect()
    }
    fn qdd(&self) -> Vec<f64> {
        self.a.iter().map(|a| 2.0 * a).collect()
    }
    /// Kinematics at time t of the path, with q̇ and q̈.
    fn kin_at(&self, t: f64) -> RodKinematics {
        let mut k = RodKinematics::new(&self.rod);
        k.update(
            &self.rod,
            &self.q_at(t),
            Some(&self.qd_at(t)),
            Some(&self.qdd()),
        )
        .unwrap();
        k
    }
}

fn cases() -> Vec<Case> {
    let mut rng = Rng::new(31);
    let general = Matrix6xX::from_column_slice(&[
        0.3, 1.0, -0.2, 0.1, 0.0, 0.05, //
        -0.4, 0.2, 0.9, 0.0, 0.3, -0.1,
    ]);
    let bases = [
        ("all", selection(&[0, 1, 2, 3, 4, 5])),
        ("[ky]", selection(&[1])),
        ("[ky qx qz]", selection(&[1, 3, 5])),
        ("[kz qx qy]", selection(&[2, 3, 4])),
        ("general 6x2", general),
    ];
    let mut out = Vec::new();
    for n in [1, 3, 7] {
        for (bname, b) in &bases {
            for kind in ["moderate", "straight", "curled"] {
                let l = rng.range(0.5, 1.5);
                let base = if rng.unit() < 0.5 {
                    Matrix4::identity()
                } else {
                    homog(&random_pose(&mut rng))
                };
                let r = RefRod {
                    base,
                    lengths: vec![l / n as f64; n],
                    bases: vec![b.clone(); n],
                    rest: vec![straight(); n],
                };
                let q0 = random_q(&mut rng, &r, kind);
                let nd = r.n_dof();
                // Rates O(1/L) for curvatures; the path stays in the regime.
                let v = rng.vec(nd, -1.0, 1.0);
                let a = rng.vec(nd, -1.0, 1.0);
                out.push(Case {
                    rod: r.rod(),
                    r,
                    q0,
                    v,
                    a,
                    label: format!("N = {n}, basis {bname}, {kind}"),
                });
            }
        }
    }
    out
}

fn rel(a: &Vector6<f64>, b: &Vector6<f64>) -> f64 {
    (a - b).amax() / 1.0f64.max(b.amax())
}

fn relm(a: &Matrix6xX<f64>, b: &Matrix6xX<f64>) -> f64 {
    (a - b).amax() / 1.0f64.max(b.amax())
}

#[test]
fn body_velocity_is_jacobian_times_qdot() {
    let mut worst = 0.0f64;
    for c in cases() {
        let kin = c.kin_at(0.0);
        let qd = DVector::from_column_slice(&c.v);
        for &(_, _, s) in &eval_points(&c.r) {
            let j = jac(&kin, &c.rod, s, Frame::Body);
            let eta = kin.velocity_at(&c.rod, s, Frame::Body).unwrap();
            let jq = RodKinematics::apply_jacobian(&j, qd.as_view());
            let e = rel(&eta, &jq);
            assert!(e < 1e-13, "{}: s = {s}, {e:.3e}", c.label);
            worst = worst.max(e);
        }
    }
    println!("η vs J q̇: worst {worst:.3e}");
}

#[test]
fn velocity_frames_and_independent_velocity() {
    let (mut w_frames, mut w_fd) = (0.0f64, 0.0f64);
    for c in cases() {
        let kin = c.kin_at(0.0);
        let pts = eval_points(&c.r);
        let at: Vec<(usize, f64)> = pts.iter().map(|&(n, x, _)| (n, x)).collect();
        let g = c.r.poses_local(&c.q0, &at);
        // Time derivative of the independent reference pose along the path.
        let gdot = d4(|t| {
            c.r.poses_local(&c.q_at(t), &at)
                .into_iter()
                .collect::<Stack>()
        });
        for (k, &(_, _, s)) in pts.iter().enumerate() {
            let eb = kin.velocity_at(&c.rod, s, Frame::Body).unwrap();
            let es = kin.velocity_at(&c.rod, s, Frame::Spatial).unwrap();
            let em = kin.velocity_at(&c.rod, s, Frame::Mixed).unwrap();
            let sc = 1.0f64.max(g[k].amax());
            let e1 = rel(&es, &(ad_mat(&g[k]) * eb)) / sc;
            let e2 = rel(&em, &(rr_mat(&g[k]) * eb)) / sc;
            assert!(
                e1 < 1e-13 && e2 < 1e-13,
                "{}: s = {s}: {e1:.3e} {e2:.3e}",
                c.label
            );
            w_frames = w_frames.max(e1).max(e2);
            // Independent body twist vee(g⁻¹ ġ) and world-position rate.
            let gd = gdot.0[k];
            let eta_ref = vee4(&(homog_inv(&g[k]) * gd));
            let pdot_ref = Vector3::new(gd[(0, 3)], gd[(1, 3)], gd[(2, 3)]);
            let omega_world = vee4(&(gd * homog_inv(&g[k])));
            let e3 = rel(&eb, &eta_ref);
            let lin = Vector3::new(em[3], em[4], em[5]);
            let e4 = (lin - pdot_ref).amax() / 1.0f64.max(pdot_ref.amax());
            let ang = Vector3::new(em[0], em[1], em[2]);
            let e5 = (ang - omega_world.fixed_rows::<3>(0)).amax() / 1.0f64.max(ang.amax());
            assert!(
                e3 < 1e-9 && e4 < 1e-9 && e5 < 1e-9,
                "{}: s = {s}: body {e3:.3e}, ṗ {e4:.3e}, ω {e5:.3e}",
                c.label
            );
            w_fd = w_fd.max(e3).max(e4).max(e5);
        }
    }
    println!("velocity frames: worst {w_frames:.3e}; vs FD of reference pose: worst {w_fd:.3e}");
}

/// A vector of 4×4 matrices with the arithmetic `d4` needs.
struct Stack(Vec<Matrix4<f64>>);

impl std::ops::Sub for Stack {
    type Output = Stack;
    fn sub(self, o: Stack) -> Stack {
        Stack(self.0.iter().zip(&o.0).map(|(a, b)| a - b).collect())
    }
}
impl std::ops::Add for Stack {
    type Output = Stack;
    fn add(self, o: Stack) -> Stack {
        Stack(self.0.iter().zip(&o.0).map(|(a, b)| a + b).collect())
    }
}
impl std::ops::Mul<f64> for Stack {
    type Output = Stack;
    fn mul(self, k: f64) -> Stack {
        Stack(self.0.iter().map(|a| a * k).collect())
    }
}
impl FromIterator<Matrix4<f64>> for Stack {
    fn from_iter<I: IntoIterator<Item = Matrix4<f64>>>(it: I) -> Self {
        Stack(it.into_iter().collect())
    }
}

#[test]
fn jacobian_dot_matches_time_difference_of_jacobian() {
    let mut worst = [0.0f64; 3];
    for c in cases() {
        let kin = c.kin_at(0.0);
        for &(_, _, s) in &eval_points(&c.r) {
            for (fi, frame) in [Frame::Body, Frame::Spatial, Frame::Mixed]
                .into_iter()
                .enumerate()
            {
                let jd = jac_dot(&kin, &c.rod, s, frame);
                let fd = d4(|t| jac(&c.kin_at(t), &c.rod, s, frame));
                let e = relm(&jd, &fd);
                assert!(
                    e < 1e-9,
                    "{}: s = {s}, {frame:?}: {e:.3e}\nJdot = {jd}\nFD = {fd}",
                    c.label
                );
                worst[fi] = worst[fi].max(e);
            }
        }
    }
    println!(
        "J̇ vs FD of J (Body, Spatial, Mixed): worst {:.3e} {:.3e} {:.3e}",
        worst[0], worst[1], worst[2]
    );
}

#[test]
fn acceleration_is_j_qddot_plus_jdot_qdot_and_matches_fd() {
    let (mut w_alg, mut w_fd, mut w_fr) = (0.0f64, 0.0f64, 0.0f64);
    for c in cases() {
        let kin = c.kin_at(0.0);
        let qd = DVector::from_column_slice(&c.v);
        let qdd = DVector::from_column_slice(&c.qdd());
        let pts = eval_points(&c.r);
        let at: Vec<(usize, f64)> = pts.iter().map(|&(n, x, _)| (n, x)).collect();
        let g = c.r.poses_local(&c.q0, &at);
        for (k, &(_, _, s)) in pts.iter().enumerate() {
            let acc = kin.acceleration_at(&c.rod, s, Frame::Body).unwrap();
            let j = jac(&kin, &c.rod, s, Frame::Body);
            let jd = jac_dot(&kin, &c.rod, s, Frame::Body);
            let alg = RodKinematics::apply_jacobian(&j, qdd.as_view())
                + RodKinematics::apply_jacobian(&jd, qd.as_view());
            let e1 = rel(&acc, &alg);
            // d/dt of η(t) = J(q(t)) q̇(t), J from the (separately verified) code.
            let fd = d4(|t| {
                let kt = c.kin_at(t);
                let jt = jac(&kt, &c.rod, s, Frame::Body);
                RodKinematics::apply_jacobian(
                    &jt,
                    DVector::from_column_slice(&c.qd_at(t)).as_view(),
                )
            });
            let e2 = rel(&acc, &fd);
            assert!(
                e1 < 1e-12 && e2 < 1e-9,
                "{}: s = {s}: {e1:.3e} {e2:.3e}",
                c.label
            );
            // Spatial/Mixed accelerations are the rotated body ones (documented).
            let sc = 1.0f64.max(g[k].amax());
            let es = kin.acceleration_at(&c.rod, s, Frame::Spatial).unwrap();
            let em = kin.acceleration_at(&c.rod, s, Frame::Mixed).unwrap();
            let e3 = rel(&es, &(ad_mat(&g[k]) * acc)) / sc;
            let e4 = rel(&em, &(rr_mat(&g[k]) * acc)) / sc;
            assert!(
                e3 < 1e-13 && e4 < 1e-13,
                "{}: s = {s}: {e3:.3e} {e4:.3e}",
                c.label
            );
            w_alg = w_alg.max(e1);
            w_fd = w_fd.max(e2);
            w_fr = w_fr.max(e3).max(e4);
        }
    }
    println!(
        "η̇: vs J q̈ + J̇ q̇ worst {w_alg:.3e}; vs FD of J q̇ worst {w_fd:.3e}; frames worst {w_fr:.3e}"
    );
}

#[test]
fn missing_rates_are_zero() {
    for c in cases().into_iter().step_by(4) {
        let mut kin = RodKinematics::new(&c.rod);
        // A previous update with rates must not leak into a rate-free one.
        kin.update(&c.rod, &c.q0, Some(&c.v), Some(&c.a)).unwrap();
        kin.update(&c.rod, &c.q0, None, None).unwrap();
        for &(_, _, s) in &eval_points(&c.r) {
            for frame in [Frame::Body, Frame::Spatial, Frame::Mixed] {
                assert_eq!(kin.velocity_at(&c.rod, s, frame).unwrap(), Vector6::zeros());
                assert_eq!(
                    kin.acceleration_at(&c.rod, s, frame).unwrap(),
                    Vector6::zeros()
                );
                let jd = jac_dot(&kin, &c.rod, s, frame);
                assert!(
                    jd.iter().all(|v| *v == 0.0),
                    "{}: s = {s}, {frame:?}: J̇ = {jd} after an update without q̇",
                    c.label
                );
            }
        }
        // q̇ without q̈: η̇ = J̇ q̇.
        kin.update(&c.rod, &c.q0, Some(&c.v), None).unwrap();
        let qd = DVector::from_column_slice(&c.v);
        for &(_, _, s) in &eval_points(&c.r) {
            let acc = kin.acceleration_at(&c.rod, s, Frame::Body).unwrap();
            let jd = jac_dot(&kin, &c.rod, s, Frame::Body);
            let e = rel(&acc, &RodKinematics::apply_jacobian(&jd, qd.as_view()));
            assert!(e < 1e-12, "{}: s = {s}: {e:.3e}", c.label);
        }
    }
}
