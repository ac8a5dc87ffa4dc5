//! Extreme motion (issue 8): a fast whirl of a bent rod.
//!
//! The fixtures (scenes, statics with an independent residual check, runs
//! checked for NaN) are in `softrod_tests::extreme` (`tests/src/extreme.rs`);
//! the failure contract every case follows is stated in `extreme_curvature.rs`.
//! Long versions of these scenes, for `softrod report`, are in
//! `examples/extreme/`. Every test prints its measured numbers
//! (`cargo test -p softrod-tests --test extreme_motion -- --nocapture`).

use softrod_integrate::{Integrator, Options};
use softrod_tests::extreme::*;

/// A fast whirl: a bent rod (κ_z = 10 1/m) given a large bending rate
/// κ̇_y = 300 1/(m s) (tip angular velocity ~90 rad/s), no gravity.
/// Undamped the energy is conserved by dopri5 and the stiff method; damped it
/// decreases. No NaN; generalized-α at a large fixed step stays bounded.
#[test]
fn fast_whirl() {
    let l = 0.3;
    let n = 6;
    let rod = |visc: f64| {
        format!(
            "strains = \"all\"\nsection = {{ shape = \"circle\", radius = 0.005 }}\n\
             material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = {visc:?} }}"
        )
    };
    let init = {
        let q: Vec<String> = (0..6 * n)
            .map(|i| {
                if i % 6 == 2 {
                    "10.0".into()
                } else {
                    "0.0".into()
                }
            })
            .collect();
        let qd: Vec<String> = (0..6 * n)
            .map(|i| {
                if i % 6 == 1 {
                    "300.0".into()
                } else {
                    "0.0".into()
                }
            })
            .collect();
        format!(
            "[initial]\nq = [{}]\nqdot = [{}]\n",
            q.join(", "),
            qd.join(", ")
        )
    };
    let built = build(&scene(false, l, n, &rod(0.0), &init));
    let t1 = 0.1;
    let ros = integrate(
        &built,
        &built.q0,
        &built.qd0,
        Integrator::Rosenbrock,
        Options::tol(1e-6, 1e-9),
        t1,
        20,
        0.0,
    )
    .expect("whirl: stiff run succeeds");
    let e0 = ros.energy[0];
    let d = drift(&ros.energy, e0);
    let tip_max = tips(&built.model, &ros.sol)
        .iter()
        .map(|p| p[1].abs().max(p[2].abs()))
        .fold(0.0, f64::max);
    println!(
        "whirl Rosenbrock: E0 = {e0:.4e} J, energy drift {d:.2e}, max lateral tip excursion {tip_max:.3} m, {} steps",
        ros.sol.stats.steps
    );
    assert!(d < 1e-5);
    assert!(tip_max > 0.05, "the whirl moved the tip");
    let ok = explicit_ok_or_clear_error(
        "whirl",
        &built,
        Integrator::Dopri5,
        Options::tol(1e-6, 1e-9),
        t1,
        20,
        &tips(&built.model, &ros.sol),
        1e-4,
    );
    assert!(
        ok,
        "whirl: dopri5 must succeed on this moderately stiff rod"
    );
    // Generalized-α (ρ∞ = 0.9, as `softrod run` uses it) at fixed steps:
    // stable, energy bounded; its energy error is O(dt²) for this nonlinear
    // motion (not monotone: the method is dissipative only for linear
    // problems).
    let mut prev = f64::INFINITY;
    for dt in [1e-3, 2.5e-4] {
        let ga = integrate(
            &built,
            &built.q0,
            &built.qd0,
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 0.9,
                ..Options::fixed(dt)
            },
            t1,
            20,
            0.0,
        )
        .expect("whirl: generalized-α succeeds");
        let dev = drift(&ga.energy, e0);
        println!(
            "whirl generalized-α (ρ∞ = 0.9, dt = {dt:e} s): max |E − E0|/E0 = {dev:.2e}, final (E − E0)/E0 = {:+.2e}, {} steps",
            (ga.energy[20] - e0) / e0,
            ga.sol.stats.steps
        );
        assert!(
            dev < 0.1 && dev < prev / 4.0,
            "generalized-α energy error {dev:e}"
        );
        prev = dev;
    }
    let damped_b = build(&scene(false, l, n, &rod(1000.0), &init));
    let damped = integrate(
        &damped_b,
        &damped_b.q0,
        &damped_b.qd0,
        Integrator::Rosenbrock,
        Options::tol(1e-6, 1e-9),
        t1,
        20,
        0.0,
    )
    .expect("whirl damped: stiff run succeeds");
    let inc = worst_increase(&damped.energy, e0);
    println!(
        "whirl damped: E(t1)/E0 = {:.3}, worst increase {inc:.2e}",
        damped.energy[20] / e0
    );
    assert!(inc < 1e-7 && damped.energy[20] < damped.energy[0]);
}
