//! Extreme loads (issue 8): a cable tension that curls the arm past a full
//! circle, and a large follower tip force.
//!
//! The fixtures (scenes, statics with an independent residual check, runs
//! checked for NaN) are in `softrod_tests::extreme` (`tests/src/extreme.rs`);
//! the failure contract every case follows is stated in `extreme_curvature.rs`.
//! Long versions of these scenes, for `softrod report`, are in
//! `examples/extreme/`. Every test prints its measured numbers
//! (`cargo test -p softrod-tests --test extreme_loads -- --nocapture`).

use std::f64::consts::PI;

use softrod_integrate::{Integrator, Options};
use softrod_kinematics::{GaussLegendre, RodKinematics};
use softrod_tests::extreme::*;

/// Independent uniform-strain balance of a rod pulled by a cable of constant
/// offset `d` anchored at the tip: cutting the rod anywhere, the distal part
/// with its cable is held by the internal wrench and the cable tension, so
/// `Γ(ξ − ξ*) = −T (d × t̂; t̂)` with `t̂ ∝ ν + κ × d` (the cable's tangent in
/// the body frame). Solved by Newton with a finite-difference Jacobian.
fn cable_uniform_strain(gamma: [f64; 6], d: [f64; 3], tension: f64) -> [f64; 6] {
    let resid = |x: &[f64; 6]| -> [f64; 6] {
        let k = nalgebra::Vector3::new(x[0], x[1], x[2]);
        let nu = nalgebra::Vector3::new(x[3], x[4], x[5]) + nalgebra::Vector3::x();
        let dv = nalgebra::Vector3::from(d);
        let v = nu + k.cross(&dv);
        let t = v / v.norm();
        let mom = dv.cross(&t);
        let w = [mom.x, mom.y, mom.z, t.x, t.y, t.z];
        std::array::from_fn(|i| gamma[i] * x[i] + tension * w[i])
    };
    let mut x = [0.0; 6];
    for _ in 0..100 {
        let r = resid(&x);
        let rn = r.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if rn < 1e-13 * tension {
            break;
        }
        let mut jac = nalgebra::Matrix6::zeros();
        for j in 0..6 {
            let h = 1e-7 * x[j].abs().max(1e-3);
            let mut xp = x;
            xp[j] += h;
            let mut xm = x;
            xm[j] -= h;
            let (rp, rm) = (resid(&xp), resid(&xm));
            for i in 0..6 {
                jac[(i, j)] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        let dx = jac
            .lu()
            .solve(&nalgebra::Vector6::from(r))
            .expect("regular");
        for i in 0..6 {
            x[i] -= dx[i];
        }
    }
    x
}

/// A cable tension that curls the arm past a full circle (κL ≈ 2.5π): every
/// piece takes the strain of the independent uniform-strain balance, for 1
/// and 4 pieces. Released from straight with the cable pulling: damped, the
/// energy including the cable potential `T ℓ_c` decreases; undamped it is
/// conserved.
#[test]
fn cable_curls_past_full_circle() {
    let (l, r, e, d) = (0.3, 0.01, 1e6, 0.008);
    let kappa_target = 2.5 * PI / l;
    let tension = kappa_target * ei(e, r) / d;
    let rod = |visc: f64| {
        format!(
            "strains = \"all\"\nsection = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1100.0, young = 1.0e6, poisson = 0.5, viscosity = {visc:?} }}"
        )
    };
    let cable = format!("[[cable]]\nrod = \"arm\"\noffset = [0.0, {d:?}]\ntension = {tension:?}\n");
    let (g, a) = (e / 3.0, PI * r * r);
    let gamma = [
        g * PI * r.powi(4) / 2.0,
        ei(e, r),
        ei(e, r),
        e * a,
        g * a,
        g * a,
    ];
    let xi = cable_uniform_strain(gamma, [0.0, 0.0, d], tension);
    println!(
        "cable: T = {tension:.3} N, independent uniform strain κ_y = {:.10} 1/m (κL = {:.4} rad = {:.3} turns), ε = {:.3e}",
        xi[1],
        xi[1] * l,
        xi[1].abs() * l / (2.0 * PI),
        xi[3]
    );
    assert!(xi[1].abs() * l > 2.0 * PI);
    for n in [1usize, 4] {
        let built = build(&scene(false, l, n, &rod(0.0), &cable));
        let res = statics_or_clear_error(
            &format!("cable N = {n}"),
            &built.model,
            &vec![0.0; built.model.n_dof()],
        )
        .expect("cable statics converges");
        let worst = (0..n)
            .flat_map(|p| (0..6).map(move |k| (p, k)))
            .map(|(p, k)| (res.q[6 * p + k] - xi[k]).abs() / xi[k].abs().max(1e-9 * xi[1].abs()))
            .fold(0.0, f64::max);
        println!(
            "cable N = {n}: max relative |ξ_piece − ξ_balance| over pieces and strains = {worst:.2e}"
        );
        assert!(worst < 1e-8);
    }
    // Dynamics from straight with the full tension applied at t = 0.
    for (visc, t1) in [(0.0, 0.1), (2000.0, 0.3)] {
        let built = build(&scene(false, l, 4, &rod(visc), &cable));
        let run = integrate(
            &built,
            &built.q0,
            &built.qd0,
            Integrator::Rosenbrock,
            Options::tol(1e-7, 1e-10),
            t1,
            30,
            tension,
        )
        .expect("cable: stiff run succeeds");
        let scale = run.kinetic.iter().cloned().fold(0.0, f64::max);
        let p = tips(&built.model, &run.sol);
        println!(
            "cable dynamics (viscosity {visc}): max KE {scale:.3e} J, drift of E + Tℓ_c {:.2e}, worst increase {:.2e} of max KE, final tip ({:.4}, {:.4}), {} steps",
            drift(&run.energy, scale),
            worst_increase(&run.energy, scale),
            p[p.len() - 1][0],
            p[p.len() - 1][2],
            run.sol.stats.steps
        );
        if visc == 0.0 {
            assert!(drift(&run.energy, scale) < 1e-4);
        } else {
            assert!(worst_increase(&run.energy, scale) < 1e-6);
            assert!(run.energy[30] < run.energy[0] - 0.5 * scale);
        }
    }
}

/// A large follower (body-frame) tip force, `P L²/EI = 20`, perpendicular to
/// the tip: the rod curls far. Statics converges by continuation; the
/// equilibrium is checked independently by virtual work on each piece using
/// only the kinematics: `EI ℓ κ_n = ∫_piece (R e_y)·((p_tip − p(s)) × F) ds`
/// and `EA ℓ ε_n = ∫_piece (R e_x)·F ds`. Damped dynamics with the load is
/// stable; dopri5 succeeds or stops clearly.
#[test]
fn large_follower_load() {
    let l = 0.5;
    let n = 8;
    let (e, r) = (1e7, 0.01);
    let p = 20.0 * ei(e, r) / (l * l);
    let rod = |visc: f64| {
        format!(
            "strains = [\"ky\", \"qx\", \"qz\"]\nsection = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5, viscosity = {visc:?} }}"
        )
    };
    let load = format!(
        "[[load]]\nrod = \"arm\"\ns = {l:?}\nforce = [0.0, 0.0, {p:e}]\nframe = \"body\"\n"
    );
    let built = build(&scene(false, l, n, &rod(0.0), &load));
    let model = &built.model;
    let res = statics_or_clear_error("follower", model, &vec![0.0; model.n_dof()])
        .expect("follower statics converges");
    let rodk = &model.rods()[0].spec.geometry;
    let mut kin = RodKinematics::new(rodk);
    kin.update(rodk, res.q.as_slice(), None, None).unwrap();
    let tipp = *kin.tip_pose();
    let f_w = tipp.rotation * nalgebra::Vector3::new(0.0, 0.0, p);
    let gl = GaussLegendre::new(12);
    let (eiv, ea) = (ei(e, r), e * PI * r * r);
    let mut worst: f64 = 0.0;
    let mut worst_ax: f64 = 0.0;
    for (k, piece) in rodk.pieces().iter().enumerate() {
        let (mut mom, mut ax) = (0.0, 0.0);
        for (x, w) in gl.on_interval(piece.length) {
            let g = kin.pose_in_piece(k, x);
            let arm = tipp.translation - g.translation;
            mom += w * (g.rotation * nalgebra::Vector3::y()).dot(&arm.cross(&f_w));
            ax += w * (g.rotation * nalgebra::Vector3::x()).dot(&f_w);
        }
        let q = &res.q.as_slice()[3 * k..3 * k + 3];
        worst = worst.max((eiv * piece.length * q[0] - mom).abs() / (p * l * piece.length));
        worst_ax = worst_ax.max((ea * piece.length * q[1] - ax).abs() / (p * piece.length));
    }
    let angle: f64 = (0..n).map(|k| res.q[3 * k] * rodk.pieces()[k].length).sum();
    println!(
        "follower P L²/EI = 20: tip rotation {angle:.4} rad, tip ({:.4}, {:.4}); virtual-work check: bending {worst:.2e}, axial {worst_ax:.2e} (relative to P·L, P)",
        tipp.translation.x, tipp.translation.z
    );
    assert!(angle.abs() > PI / 2.0, "the load curls the rod");
    assert!(worst < 1e-8 && worst_ax < 1e-8);
    // Damped dynamics under the suddenly applied follower load.
    let damped = build(&scene(false, l, n, &rod(2e4), &load));
    let run = integrate(
        &damped,
        &damped.q0,
        &damped.qd0,
        Integrator::Rosenbrock,
        Options::tol(1e-6, 1e-9),
        0.3,
        30,
        0.0,
    )
    .expect("follower: stiff run succeeds");
    let final_tip = tips(&damped.model, &run.sol)[30];
    let eq = tip(&damped.model, res.q.as_slice()).translation;
    println!(
        "follower damped dynamics: {} steps, tip at 0.3 s ({:.4}, {:.4}), equilibrium ({:.4}, {:.4})",
        run.sol.stats.steps, final_tip[0], final_tip[2], eq.x, eq.z
    );
    explicit_ok_or_clear_error(
        "follower",
        &damped,
        Integrator::Dopri5,
        Options {
            max_steps: 20_000,
            ..Options::tol(1e-6, 1e-9)
        },
        0.3,
        30,
        &tips(&damped.model, &run.sol),
        1e-3,
    );
}
