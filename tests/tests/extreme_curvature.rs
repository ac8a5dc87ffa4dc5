//! Extreme curvature (issue 8): a nearly straight rod (θ ~ 1e-9, the series
//! branches of exp/T) and a rod rolled into three full turns.
//!
//! Every extreme case (the `extreme_*.rs` files) asserts physics against an
//! independent reference where one exists, and the failure contract
//! everywhere else:
//!
//! - statics converges (residual checked here, independently of the solver's
//!   own test) or fails with `DynamicsError::StaticsFailed`;
//! - the stiff integrators (`Rosenbrock`, `GeneralizedAlpha`) are stable at steps
//!   far beyond the explicit stability limit;
//! - energy is conserved without damping and does not increase with it;
//! - no NaN anywhere (states, energies, tips);
//! - explicit methods either succeed (and then agree with a stiff reference)
//!   or stop with an `IntegrateError`, never return a garbage trajectory.
//!
//! The fixtures (scenes, statics with an independent residual check, runs
//! checked for NaN) are in `softrod_tests::extreme` (`tests/src/extreme.rs`).
//! Long versions of these scenes, for `softrod report`, are in
//! `examples/extreme/`. Every test prints its measured numbers
//! (`cargo test -p softrod-tests --test extreme_curvature -- --nocapture`).

use std::f64::consts::PI;

use nalgebra::DVector;
use softrod_dynamics::{Data, StaticsOptions, forward_dynamics, forward_dynamics_cholesky};
use softrod_integrate::{Integrator, Options};
use softrod_tests::extreme::*;

/// θ ~ 1e-9: the series branches of exp/T. The tip of a bent rod (exact
/// circle of curvature κ) and the statics answer to a tiny tip moment are
/// accurate to 1e-6 *relative to the deflection* (≈ 1e-16 m); the dynamics
/// is linear: the trajectory scales exactly with the amplitude.
#[test]
fn near_straight_rod() {
    let l = 0.5;
    let n = 4;
    let kappa = 2e-9 / l; // θ = κ L = 2e-9 over the rod
    let built = build(&scene(false, l, n, SOFT_ROD, ""));
    let model = &built.model;
    let nd = model.n_dof();
    // Kinematics: uniform κ_y on every piece (coordinates: kx ky kz qx qy qz).
    let mut q = vec![0.0; nd];
    for p in 0..n {
        q[6 * p + 1] = kappa;
    }
    let p = tip(model, &q).translation;
    let (x_ex, z_ex) = (
        (kappa * l).sin() / kappa,
        // 1 − cos θ = 2 sin²(θ/2), without the cancellation.
        -2.0 * (0.5 * kappa * l).sin().powi(2) / kappa,
    );
    let z_lin = -kappa * l * l / 2.0;
    println!(
        "near-straight: tip z {:.12e}, exact {z_ex:.12e} (κL²/2 = {z_lin:.12e})",
        p.z
    );
    assert!((p.z - z_ex).abs() <= 1e-6 * z_ex.abs());
    assert!((p.x - x_ex).abs() <= 1e-15);

    // Statics: follower tip moment M = EI κ (dead and follower coincide to O(θ)).
    let m = ei(1e7, 0.01) * kappa;
    let load = format!(
        "[[load]]\nrod = \"arm\"\ns = {l:?}\nmoment = [0.0, {m:e}, 0.0]\nframe = \"body\"\n"
    );
    let built_m = build(&scene(false, l, n, SOFT_ROD, &load));
    let res = solve_statics(
        &built_m.model,
        &vec![0.0; nd],
        &StaticsOptions {
            tolerance: 1e-13,
            ..Default::default()
        },
    )
    .expect("statics converges");
    let pt = tip(&built_m.model, res.q.as_slice()).translation;
    println!(
        "near-straight statics: tip z {:.12e} vs circle {z_ex:.12e}, rel err {:.2e}, {} its",
        pt.z,
        (pt.z - z_ex).abs() / z_ex.abs(),
        res.iterations
    );
    assert!((pt.z - z_ex).abs() <= 1e-6 * z_ex.abs());

    // Forward dynamics: O(N) and Cholesky agree at θ ~ 1e-9, velocities ~ 1e-9.
    let qd: Vec<f64> = (0..nd).map(|i| 1e-9 * ((i as f64) * 0.7).sin()).collect();
    let mut data = Data::new(model);
    let a = forward_dynamics(model, &mut data, 0.0, &q, &qd, None)
        .unwrap()
        .clone();
    let b = forward_dynamics_cholesky(model, &mut data, 0.0, &q, &qd, None)
        .unwrap()
        .clone();
    let rel = (&a - &b).amax() / b.amax();
    println!("near-straight: |FD − Cholesky|/|q̈| = {rel:.2e}");
    assert!(a.iter().all(|v| v.is_finite()) && rel < 1e-8);

    // Dynamics, released from θ = 2e-9 and from θ = 2e-7: linear, so the
    // trajectories agree after scaling by 100; energy conserved.
    let qd0 = DVector::zeros(nd);
    let run = |scale: f64| {
        let q0 = DVector::from_iterator(nd, q.iter().map(|v| v * scale));
        integrate(
            &built,
            &q0,
            &qd0,
            Integrator::Rosenbrock,
            Options::tol(1e-8, 1e-20 * scale),
            0.02,
            20,
            0.0,
        )
        .expect("stiff run succeeds")
    };
    let small = run(1.0);
    let big = run(100.0);
    let zs: Vec<f64> = tips(model, &small.sol).iter().map(|p| p[2]).collect();
    let zb: Vec<f64> = tips(model, &big.sol).iter().map(|p| p[2] / 100.0).collect();
    let lin = zs
        .iter()
        .zip(&zb)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
        / z_ex.abs();
    let e_scale = small.energy[0].abs().max(1e-300);
    let d = drift(&small.energy, e_scale);
    println!(
        "near-straight dynamics: E0 = {:.3e} J, energy drift {d:.2e} relative, linearity defect {lin:.2e} (of the deflection), {} steps",
        small.energy[0], small.sol.stats.steps
    );
    assert!(small.kinetic.iter().any(|k| *k > 0.0), "the rod moved");
    assert!(d < 1e-3, "energy drift {d:e}");
    assert!(lin < 1e-4, "linearity defect {lin:e}");
}

/// A rod rolled into three full turns by a pure tip moment M = 6π EI/L: the
/// exact answer is a circle traversed three times, tip back at the clamp with
/// the identity rotation, for any number of pieces. Dead (world) and
/// follower (body) moments, 1 and 3 pieces. Then the rolled rod is released
/// (undamped): energy conserved by the stiff method at large steps.
#[test]
fn three_full_turns() {
    let l = 0.5;
    let m = 6.0 * PI * ei(1e7, 0.01) / l;
    for (frame, axis) in [("world", 1usize), ("body", 2)] {
        for n in [1usize, 3] {
            let mut mom = [0.0; 3];
            mom[axis] = m;
            let load = format!(
                "[[load]]\nrod = \"arm\"\ns = {l:?}\nmoment = [{:e}, {:e}, {:e}]\nframe = \"{frame}\"\n",
                mom[0], mom[1], mom[2]
            );
            let built = build(&scene(false, l, n, SOFT_ROD, &load));
            let opts = StaticsOptions {
                tolerance: 1e-13,
                ..Default::default()
            };
            let res = solve_statics(&built.model, &vec![0.0; built.model.n_dof()], &opts)
                .expect("three turns: statics converges");
            let t = tip(&built.model, res.q.as_slice());
            let kl: f64 = res.q[axis] * l;
            println!(
                "three turns ({frame} moment, N = {n}): κL = {kl:.12} (6π = {:.12}), |p_tip| = {:.2e} m, |R − I| = {:.2e}, {} its, {} load steps",
                6.0 * PI,
                t.translation.norm(),
                rot_err(&t),
                res.iterations,
                res.load_steps
            );
            assert!((kl.abs() - 6.0 * PI).abs() < 1e-9);
            assert!(t.translation.norm() < 1e-10);
            assert!(rot_err(&t) < 1e-9);
        }
    }
    // Release the rolled rod (no load, no gravity, undamped).
    let n = 3;
    let built = build(&scene(false, l, n, SOFT_ROD, ""));
    let nd = built.model.n_dof();
    let mut q0 = DVector::zeros(nd);
    for p in 0..n {
        q0[6 * p + 1] = 6.0 * PI / l;
    }
    let qd0 = DVector::zeros(nd);
    let run = integrate(
        &built,
        &q0,
        &qd0,
        Integrator::Rosenbrock,
        Options::tol(1e-7, 1e-10),
        0.05,
        25,
        0.0,
    )
    .expect("rolled release: stiff run succeeds");
    let d = drift(&run.energy, run.energy[0]);
    println!(
        "three turns released: E0 = {:.4} J, relative energy drift {d:.2e}, {} steps, mean step {:.2e} s, {:.3} s wall",
        run.energy[0],
        run.sol.stats.steps,
        0.05 / run.sol.stats.steps as f64,
        run.wall
    );
    assert!(run.kinetic.iter().cloned().fold(0.0, f64::max) > 1e-3 * run.energy[0]);
    assert!(d < 1e-4, "energy drift {d:e}");
}
