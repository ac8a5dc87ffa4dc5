//! Extreme materials (issue 8): a gel (E = 1e4 Pa) that hangs and stretches,
//! and a steel wire (E = 2e11 Pa) whose axial/shear modes are ~1e4 times
//! faster than its first bending mode.
//!
//! The fixtures (scenes, statics with an independent residual check, runs
//! checked for NaN) are in `softrod_tests::extreme` (`tests/src/extreme.rs`);
//! the failure contract every case follows is stated in `extreme_curvature.rs`.
//! Long versions of these scenes, for `softrod report`, are in
//! `examples/extreme/`. Every test prints its measured numbers
//! (`cargo test -p softrod-tests --test extreme_materials -- --nocapture`).

use std::f64::consts::PI;

use nalgebra::DVector;
use softrod_dynamics::{Data, modes};
use softrod_integrate::{Integrator, Options};
use softrod_tests::extreme::*;

/// E = 1e4 Pa (gel): under gravity the rod hangs almost vertically and
/// stretches (ρgL/E ≈ 0.3). Statics converges (continuation) or fails
/// clearly; dynamics conserves energy undamped and loses it damped; dopri5
/// succeeds and agrees with the stiff method.
#[test]
fn very_soft_material() {
    let l = 0.3;
    let rod = |visc: f64| {
        format!(
            "strains = \"all\"\nsection = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e4, poisson = 0.5, viscosity = {visc:?} }}"
        )
    };
    let built = build(&scene(true, l, 4, &rod(0.0), ""));
    let nd = built.model.n_dof();
    let lowest = |q: &DVector<f64>| {
        let mut data = Data::new(&built.model);
        let m = modes(&built.model, &mut data, q.as_slice(), 0.0).unwrap();
        m.omega.iter().cloned().fold(f64::INFINITY, f64::min)
    };
    // From the straight rod, Newton may land on any equilibrium: it is only
    // required to be one (residual checked); its stability is reported.
    let res = statics_or_clear_error("very soft (from straight)", &built.model, &vec![0.0; nd])
        .expect("the very soft rod's statics converges from straight");
    {
        let p = tip(&built.model, res.q.as_slice()).translation;
        let w = lowest(&res.q);
        println!(
            "very soft (from straight): tip ({:.4}, {:.4}, {:.4}) m, lowest ω {w:.3e} rad/s ({})",
            p.x,
            p.y,
            p.z,
            if w < 0.0 {
                "UNSTABLE equilibrium"
            } else {
                "stable"
            }
        );
    }
    // From a hanging guess (quarter turn down): the stable hanging equilibrium.
    let mut guess = vec![0.0; nd];
    for p in 0..4 {
        guess[6 * p + 1] = PI / (2.0 * l);
    }
    let res = statics_or_clear_error("very soft (from hanging guess)", &built.model, &guess)
        .expect("hanging equilibrium");
    let p = tip(&built.model, res.q.as_slice()).translation;
    let w = lowest(&res.q);
    println!(
        "very soft (from hanging guess): tip ({:.4}, {:.4}, {:.4}) m, lowest ω {w:.3e} rad/s",
        p.x, p.y, p.z
    );
    // It hangs: the tip is well below the clamp, near the wall; stable.
    assert!(p.z < -0.6 * l && p.x < 0.5 * l && p.x > -0.1 * l);
    assert!(w > 0.0);
    let t1 = 0.2;
    let undamped = integrate(
        &built,
        &built.q0,
        &built.qd0,
        Integrator::Rosenbrock,
        Options::tol(1e-8, 1e-11),
        t1,
        20,
        0.0,
    )
    .expect("soft, undamped: stiff run succeeds");
    let scale = undamped.kinetic.iter().cloned().fold(0.0, f64::max);
    let d = drift(&undamped.energy, scale);
    println!(
        "very soft undamped: max KE {scale:.3e} J, energy drift {d:.2e} of it, {} steps",
        undamped.sol.stats.steps
    );
    assert!(d < 1e-4);
    let damped_b = build(&scene(true, l, 4, &rod(500.0), ""));
    let damped = integrate(
        &damped_b,
        &damped_b.q0,
        &damped_b.qd0,
        Integrator::Rosenbrock,
        Options::tol(1e-8, 1e-11),
        t1,
        20,
        0.0,
    )
    .expect("soft, damped: stiff run succeeds");
    let inc = worst_increase(&damped.energy, scale);
    println!(
        "very soft damped: E(0) − E(t1) = {:.3e} J, worst energy increase {inc:.2e} of max KE",
        damped.energy[0] - damped.energy[20]
    );
    assert!(inc < 1e-6 && damped.energy[20] < damped.energy[0]);
    let reference = tips(&built.model, &undamped.sol);
    let ok = explicit_ok_or_clear_error(
        "very soft",
        &built,
        Integrator::Dopri5,
        Options::tol(1e-8, 1e-11),
        t1,
        20,
        &reference,
        1e-5,
    );
    assert!(ok, "a soft rod is not stiff: dopri5 must succeed");
}

/// E = 2e11 Pa (steel wire, L/r = 600): the axial/shear modes are ~1e4 times
/// faster than the first bending mode. The stiff methods step far beyond the
/// explicit stability limit 2.8/ω_max; undamped the energy stays bounded;
/// damped it decreases. RK4 beyond its limit stops with an error (never a
/// garbage trajectory); dopri5 either agrees or stops at `max_steps`.
#[test]
fn very_stiff_material() {
    let l = 0.3;
    let rod = |visc: f64| {
        format!(
            "strains = [\"ky\", \"qx\", \"qz\"]\nsection = {{ shape = \"circle\", radius = 5.0e-4 }}\n\
             material = {{ density = 7850.0, young = 2.0e11, poisson = 0.3, viscosity = {visc:?} }}"
        )
    };
    let built = build(&scene(true, l, 5, &rod(0.0), ""));
    let nd = built.model.n_dof();
    let mut data = Data::new(&built.model);
    let md = modes(&built.model, &mut data, &vec![0.0; nd], 0.0).unwrap();
    let w_max = md.omega.iter().cloned().fold(0.0, f64::max);
    let w_min = md.omega.iter().cloned().fold(f64::INFINITY, f64::min);
    let h_explicit = 2.8 / w_max;
    println!(
        "very stiff: ω_min {w_min:.3e}, ω_max {w_max:.3e} rad/s (ratio {:.1e}), explicit limit ≈ {h_explicit:.2e} s",
        w_max / w_min
    );
    let res = statics_or_clear_error("very stiff", &built.model, &vec![0.0; nd])
        .expect("the very stiff rod's statics converges");
    {
        // Linear regime: sag ρAgL⁴/(8EI).
        let a = PI * 25e-8;
        let sag = 7850.0 * a * 9.81 * l.powi(4) / (8.0 * ei(2e11, 5e-4));
        let z = tip(&built.model, res.q.as_slice()).translation.z;
        println!(
            "very stiff: static sag {:.6e} m vs Euler–Bernoulli {sag:.6e} m",
            -z
        );
        // 5 pieces: the PCS bending error is ~1/(4N²)·(something) < 2 %.
        assert!((-z - sag).abs() < 0.02 * sag);
    }
    let t1 = 0.05;
    // Undamped: the release rings the axial/shear modes forever, and an
    // error-controlled method must resolve them; the fixed-step implicit
    // generalized-α steps over them. ρ∞ = 1: no numerical dissipation.
    let dt = 200.0 * h_explicit;
    let ga_run = |dt: f64| {
        integrate(
            &built,
            &built.q0,
            &built.qd0,
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 1.0,
                ..Options::fixed(dt)
            },
            t1,
            25,
            0.0,
        )
        .expect("steel: generalized-α succeeds")
    };
    let ga = ga_run(dt);
    let ga_fine = ga_run(dt / 4.0);
    let scale = ga.kinetic.iter().cloned().fold(0.0, f64::max);
    let dga = drift(&ga.energy, scale);
    let dev = max_dist(
        &tips(&built.model, &ga.sol),
        &tips(&built.model, &ga_fine.sol),
    );
    println!(
        "very stiff undamped, generalized-α (ρ∞ = 1, dt = {dt:.2e} s = 200× limit): {} steps, energy drift {dga:.2e} of max KE ({scale:.3e} J), tip vs dt/4 {dev:.2e} m, {:.3} s wall",
        ga.sol.stats.steps, ga.wall
    );
    assert!(dga < 1e-2, "energy drift {dga:e}");
    assert!(dev < 1e-5, "generalized-α tip deviation {dev:e}");
    // Damped steel (viscosity 1e6 Pa s overdamps the axial/shear modes, leaves
    // bending almost undamped): the adaptive Rosenbrock steps far beyond the
    // explicit limit and the energy never increases.
    let damped_b = build(&scene(true, l, 5, &rod(1e6), ""));
    let ros = integrate(
        &damped_b,
        &damped_b.q0,
        &damped_b.qd0,
        Integrator::Rosenbrock,
        Options::tol(1e-5, 1e-8),
        t1,
        25,
        0.0,
    )
    .expect("damped steel: Rosenbrock succeeds");
    let mean_h = t1 / ros.sol.stats.steps as f64;
    let inc = worst_increase(&ros.energy, scale);
    let dev_b = max_dist(
        &tips(&built.model, &ga_fine.sol),
        &tips(&damped_b.model, &ros.sol),
    );
    println!(
        "very stiff damped, Rosenbrock: {} steps, mean step {mean_h:.2e} s = {:.0}× the explicit limit, worst energy increase {inc:.2e} of max KE, E(t1) − E(0) = {:.3e} J, tip vs undamped {dev_b:.2e} m, {:.3} s wall",
        ros.sol.stats.steps,
        mean_h / h_explicit,
        ros.energy[25] - ros.energy[0],
        ros.wall
    );
    assert!(mean_h > 20.0 * h_explicit);
    assert!(inc < 1e-6 && ros.energy[25] < ros.energy[0]);
    // RK4 at 10× its stability limit: must stop with an error.
    let r = integrate(
        &built,
        &built.q0,
        &built.qd0,
        Integrator::Rk4,
        Options::fixed(10.0 * h_explicit),
        t1,
        25,
        0.0,
    );
    match r {
        Ok(run) => {
            let dev = max_dist(
                &tips(&built.model, &run.sol),
                &tips(&built.model, &ga_fine.sol),
            );
            panic!("RK4 beyond its stability limit returned a trajectory (deviation {dev:e} m)");
        }
        Err(e) => println!("very stiff RK4 at 10× the limit: clear error: {e}"),
    }
    // dopri5 with a step budget: succeeds (and agrees) or stops at max_steps.
    let opts = Options {
        max_steps: 3000,
        ..Options::tol(1e-5, 1e-8)
    };
    explicit_ok_or_clear_error(
        "very stiff",
        &damped_b,
        Integrator::Dopri5,
        opts,
        t1,
        25,
        &tips(&damped_b.model, &ros.sol),
        1e-4,
    );
}
