//! The common interface: dense output at requested times, events, the
//! per-step callback, failures as structured errors, determinism, statistics.

mod common;

use std::convert::Infallible;

use common::{Linear, VanDerPol, dist, dv};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use softrod_integrate::{
    Callbacks, Control, Direction, Event, Hooks, IntegrateError, Integrator, Iteration, NoHooks,
    Options, SecondOrderSystem, Status, StepInfo, integrate, integrate_second_order,
};

const ALL: [Integrator; 5] = [
    Integrator::Rk4,
    Integrator::Dopri5,
    Integrator::Rosenbrock,
    Integrator::GeneralizedAlpha,
    Integrator::Esdirk,
];

/// Options per method: fixed methods get a step, adaptive ones tolerances;
/// generalized-α runs with `ρ∞ = 0.8`.
fn opts_for(method: Integrator, dt: f64, tol: f64) -> Options {
    match method {
        Integrator::Rk4 => Options::fixed(dt),
        Integrator::GeneralizedAlpha => Options {
            rho_inf: 0.8,
            ..Options::fixed(dt)
        },
        _ => Options::tol(tol, tol),
    }
}

fn run(
    method: Integrator,
    sys: &mut Linear,
    t1: f64,
    opts: &Options,
) -> softrod_integrate::Solution {
    integrate_second_order(
        sys,
        method,
        (0.0, t1),
        &Linear::q0(),
        &Linear::qd0(),
        opts,
        &mut NoHooks,
    )
    .unwrap()
}

#[test]
fn dense_output_at_requested_times_does_not_force_steps() {
    let sys = Linear::damped();
    let t_eval: Vec<f64> = (0..=400).map(|i| i as f64 * 0.01).collect();
    for (method, dt, tol) in [
        (Integrator::Rk4, 0.05, 0.0),
        (Integrator::Dopri5, 0.0, 1e-10),
        (Integrator::Rosenbrock, 0.0, 1e-6),
        (Integrator::GeneralizedAlpha, 0.02, 0.0),
    ] {
        // Generalized-α with ρ∞ = 1.
        let opts = Options {
            rho_inf: 1.0,
            ..opts_for(method, dt, tol).with_t_eval(t_eval.clone())
        };
        let sol = run(method, &mut sys.clone(), 4.0, &opts);
        assert_eq!(sol.t, t_eval);
        let err = sol
            .t
            .iter()
            .zip(&sol.y)
            .map(|(&t, y)| dist(y, &sys.exact(t, &Linear::y0())))
            .fold(0.0, f64::max);
        println!(
            "{method:?}: {} steps for 401 outputs, max error {err:.2e}",
            sol.stats.steps
        );
        // Fewer steps than outputs: the outputs are interpolated.
        assert!(
            sol.stats.steps < 300,
            "{method:?} took {} steps",
            sol.stats.steps
        );
        // Dense output is as accurate as the steps (bounds from the methods'
        // global errors at these settings).
        let bound = match method {
            Integrator::Rk4 => 1e-5,
            Integrator::Dopri5 => 1e-8,
            Integrator::Rosenbrock => 1e-4,
            _ => 1e-3, // second order, h = 0.02
        };
        assert!(err < bound, "{method:?}: dense error {err}");
    }
}

/// `Options::steps_to_outputs` (docs/theory-derivatives.md CD10): the
/// adaptive methods' steps end on the 401 output times (at least one step
/// per output interval, where the same run without it steps across them),
/// and the outputs, now step ends, are as accurate as the dense ones
/// against the exact solution.
#[test]
fn steps_to_outputs_ends_the_adaptive_steps_on_the_output_times() {
    let sys = Linear::damped();
    let t_eval: Vec<f64> = (0..=400).map(|i| i as f64 * 0.01).collect();
    for method in [
        Integrator::Dopri5,
        Integrator::Rosenbrock,
        Integrator::Esdirk,
        Integrator::Radau5,
    ] {
        let free_opts = opts_for(method, 0.0, 1e-6).with_t_eval(t_eval.clone());
        let landed_opts = Options {
            steps_to_outputs: true,
            ..free_opts.clone()
        };
        let free = run(method, &mut sys.clone(), 4.0, &free_opts);
        let landed = run(method, &mut sys.clone(), 4.0, &landed_opts);
        assert_eq!(landed.t, t_eval);
        assert!(
            free.stats.steps < 400 && landed.stats.steps >= 400,
            "{method:?}: {} steps free, {} landed",
            free.stats.steps,
            landed.stats.steps
        );
        let err = |sol: &softrod_integrate::Solution| {
            sol.t
                .iter()
                .zip(&sol.y)
                .map(|(&t, y)| dist(y, &sys.exact(t, &Linear::y0())))
                .fold(0.0, f64::max)
        };
        assert!(
            err(&landed) < 1e-4 && err(&free) < 1e-4,
            "{method:?}: error {:e} landed, {:e} free",
            err(&landed),
            err(&free)
        );
    }
    // Fixed steps keep their grid.
    let fixed = opts_for(Integrator::Rk4, 0.05, 0.0).with_t_eval(t_eval.clone());
    let a = run(Integrator::Rk4, &mut sys.clone(), 4.0, &fixed);
    let b = run(
        Integrator::Rk4,
        &mut sys.clone(),
        4.0,
        &Options {
            steps_to_outputs: true,
            ..fixed
        },
    );
    assert_eq!(a.stats.steps, b.stats.steps);
    assert_eq!(a.y, b.y);
}

/// `q̈ = −diag(4, 9) q`, `q(0) = (1, 0)`: `q₁ = cos 2t` is zero at π/4, 3π/4.
fn decoupled() -> Linear {
    Linear {
        k: DMatrix::from_diagonal(&dv(&[4.0, 9.0])),
        d: DMatrix::zeros(2, 2),
        calls: 0,
    }
}

#[test]
fn terminal_and_recorded_events_are_located_on_the_dense_output() {
    let pi = std::f64::consts::PI;
    for method in ALL {
        let opts = match method {
            Integrator::Rk4 => Options::fixed(1e-3),
            Integrator::GeneralizedAlpha => Options {
                rho_inf: 0.8,
                ..Options::fixed(1e-4)
            },
            _ => Options::tol(1e-10, 1e-10),
        };
        let mut hooks = Callbacks::new()
            // Recorded: q₁ crosses zero downwards at π/4.
            .event(Event::record(|_t, y: &DVector<f64>| y[0]).direction(Direction::Falling))
            // Terminal: q₁ crosses zero upwards at 3π/4.
            .event(Event::terminal(|_t, y: &DVector<f64>| y[0]).direction(Direction::Rising));
        let sol = integrate_second_order(
            &mut decoupled(),
            method,
            (0.0, 10.0),
            &dv(&[1.0, 0.0]),
            &dv(&[0.0, 0.0]),
            &opts,
            &mut hooks,
        )
        .unwrap();
        assert_eq!(sol.status, Status::Event { index: 1 });
        assert_eq!(sol.events.len(), 2, "{:?}", sol.events);
        let tol = match method {
            Integrator::GeneralizedAlpha => 1e-6,
            _ => 1e-8,
        };
        assert_eq!(sol.events[0].index, 0);
        assert!(
            (sol.events[0].t - pi / 4.0).abs() < tol,
            "{method:?}: {}",
            sol.events[0].t
        );
        assert!(
            (sol.t_final - 3.0 * pi / 4.0).abs() < tol,
            "{method:?}: {}",
            sol.t_final
        );
        assert_eq!(*sol.t.last().unwrap(), sol.t_final);
        assert!(sol.y_final[0].abs() < tol);
    }
}

/// Records every step `(t, steps so far)`; stops after the 5th.
#[derive(Default)]
struct StopAfterFive {
    seen: Vec<(f64, usize)>,
}

impl Hooks<Linear> for StopAfterFive {
    fn step(&mut self, info: &StepInfo<'_>, _: &mut Linear) -> Control {
        self.seen.push((info.t, info.stats.steps));
        if info.stats.steps == 5 {
            Control::Stop
        } else {
            Control::Continue
        }
    }
}

#[test]
fn callback_can_stop_and_sees_every_step() {
    for method in ALL {
        let mut hooks = StopAfterFive::default();
        let sol = integrate_second_order(
            &mut Linear::undamped(),
            method,
            (0.0, 100.0),
            &Linear::q0(),
            &Linear::qd0(),
            &opts_for(method, 0.01, 1e-6),
            &mut hooks,
        )
        .unwrap();
        assert_eq!(sol.status, Status::Stopped);
        assert_eq!(sol.stats.steps, 5);
        let seen = hooks.seen;
        assert_eq!(seen.len(), 5);
        assert_eq!(sol.t_final, seen[4].0);
        assert_eq!(*sol.t.last().unwrap(), sol.t_final);
    }
}

/// A control law: at the first step with `t ≥ 1` it doubles `K`.
struct Stiffen {
    t_switch: f64,
}

impl Hooks<Linear> for Stiffen {
    fn step(&mut self, info: &StepInfo<'_>, s: &mut Linear) -> Control {
        if info.t >= 1.0 && self.t_switch.is_nan() {
            self.t_switch = info.t;
            s.k *= 2.0;
            Control::SystemChanged
        } else {
            Control::Continue
        }
    }
}

#[test]
fn a_control_law_changing_the_system_equals_a_restart() {
    // At the first step with t ≥ 1 the callback stiffens K (a parameter
    // change); the result must equal stopping there and restarting with the
    // new system — bit for bit with fixed-step RK4.
    let opts = Options::fixed(0.01);
    let mut hooks = Stiffen { t_switch: f64::NAN };
    let mut sys = Linear::undamped();
    let full = integrate_second_order(
        &mut sys,
        Integrator::Rk4,
        (0.0, 2.0),
        &Linear::q0(),
        &Linear::qd0(),
        &opts,
        &mut hooks,
    )
    .unwrap();
    let t_switch = hooks.t_switch;
    assert!((1.0..1.02).contains(&t_switch));
    let first = run(Integrator::Rk4, &mut Linear::undamped(), t_switch, &opts);
    let mut stiffer = Linear::undamped();
    stiffer.k *= 2.0;
    let y = &first.y_final;
    let second = integrate_second_order(
        &mut stiffer,
        Integrator::Rk4,
        (t_switch, 2.0),
        &y.rows(0, 2).into_owned(),
        &y.rows(2, 2).into_owned(),
        &opts,
        &mut NoHooks,
    )
    .unwrap();
    assert_eq!(full.y_final, second.y_final);
    assert_eq!(full.t_final, 2.0);
}

/// `q̈ = −q` until `t_bad`, then NaN (or an error, if `fail`).
struct Breaks {
    t_bad: f64,
    fail: bool,
}

#[derive(Debug, thiserror::Error)]
#[error("model broke")]
struct Broke;

impl SecondOrderSystem for Breaks {
    type Error = Broke;
    fn dim(&self) -> usize {
        1
    }
    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        _qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Broke> {
        if t > self.t_bad {
            if self.fail {
                return Err(Broke);
            }
            qdd[0] = f64::NAN;
        } else {
            qdd[0] = -q[0];
        }
        Ok(())
    }
}

fn run_breaks(
    method: Integrator,
    fail: bool,
) -> Result<softrod_integrate::Solution, IntegrateError> {
    integrate_second_order(
        &mut Breaks { t_bad: 1.0, fail },
        method,
        (0.0, 2.0),
        &dv(&[1.0]),
        &dv(&[0.0]),
        &opts_for(method, 0.1, 1e-6),
        &mut NoHooks,
    )
}

#[test]
fn nan_in_the_model_is_an_error_with_context_never_a_nan_trajectory() {
    for method in ALL {
        let err = run_breaks(method, false).unwrap_err();
        println!("{method:?}: {err}");
        match (method, &err) {
            (Integrator::Rk4, IntegrateError::NonFinite { t, .. }) => assert!(*t > 1.0),
            (
                Integrator::Dopri5 | Integrator::Rosenbrock | Integrator::Esdirk,
                IntegrateError::StepSizeUnderflow { t, reason, .. },
            ) => {
                assert!((*t - 1.0).abs() < 1e-6, "stopped at {t}");
                assert!(reason.contains("non-finite"), "{reason}");
            }
            (
                Integrator::GeneralizedAlpha,
                IntegrateError::NewtonNonConvergence { t, what, .. },
            ) => {
                assert!((*t - 1.0).abs() < 1e-6, "stopped at {t}");
                assert_eq!(*what, "non-finite iterate");
            }
            _ => panic!("{method:?}: unexpected {err:?}"),
        }
    }
}

#[test]
fn system_errors_are_wrapped_with_time() {
    for method in ALL {
        match run_breaks(method, true).unwrap_err() {
            IntegrateError::System { t, source, .. } => {
                assert!(t <= 1.0 + 1e-12 && t > 0.5, "{method:?}: t = {t}");
                assert_eq!(source.to_string(), "model broke");
            }
            e => panic!("{method:?}: unexpected {e:?}"),
        }
    }
}

#[test]
fn blow_up_beyond_a_user_bound_is_an_error() {
    // q̈ = +q grows like eᵗ.
    let unstable = || Linear {
        k: -DMatrix::identity(2, 2),
        d: DMatrix::zeros(2, 2),
        calls: 0,
    };
    for method in ALL {
        let opts = Options {
            max_norm: 1e3,
            ..opts_for(method, 0.01, 1e-6)
        };
        let err = run_m(method, &mut unstable(), 20.0, &opts, &mut NoHooks).unwrap_err();
        match err {
            IntegrateError::BoundExceeded {
                t, value, bound, ..
            } => {
                assert_eq!(bound, 1e3);
                assert!(value > 1e3 && t > 6.0 && t < 8.0, "{method:?}: t = {t}");
            }
            e => panic!("{method:?}: {e:?}"),
        }
        // An energy monitor.
        let energy = |_t: f64, y: &DVector<f64>| 0.5 * y.rows(2, 2).norm_squared();
        let mut hooks = Callbacks::new().monitor("kinetic energy", 50.0, energy);
        match run_m(
            method,
            &mut unstable(),
            20.0,
            &opts_for(method, 0.01, 1e-6),
            &mut hooks,
        )
        .unwrap_err()
        {
            IntegrateError::BoundExceeded { what, .. } => assert_eq!(what, "kinetic energy"),
            e => panic!("{method:?}: {e:?}"),
        }
    }
}

fn run_m(
    method: Integrator,
    sys: &mut Linear,
    t1: f64,
    opts: &Options,
    hooks: &mut dyn Hooks<Linear>,
) -> Result<softrod_integrate::Solution, IntegrateError> {
    integrate_second_order(
        sys,
        method,
        (0.0, t1),
        &Linear::q0(),
        &Linear::qd0(),
        opts,
        hooks,
    )
}

#[test]
fn invalid_input_is_rejected() {
    let mut s = Linear::undamped();
    let cases: Vec<(Integrator, Options, f64)> = vec![
        (Integrator::Rk4, Options::default(), 1.0), // adaptive: no error estimate
        (Integrator::Rk4, Options::fixed(0.0), 1.0),
        (Integrator::Dopri5, Options::fixed(f64::NAN), 1.0),
        (Integrator::Dopri5, Options::default().with_h0(-1.0), 1.0),
        (Integrator::Rosenbrock, Options::linearly_implicit(0.1), 1.0), // gen-α only
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 0.8,
                iteration: Iteration::Newton {
                    tol: 1e-2,
                    max_iter: 0,
                },
                ..Options::fixed(0.1)
            },
            1.0,
        ),
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 0.8,
                iteration: Iteration::Newton {
                    tol: f64::NAN,
                    max_iter: 4,
                },
                ..Options::fixed(0.1)
            },
            1.0,
        ),
        (
            Integrator::GeneralizedAlpha,
            Options {
                rho_inf: 1.5,
                ..Options::fixed(0.1)
            },
            1.0,
        ),
        (Integrator::Dopri5, Options::default(), -1.0), // t1 < t0
        (Integrator::Dopri5, Options::tol(0.0, 0.0), 1.0),
        (
            Integrator::Dopri5,
            Options::default().with_t_eval(vec![0.5, 0.2]),
            1.0,
        ),
        (
            Integrator::Dopri5,
            Options::default().with_t_eval(vec![2.0]),
            1.0,
        ),
    ];
    for (m, o, t1) in cases {
        // The settings alone are rejected by Options::validate unless the
        // fault is in the time span.
        if t1 >= 0.0
            && o.t_eval
                .as_ref()
                .is_none_or(|te| te.iter().all(|&t| t <= t1))
        {
            assert!(
                matches!(o.validate(m), Err(IntegrateError::InvalidInput { .. })),
                "{m:?} {o:?}"
            );
        }
        match run_m(m, &mut s, t1, &o, &mut NoHooks) {
            Err(IntegrateError::InvalidInput { what }) => println!("{m:?}: {what}"),
            r => panic!("{m:?}: expected InvalidInput, got {r:?}"),
        }
    }
    // Generalized-α on a first-order system.
    let r = integrate(
        &mut VanDerPol { mu: 1.0 },
        Integrator::GeneralizedAlpha,
        (0.0, 1.0),
        &dv(&[2.0, 0.0]),
        &Options {
            rho_inf: 0.5,
            ..Options::fixed(0.1)
        },
        &mut NoHooks,
    );
    assert!(matches!(r, Err(IntegrateError::InvalidInput { .. })));
}

#[test]
fn same_input_same_bits() {
    for method in ALL {
        let opts = opts_for(method, 0.01, 1e-7).with_t_eval(vec![0.3, 1.7, 2.9]);
        let a = run(method, &mut Linear::damped(), 3.0, &opts);
        let b = run(method, &mut Linear::damped(), 3.0, &opts);
        assert_eq!(a, b);
    }
    let vdp = |_: ()| {
        integrate(
            &mut VanDerPol { mu: 10.0 },
            Integrator::Rosenbrock,
            (0.0, 30.0),
            &dv(&[2.0, 0.0]),
            &Options::tol(1e-6, 1e-6),
            &mut NoHooks,
        )
        .unwrap()
    };
    assert_eq!(vdp(()), vdp(()));
}

#[test]
fn statistics_count_the_work() {
    for method in ALL {
        let mut s = Linear::damped();
        let sol = run(method, &mut s, 4.0, &opts_for(method, 0.05, 1e-6));
        println!("{method:?}: {:?}", sol.stats);
        // Every accel call is counted (the Jacobians are analytic here).
        assert_eq!(sol.stats.rhs_evaluations, s.calls, "{method:?}");
        let st = sol.stats;
        match method {
            Integrator::Rk4 => assert_eq!(st.rhs_evaluations, 4 * st.steps + 1),
            Integrator::Dopri5 => {
                // FSAL: 6 per attempted step, + initial f + starting-step guess.
                assert_eq!(st.rhs_evaluations, 6 * (st.steps + st.rejected_steps) + 2)
            }
            Integrator::Rosenbrock => {
                assert!(st.factorizations >= 1 && st.jacobian_evaluations >= 1);
                assert_eq!(st.lu_solves, 4 * (st.steps + st.rejected_steps));
            }
            Integrator::GeneralizedAlpha => {
                assert_eq!(st.lu_solves, st.newton_iterations);
                assert_eq!(st.rhs_evaluations, st.newton_iterations + 1);
            }
            Integrator::Esdirk => {
                // One residual per Newton iteration, the initial
                // acceleration and the starting-step guess; one solve per
                // iteration and per error estimate (accepted or rejected by
                // the error test).
                assert_eq!(st.rhs_evaluations, st.newton_iterations + 2);
                assert!(st.lu_solves >= st.newton_iterations + st.steps);
                assert!(st.lu_solves <= st.newton_iterations + st.steps + st.rejected_steps);
            }
            _ => unreachable!(),
        }
    }
}

#[test]
fn first_and_second_order_interfaces_agree() {
    // The same damped oscillator through both traits with DOPRI5 (no
    // Jacobian involved): same steps, same result to rounding (the matrix
    // product A·y and the split accel sum in a different order).
    let sys = Linear::damped();
    let opts = Options::tol(1e-8, 1e-8);
    let a = run(Integrator::Dopri5, &mut sys.clone(), 3.0, &opts);
    let b = integrate(
        &mut common::LinearFirstOrder(sys.a()),
        Integrator::Dopri5,
        (0.0, 3.0),
        &Linear::y0(),
        &opts,
        &mut NoHooks,
    )
    .unwrap();
    assert_eq!(a.stats.steps, b.stats.steps);
    assert!(dist(&a.y_final, &b.y_final) < 1e-14);
}

/// An infallible scalar decay `y' = −λ y`.
struct Decay(f64);
impl softrod_integrate::OdeSystem for Decay {
    type Error = Infallible;
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, y: &DVector<f64>, dy: &mut DVector<f64>) -> Result<(), Infallible> {
        dy[0] = -self.0 * y[0];
        Ok(())
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]
    /// For any rate and interval, the adaptive methods meet the tolerance on
    /// `y' = −λ y` and never leave [0, y0] (L-stability for ROS34PW2).
    #[test]
    fn decay_is_accurate_and_monotone(lambda in 0.1f64..1e4, t1 in 0.1f64..10.0) {
        for method in [Integrator::Dopri5, Integrator::Rosenbrock] {
            let sol = integrate(&mut Decay(lambda), method, (0.0, t1), &dv(&[1.0]),
                &Options { max_steps: 1_000_000, ..Options::tol(1e-8, 1e-10) }, &mut NoHooks).unwrap();
            let exact = (-lambda * t1).exp();
            prop_assert!((sol.y_final[0] - exact).abs() < 1e-6, "{:?}: {} vs {}", method, sol.y_final[0], exact);
            prop_assert!(sol.y.iter().all(|y| y[0] <= 1.0 + 1e-12 && y[0] >= -1e-6));
        }
    }
}

/// Logs outputs (`'o'`) and steps (`'s'`) in the order they come, keeping
/// no outputs in the solution.
#[derive(Default)]
struct Log(Vec<(char, f64, DVector<f64>)>);

impl Hooks<Linear> for Log {
    fn keep_outputs(&self) -> bool {
        false
    }
    fn output(&mut self, t: f64, y: &DVector<f64>, _: &mut Linear) -> Control {
        self.0.push(('o', t, y.clone()));
        Control::Continue
    }
    fn step(&mut self, info: &StepInfo<'_>, _: &mut Linear) -> Control {
        self.0.push(('s', info.t, info.y.clone()));
        Control::Continue
    }
}

/// The output hook sees exactly the stored outputs, in order, as the run
/// proceeds (before the step's hook); with `keep_outputs` false none is
/// stored; `Stop` from it ends the run at that output time.
#[test]
fn output_callback_streams_dense_output_and_can_stop() {
    let te: Vec<f64> = (0..=40).map(|k| 0.25 * k as f64).collect();
    for method in ALL {
        let opts = opts_for(method, 0.01, 1e-8).with_t_eval(te.clone());
        let reference = run(method, &mut Linear::undamped(), 10.0, &opts);

        let mut hooks = Log::default();
        let sol = integrate_second_order(
            &mut Linear::undamped(),
            method,
            (0.0, 10.0),
            &Linear::q0(),
            &Linear::qd0(),
            &opts,
            &mut hooks,
        )
        .unwrap();
        assert!(sol.t.is_empty() && sol.y.is_empty());
        assert_eq!(sol.y_final, reference.y_final);
        let log = hooks.0;
        let outs: Vec<_> = log.iter().filter(|e| e.0 == 'o').collect();
        assert_eq!(outs.len(), te.len());
        for (o, (t, y)) in outs.iter().zip(reference.t.iter().zip(&reference.y)) {
            assert_eq!(o.1, *t);
            assert_eq!(&o.2, y);
        }
        // Outputs in (t_prev, t] come before the step's callback at t.
        let mut last_step_t = 0.0;
        for e in &log {
            match e.0 {
                's' => last_step_t = e.1,
                _ => assert!(
                    e.1 >= last_step_t,
                    "{method:?}: output at {} after step {}",
                    e.1,
                    last_step_t
                ),
            }
        }

        // Stop at the 5th output (t = 1).
        let mut count = 0;
        let mut hooks = Callbacks::new().on_output(|_, _, _: &mut Linear| {
            count += 1;
            if count == 5 {
                Control::Stop
            } else {
                Control::Continue
            }
        });
        let sol = integrate_second_order(
            &mut Linear::undamped(),
            method,
            (0.0, 10.0),
            &Linear::q0(),
            &Linear::qd0(),
            &opts,
            &mut hooks,
        )
        .unwrap();
        assert_eq!(sol.status, Status::Stopped);
        assert_eq!(sol.t_final, 1.0);
        assert_eq!(sol.t.len(), 5);
        assert_eq!(sol.y_final, reference.y[4]);
    }
}

/// `Solution::h_next` lets a run be continued where it ended without
/// ramping the step up again (issue 29's control periods): twenty periods
/// of 0.05 s, each a new run from the last one's end, started with the
/// carried `h_next` take fewer steps than the same periods each started
/// from the small first step `1e-4`, and both stay within the tolerance of
/// the exact solution at every period's end.
#[test]
fn a_continuation_starts_with_the_carried_step() {
    let sys = Linear::damped();
    for method in [
        Integrator::Esdirk,
        Integrator::Radau5,
        Integrator::Rosenbrock,
        Integrator::Dopri5,
    ] {
        let mut steps = [0usize; 2];
        for (k, warm) in [false, true].into_iter().enumerate() {
            let (mut q, mut qd) = (Linear::q0(), Linear::qd0());
            let mut h: f64 = 1e-4;
            let mut worst: f64 = 0.0;
            for i in 0..20 {
                let (t0, t1) = (0.05 * i as f64, 0.05 * (i + 1) as f64);
                let opts = Options {
                    step: softrod_integrate::StepControl::Adaptive {
                        h0: Some(if warm { h.min(t1 - t0) } else { 1e-4 }),
                    },
                    ..Options::tol(1e-6, 1e-8)
                };
                let sol = integrate_second_order(
                    &mut sys.clone(),
                    method,
                    (t0, t1),
                    &q,
                    &qd,
                    &opts,
                    &mut NoHooks,
                )
                .unwrap();
                assert!(sol.h_next > 0.0 && sol.h_next.is_finite(), "{method:?}");
                h = sol.h_next;
                steps[k] += sol.stats.steps;
                let n = q.len();
                q.copy_from(&sol.y_final.rows(0, n));
                qd.copy_from(&sol.y_final.rows(n, n));
                let exact = sys.exact(t1, &Linear::y0());
                worst = worst.max(dist(&sol.y_final, &exact));
            }
            assert!(worst < 1e-4, "{method:?} warm {warm}: error {worst:.2e}");
        }
        println!("{method:?}: {} steps cold, {} warm", steps[0], steps[1]);
        assert!(steps[1] < steps[0], "{method:?}: {steps:?}");
    }
}

/// `q̈ = −q + f`, the constant force `f` set by a step hook.
struct Pushed {
    f: f64,
}

impl SecondOrderSystem for Pushed {
    type Error = Infallible;
    fn dim(&self) -> usize {
        1
    }
    fn accel(
        &mut self,
        _t: f64,
        q: &DVector<f64>,
        _qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), Infallible> {
        qdd[0] = -q[0] + self.f;
        Ok(())
    }
}

/// At the first step with `t ≥ 1` it pushes with `f = 1` and says only the
/// forces changed (the Jacobian is the same).
struct Push {
    t_switch: f64,
}

impl Hooks<Pushed> for Push {
    fn step(&mut self, info: &StepInfo<'_>, s: &mut Pushed) -> Control {
        if info.t >= 1.0 && self.t_switch.is_nan() {
            self.t_switch = info.t;
            s.f = 1.0;
            Control::ForcesChanged
        } else {
            Control::Continue
        }
    }
}

#[test]
fn a_hook_changing_only_the_forces_restarts_from_the_new_acceleration() {
    // q̈ = −q from (1, 0) until t_s, then q̈ = −q + 1: exactly
    // q = 1 + (cos t_s − 1) cos(t − t_s) − sin t_s sin(t − t_s) after it.
    // Every method must start the next step from the new acceleration
    // (ESDIRK's step-start acceleration is carried from the last stage).
    for method in [Integrator::Esdirk, Integrator::Radau5, Integrator::Dopri5] {
        let mut hooks = Push { t_switch: f64::NAN };
        let sol = integrate_second_order(
            &mut Pushed { f: 0.0 },
            method,
            (0.0, 3.0),
            &dv(&[1.0]),
            &dv(&[0.0]),
            &opts_for(method, 0.01, 1e-9),
            &mut hooks,
        )
        .unwrap();
        let ts = hooks.t_switch;
        assert!((1.0..1.5).contains(&ts), "{method:?}: switched at {ts}");
        let u = 3.0 - ts;
        let q = 1.0 + (ts.cos() - 1.0) * u.cos() - ts.sin() * u.sin();
        let v = -(ts.cos() - 1.0) * u.sin() - ts.sin() * u.cos();
        let (eq, ev) = (sol.y_final[0] - q, sol.y_final[1] - v);
        assert!(
            eq.abs() < 1e-6 && ev.abs() < 1e-6,
            "{method:?}: errors {eq:e}, {ev:e}"
        );
    }
}
