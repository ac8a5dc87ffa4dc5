//! Each method reaches its nominal order on linear oscillators in matrix form
//! with exact solutions `exp(A t) y0`: observed order `log₂(e(h)/e(h/2))` from
//! two fixed step sizes, and for the adaptive methods the slope of error versus
//! number of steps from two tolerances.

mod common;

use common::{Forced, Linear, LinearFirstOrder, dist, dv};
use softrod_integrate::{
    Integrator, NoHooks, Options, StepControl, integrate, integrate_second_order,
};

const T1: f64 = 4.0;

/// Error at `T1` with fixed step `h` (adaptive methods too), the other
/// options from `base`.
fn fixed_error(sys: &Linear, method: Integrator, base: &Options, h: f64) -> f64 {
    let mut s = sys.clone();
    let opts = Options {
        step: StepControl::Fixed(h),
        ..base.clone()
    };
    let sol = integrate_second_order(
        &mut s,
        method,
        (0.0, T1),
        &Linear::q0(),
        &Linear::qd0(),
        &opts,
        &mut NoHooks,
    )
    .unwrap();
    assert_eq!(sol.t_final, T1);
    dist(&sol.y_final, &sys.exact(T1, &Linear::y0()))
}

fn observed_order(sys: &Linear, method: Integrator, h: f64) -> f64 {
    observed_order_with(sys, method, &Options::default(), h)
}

/// [`observed_order`] with the other options from `base`.
fn observed_order_with(sys: &Linear, method: Integrator, base: &Options, h: f64) -> f64 {
    let e1 = fixed_error(sys, method, base, h);
    let e2 = fixed_error(sys, method, base, h / 2.0);
    let p = (e1 / e2).log2();
    println!("{method:?}: h = {h}: e = {e1:.3e}, h/2: e = {e2:.3e}, observed order {p:.3}");
    p
}

fn assert_order(p: f64, nominal: f64) {
    assert!(
        (p - nominal).abs() < 0.15,
        "observed order {p}, nominal {nominal}"
    );
}

#[test]
fn rk4_is_fourth_order() {
    for sys in [Linear::undamped(), Linear::damped()] {
        assert_order(observed_order(&sys, Integrator::Rk4, 0.05), 4.0);
    }
}

#[test]
fn dopri5_is_fifth_order() {
    for sys in [Linear::undamped(), Linear::damped()] {
        assert_order(observed_order(&sys, Integrator::Dopri5, 0.1), 5.0);
    }
}

#[test]
fn rosw34_is_third_order() {
    for sys in [Linear::undamped(), Linear::damped()] {
        assert_order(observed_order(&sys, Integrator::Rosenbrock, 0.1), 3.0);
    }
}

#[test]
fn esdirk46_is_fourth_order() {
    for sys in [Linear::undamped(), Linear::damped()] {
        assert_order(observed_order(&sys, Integrator::Esdirk, 0.1), 4.0);
    }
}

#[test]
fn esdirk5_is_fifth_order() {
    for sys in [Linear::undamped(), Linear::damped()] {
        assert_order(observed_order(&sys, Integrator::Esdirk5, 0.1), 5.0);
    }
}

#[test]
fn esdirk5_is_fifth_order_on_a_non_autonomous_problem() {
    // The stage times tₙ + cᵢh (one of them, c₆ = 1.04, beyond the step)
    // enter the forcing; a wrong one drops the order.
    let err = |h: f64| {
        let mut s = Forced { w: 2.0, big_w: 1.3 };
        let sol = integrate_second_order(
            &mut s,
            Integrator::Esdirk5,
            (0.0, T1),
            &dv(&[0.0]),
            &dv(&[0.0]),
            &Options::fixed(h),
            &mut NoHooks,
        )
        .unwrap();
        let (q, v) = s.exact(T1);
        (sol.y_final[0] - q).abs().max((sol.y_final[1] - v).abs())
    };
    let p = (err(0.1) / err(0.05)).log2();
    println!("esdirk5 forced: observed order {p:.3}");
    assert_order(p, 5.0);
}

#[test]
fn radau5_is_fifth_order() {
    // Classical order 5 on linear problems (stage order 3 limits it only on
    // very stiff nonlinear ones).
    for sys in [Linear::undamped(), Linear::damped()] {
        assert_order(observed_order(&sys, Integrator::Radau5, 0.2), 5.0);
    }
}

#[test]
fn radau5_first_order_form_is_fifth_order() {
    let lin = Linear::damped();
    let err = |h: f64| {
        let mut s = LinearFirstOrder(lin.a());
        let sol = integrate(
            &mut s,
            Integrator::Radau5,
            (0.0, T1),
            &Linear::y0(),
            &Options::fixed(h),
            &mut NoHooks,
        )
        .unwrap();
        dist(&sol.y_final, &lin.exact(T1, &Linear::y0()))
    };
    let p = (err(0.2) / err(0.1)).log2();
    println!("radau5 first-order: observed order {p:.3}");
    assert_order(p, 5.0);
}

#[test]
fn esdirk46_is_fourth_order_on_a_non_autonomous_problem() {
    // The stage times tₙ + cᵢh enter the forcing; a wrong one drops the
    // order.
    let sys = Forced { w: 2.0, big_w: 1.3 };
    let err = |h: f64| {
        let mut s = Forced { w: 2.0, big_w: 1.3 };
        let sol = integrate_second_order(
            &mut s,
            Integrator::Esdirk,
            (0.0, T1),
            &dv(&[0.0]),
            &dv(&[0.0]),
            &Options::fixed(h),
            &mut NoHooks,
        )
        .unwrap();
        let (q, v) = sys.exact(T1);
        (sol.y_final[0] - q).abs().max((sol.y_final[1] - v).abs())
    };
    let p = (err(0.1) / err(0.05)).log2();
    println!("esdirk46 forced: observed order {p:.3}");
    assert_order(p, 4.0);
}

#[test]
fn rosw34_is_third_order_on_a_non_autonomous_problem() {
    // ∂f/∂t enters through the γᵢ terms; a wrong one drops the order.
    let err = |h: f64| {
        let mut s = Forced { w: 2.0, big_w: 1.3 };
        let opts = Options::fixed(h);
        let sol = integrate_second_order(
            &mut s,
            Integrator::Rosenbrock,
            (0.0, T1),
            &dv(&[0.0]),
            &dv(&[0.0]),
            &opts,
            &mut NoHooks,
        )
        .unwrap();
        let (q, v) = s.exact(T1);
        dist(&sol.y_final, &dv(&[q, v]))
    };
    let p = (err(0.1) / err(0.05)).log2();
    println!("Rosw34 forced: observed order {p:.3}");
    assert_order(p, 3.0);
}

#[test]
fn generalized_alpha_is_second_order_for_all_rho() {
    for rho in [0.0, 0.5, 0.8, 1.0] {
        for sys in [Linear::undamped(), Linear::damped()] {
            let opts = Options {
                rho_inf: rho,
                ..Options::default()
            };
            let p = observed_order_with(&sys, Integrator::GeneralizedAlpha, &opts, 0.02);
            assert_order(p, 2.0);
        }
    }
}

#[test]
fn first_order_path_with_finite_difference_jacobian_matches() {
    // The same oscillator through `OdeSystem` (full 4×4 LU, FD Jacobian).
    let sys = Linear::damped();
    let run = |h: f64| {
        let mut s = LinearFirstOrder(sys.a());
        let opts = Options::fixed(h);
        let sol = integrate(
            &mut s,
            Integrator::Rosenbrock,
            (0.0, T1),
            &Linear::y0(),
            &opts,
            &mut NoHooks,
        )
        .unwrap();
        dist(&sol.y_final, &sys.exact(T1, &Linear::y0()))
    };
    let p = (run(0.1) / run(0.05)).log2();
    assert_order(p, 3.0);
    // And agrees with the Schur-complement path of the second-order adaptor.
    assert!(
        (run(0.1) - fixed_error(&sys, Integrator::Rosenbrock, &Options::default(), 0.1)).abs()
            < 1e-9
    );
}

/// Adaptive runs: error ∝ N^(−p) where N is the number of steps; the slope
/// between two tolerances three decades apart recovers the order.
fn adaptive_slope(method: Integrator, tol_a: f64, tol_b: f64) -> f64 {
    let sys = Linear::damped();
    let run = |tol: f64| {
        let mut s = sys.clone();
        let sol = integrate_second_order(
            &mut s,
            method,
            (0.0, T1),
            &Linear::q0(),
            &Linear::qd0(),
            &Options::tol(tol, tol),
            &mut NoHooks,
        )
        .unwrap();
        (
            dist(&sol.y_final, &sys.exact(T1, &Linear::y0())),
            sol.stats.steps as f64,
        )
    };
    let (ea, na) = run(tol_a);
    let (eb, nb) = run(tol_b);
    let p = (ea / eb).ln() / (nb / na).ln();
    println!(
        "{method:?}: tol {tol_a:e}: {na} steps, e = {ea:.2e}; tol {tol_b:e}: {nb} steps, e = {eb:.2e}; slope {p:.2}"
    );
    p
}

#[test]
fn adaptive_methods_show_their_order_in_error_versus_steps() {
    // Slack: the controller's step-size sequence is not exactly uniform.
    let p = adaptive_slope(Integrator::Dopri5, 1e-5, 1e-9);
    assert!((4.3..=5.8).contains(&p), "dopri5 slope {p}");
    let p = adaptive_slope(Integrator::Rosenbrock, 1e-4, 1e-7);
    assert!((2.5..=3.6).contains(&p), "rosw34 slope {p}");
    let p = adaptive_slope(Integrator::Esdirk, 1e-4, 1e-8);
    assert!((3.4..=4.6).contains(&p), "esdirk46 slope {p}");
    let p = adaptive_slope(Integrator::Esdirk5, 1e-4, 1e-8);
    assert!((4.3..=5.8).contains(&p), "esdirk5 slope {p}");
    let p = adaptive_slope(Integrator::Radau5, 1e-4, 1e-8);
    assert!((4.3..=5.8).contains(&p), "radau5 slope {p}");
}
