//! `Options::breakpoints`: adaptive steps end at a drive's breakpoints
//! instead of stepping across them.

use std::convert::Infallible;

use nalgebra::DVector;
use softrod_integrate::{Integrator, NoHooks, Options, SecondOrderSystem, integrate_second_order};

/// `q̈ = 1` until `t = 1`, then `q̈ = 0`: a push that stops. Exact:
/// `q̇ = min(t, 1)`, `q = t²/2` then `1/2 + (t − 1)`, piecewise polynomial.
struct Push;

impl SecondOrderSystem for Push {
    type Error = Infallible;
    fn dim(&self) -> usize {
        1
    }
    fn accel(
        &mut self,
        t: f64,
        _q: &DVector<f64>,
        _qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Infallible> {
        qdd[0] = if t <= 1.0 { 1.0 } else { 0.0 };
        Ok(())
    }
}

const OUTPUTS: [f64; 7] = [0.3, 0.9, 0.99, 1.0, 1.01, 1.5, 3.0];

fn worst_error(method: Integrator, breakpoints: Vec<f64>) -> f64 {
    let opts = Options {
        t_eval: Some(OUTPUTS.to_vec()),
        breakpoints,
        ..Options::tol(1e-3, 1e-3)
    };
    let zero = DVector::zeros(1);
    let sol = integrate_second_order(
        &mut Push,
        method,
        (0.0, 3.0),
        &zero,
        &zero,
        &opts,
        &mut NoHooks,
    )
    .unwrap();
    let q = |t: f64| if t <= 1.0 { 0.5 * t * t } else { t - 0.5 };
    sol.t
        .iter()
        .zip(&sol.y)
        .map(|(&t, y)| (y[0] - q(t)).abs().max((y[1] - t.min(1.0)).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn adaptive_steps_end_at_breakpoints() {
    for method in [
        Integrator::Dopri5,
        Integrator::Esdirk,
        Integrator::Radau5,
        Integrator::Rosenbrock,
    ] {
        // Both pieces are integrated exactly (polynomial solutions), so what is
        // left is round-off ...
        let with = worst_error(method, vec![1.0, 7.0, -2.0]);
        assert!(with < 1e-12, "{method:?}: {with:e} with the breakpoint");
        // ... while a step across t = 1 meets the kink: an error of the
        // tolerance's size, in the outputs near it.
        let without = worst_error(method, Vec::new());
        assert!(
            without > 1e3 * with.max(1e-15),
            "{method:?}: {without:e} without"
        );
    }
}

/// Generalized-α is not exact on piecewise quadratics (its acceleration
/// variable relaxes over several steps after a jump), but it too lands on
/// the breakpoint and stays within the tolerance there.
#[test]
fn generalized_alpha_stays_within_the_tolerance() {
    let with = worst_error(Integrator::GeneralizedAlpha, vec![1.0]);
    assert!(with < 1e-3, "{with:e}");
}

#[test]
fn a_non_finite_breakpoint_is_an_input_error() {
    let opts = Options {
        breakpoints: vec![f64::NAN],
        ..Options::default()
    };
    let zero = DVector::zeros(1);
    let err = integrate_second_order(
        &mut Push,
        Integrator::Dopri5,
        (0.0, 1.0),
        &zero,
        &zero,
        &opts,
        &mut NoHooks,
    )
    .unwrap_err();
    assert!(err.to_string().contains("breakpoint"), "{err}");
}

/// Breakpoints that are one time up to rounding (`0.3` and `0.1 + 0.2`,
/// 5.6e-17 apart; one a few ulps before the end) are one step end: the run
/// completes instead of failing on a step of a few ulps (issue 28: the loss
/// times `0.05·k` beside a tension table's knot at 0.3), and it is as exact
/// as with the single breakpoint.
#[test]
fn breakpoints_within_rounding_are_one() {
    let third = 0.1 + 0.2;
    assert!(third != 0.3);
    let end = 3.0 - 2.0 * f64::EPSILON;
    assert!(end != 3.0);
    for method in [Integrator::Dopri5, Integrator::Esdirk, Integrator::Radau5] {
        let one = worst_error(method, vec![1.0]);
        let many = worst_error(method, vec![0.3, third, 1.0, 1.0 + f64::EPSILON, end]);
        assert!(many < 1e-12, "{method:?}: {many:e}");
        assert!(one < 1e-12, "{method:?}: {one:e}");
    }
}
