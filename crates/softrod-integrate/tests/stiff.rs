//! Stiff problems: the stiff method finishes within a step budget that the
//! explicit method cannot meet, and generalized-α takes large fixed steps on
//! a stiff structural system.

mod common;

use common::{Linear, Robertson, VanDerPol, dist, dv};
use nalgebra::DMatrix;
use softrod_integrate::{
    IntegrateError, Integrator, NoHooks, Options, integrate, integrate_second_order,
};

/// Van der Pol, μ = 1000, over [0, 3000]: almost two relaxation periods
/// (period ≈ (3 − 2 ln 2) μ ≈ 1614), with two fast jumps.
const VDP_T1: f64 = 3000.0;
/// Step budget: the stiff method needs ≈ 2 700 steps at tolerance 1e-6 (most
/// of them in the four fast jumps, whose time scale is ~1/μ), while on the
/// slow branches the explicit method's stability limit `h ≲ 3.3/|λ|`,
/// `|λ| ≈ μ (y₁² − 1)`, alone needs about 10⁶ steps over the interval.
const VDP_BUDGET: usize = 5_000;

fn vdp_opts(tol: f64) -> Options {
    Options {
        max_steps: VDP_BUDGET,
        ..Options::tol(tol, tol)
    }
}

#[test]
fn van_der_pol_mu_1000_rosw_within_budget_dopri5_not() {
    let y0 = dv(&[2.0, 0.0]);
    let sol = integrate(
        &mut VanDerPol { mu: 1000.0 },
        Integrator::Rosenbrock,
        (0.0, VDP_T1),
        &y0,
        &vdp_opts(1e-6),
        &mut NoHooks,
    )
    .unwrap();
    println!("rosw34 VdP μ=1000 tol 1e-6: {:?}", sol.stats);
    assert!(sol.stats.steps < VDP_BUDGET);
    // The relaxation oscillation stays on |y₁| ≤ 2 (plus tolerance).
    assert!(sol.y.iter().all(|y| y[0].abs() < 2.01));
    // Jacobians and LUs are reused: fewer of each than steps.
    assert!(sol.stats.jacobian_evaluations < sol.stats.steps);
    assert!(sol.stats.factorizations < sol.stats.steps + sol.stats.rejected_steps);

    // Self-convergence: a tighter run agrees (the jump times are sensitive, so
    // compare away from a jump: at t1 the solution is on a slow branch).
    let fine = integrate(
        &mut VanDerPol { mu: 1000.0 },
        Integrator::Rosenbrock,
        (0.0, VDP_T1),
        &y0,
        &Options {
            max_steps: 100_000,
            ..Options::tol(1e-8, 1e-8)
        },
        &mut NoHooks,
    )
    .unwrap();
    println!("rosw34 VdP μ=1000 tol 1e-8: {:?}", fine.stats);
    let d = (sol.y_final[0] - fine.y_final[0]).abs();
    println!(
        "y1(3000): {} vs {} (diff {d:e})",
        sol.y_final[0], fine.y_final[0]
    );
    assert!(d < 1e-3, "y1 differs by {d}");

    // The explicit method runs out of the same budget.
    let err = integrate(
        &mut VanDerPol { mu: 1000.0 },
        Integrator::Dopri5,
        (0.0, VDP_T1),
        &y0,
        &vdp_opts(1e-6),
        &mut NoHooks,
    )
    .unwrap_err();
    println!("dopri5: {err}");
    match err {
        IntegrateError::MaxStepsExceeded { t, max_steps, .. } => {
            assert_eq!(max_steps, VDP_BUDGET);
            assert!(t < 0.05 * VDP_T1, "dopri5 got to t = {t}");
        }
        e => panic!("expected MaxStepsExceeded, got {e}"),
    }
}

#[test]
fn robertson_to_t_40_matches_the_reference() {
    // Reference y(40) from Hairer–Wanner, ODEs II, §IV.10 (RADAU5 at tight
    // tolerance): (0.7158270687, 0.9185534764e-5, 0.2841637457).
    let reference = [0.715_827_068_7, 0.918_553_476_4e-5, 0.284_163_745_7];
    let opts = Options {
        atol: 1e-12,
        rtol: 1e-8,
        max_steps: VDP_BUDGET,
        ..Options::default()
    };
    let sol = integrate(
        &mut Robertson,
        Integrator::Rosenbrock,
        (0.0, 40.0),
        &dv(&[1.0, 0.0, 0.0]),
        &opts,
        &mut NoHooks,
    )
    .unwrap();
    println!("Robertson: {:?}, y = {}", sol.stats, sol.y_final);
    for (i, r) in reference.iter().enumerate() {
        let rel = (sol.y_final[i] - r).abs() / r;
        assert!(rel < 1e-5, "component {i}: rel error {rel}");
    }
    let mass: f64 = sol.y_final.sum();
    assert!((mass - 1.0).abs() < 1e-12);
}

/// Two decoupled modes ω = 1 and ω = 10⁴ (an "extension" mode 10⁴ times
/// stiffer than the "bending" one), lightly damped.
fn stiff_pair() -> Linear {
    Linear {
        k: DMatrix::from_diagonal(&dv(&[1.0, 1e8])),
        d: DMatrix::from_diagonal(&dv(&[0.0, 0.0])),
        calls: 0,
    }
}

#[test]
fn generalized_alpha_takes_large_steps_and_damps_the_stiff_mode() {
    // dt = 0.05: ω₂·dt = 500. An explicit method would need dt < 2.8e-4.
    let q0 = dv(&[1.0, 1e-3]);
    let qd0 = dv(&[0.0, 0.0]);
    let t1 = 2.0;
    let mut amplitudes = Vec::new();
    for rho in [0.0, 0.5, 1.0] {
        let mut sys = stiff_pair();
        let sol = integrate_second_order(
            &mut sys,
            Integrator::GeneralizedAlpha,
            (0.0, t1),
            &q0,
            &qd0,
            &Options {
                rho_inf: rho,
                // Never refresh a Jacobian that works (it is constant here).
                jacobian_max_age: usize::MAX,
                ..Options::fixed(0.05)
            },
            &mut NoHooks,
        )
        .unwrap();
        println!("rho_inf {rho}: {:?}", sol.stats);
        assert_eq!(sol.stats.steps, 40);
        // Linear problem, fixed step: one Jacobian, one LU, 2 Newton iterations.
        assert_eq!(sol.stats.jacobian_evaluations, 1);
        assert_eq!(sol.stats.factorizations, 1);
        assert_eq!(sol.stats.rejected_steps, 0);
        // The slow mode is accurate to O((ω₁ dt)²).
        let slow = sol.y_final[0];
        assert!(
            (slow - t1.cos()).abs() < 5e-3,
            "rho {rho}: slow mode {slow}"
        );
        let amp = sol.y_final[1].abs().max(sol.y_final[3].abs() / 1e4);
        println!("rho_inf {rho}: stiff-mode amplitude after 40 steps {amp:.3e}");
        amplitudes.push(amp);
    }
    // ρ∞ = 0 annihilates the stiff mode, ρ∞ = 1 keeps it, 0.5 is in between.
    assert!(amplitudes[0] < 1e-3 * 1e-6, "{amplitudes:?}");
    // ρ∞ = 0.5: the amplification matrix tends to a triple eigenvalue −ρ∞
    // (Chung–Hulbert), a Jordan block: after N steps the amplitude ratio is ρ∞ᴺ
    // times at most the Jordan factor C(N, 2)/ρ∞² < N²/ρ∞².
    let ratio = amplitudes[1] / 1e-3;
    let rn = 0.5f64.powi(40);
    assert!(
        ratio > rn && ratio < 40.0 * 40.0 / 0.25 * rn,
        "ratio {ratio}, ρ∞ᴺ = {rn}"
    );
    assert!(amplitudes[2] > 0.5e-3);
}

#[test]
fn rosw34_on_the_stiff_pair_is_not_limited_by_the_stiff_mode() {
    // Start on the slow manifold of the stiff mode (q₂ = 0) so its amplitude
    // is not resolved: the step size is set by the slow mode only.
    let mut sys = stiff_pair();
    let sol = integrate_second_order(
        &mut sys,
        Integrator::Rosenbrock,
        (0.0, 10.0),
        &dv(&[1.0, 0.0]),
        &dv(&[0.0, 0.0]),
        &Options::tol(1e-6, 1e-8),
        &mut NoHooks,
    )
    .unwrap();
    println!("rosw34 stiff pair: {:?}", sol.stats);
    assert!(sol.stats.steps < 1000);
    let exact = stiff_pair().exact(10.0, &dv(&[1.0, 0.0, 0.0, 0.0]));
    assert!(dist(&sol.y_final, &exact) < 1e-4);
}
