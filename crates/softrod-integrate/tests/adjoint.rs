//! The discrete adjoint of ESDIRK (ESDIRK4(3) and ESDIRK5(4),
//! docs/theory-control.md G27) and of Radau IIA (G25) against central differences of whole runs
//! of the same discrete map (fixed steps, stage equations solved to
//! round-off), on a nonlinear damped, forced two-coordinate system with
//! analytic Jacobians.

use nalgebra::{DMatrix, DVector};
use softrod_integrate::{
    Control, Hooks, Integrator, Iteration, Options, ParameterSystem, SecondOrderSystem, StepInfo,
    Tape, adjoint_second_order, forward_sensitivity_second_order, integrate_second_order,
};

/// q̈₀ = −k sin q₀ − c q̇₀ + f sin 3t + 0.3 q₁²,
/// q̈₁ = −4k q₁ − c q̇₁ (1 + q₀²) − 0.5 q̇₀ q₁;  p = (k, c, f).
struct Forced {
    p: [f64; 3],
}

impl SecondOrderSystem for Forced {
    type Error = std::convert::Infallible;
    fn dim(&self) -> usize {
        2
    }
    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        a: &mut DVector<f64>,
    ) -> Result<(), Self::Error> {
        let [k, c, f] = self.p;
        a[0] = -k * q[0].sin() - c * v[0] + f * (3.0 * t).sin() + 0.3 * q[1] * q[1];
        a[1] = -4.0 * k * q[1] - c * v[1] * (1.0 + q[0] * q[0]) - 0.5 * v[0] * q[1];
        Ok(())
    }
    fn jacobians(
        &mut self,
        _t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        jq: &mut DMatrix<f64>,
        jv: &mut DMatrix<f64>,
    ) -> Result<(), Self::Error> {
        let [k, c, _] = self.p;
        jq[(0, 0)] = -k * q[0].cos();
        jq[(0, 1)] = 0.6 * q[1];
        jq[(1, 0)] = -2.0 * c * v[1] * q[0];
        jq[(1, 1)] = -4.0 * k - 0.5 * v[0];
        jv[(0, 0)] = -c;
        jv[(0, 1)] = 0.0;
        jv[(1, 0)] = -0.5 * q[1];
        jv[(1, 1)] = -c * (1.0 + q[0] * q[0]);
        Ok(())
    }
}

impl ParameterSystem for Forced {
    fn n_params(&self) -> usize {
        3
    }
    fn accel_param_vjp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        _a: &DVector<f64>,
        w: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), Self::Error> {
        out[0] += w[0] * (-q[0].sin()) + w[1] * (-4.0 * q[1]);
        out[1] += w[0] * (-v[0]) + w[1] * (-v[1] * (1.0 + q[0] * q[0]));
        out[2] += w[0] * (3.0 * t).sin();
        Ok(())
    }
}

struct Record(Tape);
impl Hooks<Forced> for Record {
    fn keep_outputs(&self) -> bool {
        false
    }
    fn step(&mut self, info: &StepInfo<'_>, _sys: &mut Forced) -> Control {
        let (q, v) = info.y.as_slice().split_at(2);
        self.0.push(info.t, info.h, q, v);
        Control::Continue
    }
}

fn options() -> Options {
    // Fixed steps (one step sequence for every run) and the stage equations
    // solved far below the differences' step.
    let mut o = Options::fixed(0.05);
    o.rtol = 1e-10;
    o.atol = 1e-10;
    o.iteration = Iteration::Newton {
        tol: 1e-4,
        max_iter: 40,
    };
    o
}

const T1: f64 = 1.5;

/// The loss: Σ over the nodes of q₀² + 0.5 q̇₁² (every step end).
fn run(p: [f64; 3], q0: [f64; 2], v0: [f64; 2]) -> (f64, Tape) {
    run_with(Integrator::Esdirk, p, q0, v0)
}

/// [`run`] with `integrator`.
fn run_with(integrator: Integrator, p: [f64; 3], q0: [f64; 2], v0: [f64; 2]) -> (f64, Tape) {
    let mut sys = Forced { p };
    let (q0, v0) = (DVector::from_row_slice(&q0), DVector::from_row_slice(&v0));
    let mut rec = Record(Tape::new(0.0, q0.as_slice(), v0.as_slice()));
    integrate_second_order(
        &mut sys,
        integrator,
        (0.0, T1),
        &q0,
        &v0,
        &options(),
        &mut rec,
    )
    .unwrap();
    let tape = rec.0;
    let loss = (0..tape.nodes())
        .map(|k| tape.q(k)[0].powi(2) + 0.5 * tape.qd(k)[1].powi(2))
        .sum();
    (loss, tape)
}

#[test]
fn esdirk_adjoint_matches_central_differences_of_whole_runs() {
    adjoint_matches_differences(Integrator::Esdirk);
}

#[test]
fn esdirk5_adjoint_matches_central_differences_of_whole_runs() {
    adjoint_matches_differences(Integrator::Esdirk5);
}

/// Radau IIA's adjoint (G25): the transposed collocation system at the
/// recomputed stages, against differences of whole radau5 runs.
#[test]
fn radau5_adjoint_matches_central_differences_of_whole_runs() {
    adjoint_matches_differences(Integrator::Radau5);
}

/// Radau IIA's forward sensitivities (G26) give its adjoint's numbers:
/// one factorization of the collocation matrix, solved with it and with
/// its transpose, on every entry.
#[test]
fn radau5_forward_sensitivities_equal_the_adjoint() {
    forward_equals_adjoint(Integrator::Radau5);
}

/// ESDIRK5(4)'s forward sensitivities (G21 on its tableau) give its
/// adjoint's numbers: two algorithms, one discrete map.
#[test]
fn esdirk5_forward_sensitivities_equal_the_adjoint() {
    forward_equals_adjoint(Integrator::Esdirk5);
}

fn forward_equals_adjoint(integrator: Integrator) {
    let (p, q0, v0) = ([3.0, 0.4, 0.7], [0.5, -0.3], [0.2, 0.1]);
    let (_, tape) = run_with(integrator, p, q0, v0);
    let mut seed = |k: usize, lq: &mut DVector<f64>, lv: &mut DVector<f64>| {
        lq[0] += 2.0 * tape.q(k)[0];
        lv[1] += tape.qd(k)[1];
    };
    let mut sys = Forced { p };
    let a = adjoint_second_order(&mut sys, integrator, &tape, &mut seed).unwrap();
    let f = forward_sensitivity_second_order(&mut sys, integrator, &tape, &mut seed, true).unwrap();
    let all = |g: &softrod_integrate::AdjointGradient| {
        let mut v = g.dp.clone();
        v.extend(g.dq0.iter().chain(g.dqd0.iter()));
        v
    };
    for (k, (x, y)) in all(&a).iter().zip(all(&f)).enumerate() {
        let rel = (x - y).abs() / x.abs().max(1e-3);
        eprintln!("[{k}]: adjoint {x:e}, forward {y:e}, {rel:e}");
        assert!(rel < 1e-10, "[{k}]: adjoint {x:e}, forward {y:e}, {rel:e}");
    }
}

fn adjoint_matches_differences(integrator: Integrator) {
    let p = [3.0, 0.4, 0.7];
    let q0 = [0.5, -0.3];
    let v0 = [0.2, 0.1];
    let run = |p, q0, v0| run_with(integrator, p, q0, v0);
    let (_, tape) = run(p, q0, v0);
    assert_eq!(tape.steps(), 30);
    let mut sys = Forced { p };
    let g = adjoint_second_order(&mut sys, integrator, &tape, &mut |k, lq, lv| {
        lq[0] += 2.0 * tape.q(k)[0];
        lv[1] += tape.qd(k)[1];
    })
    .unwrap();
    let d = 1e-6;
    let check = |name: &str, exact: f64, plus: f64, minus: f64| {
        let fd = (plus - minus) / (2.0 * d);
        let rel = (exact - fd).abs() / fd.abs().max(1e-3);
        eprintln!("{name}: adjoint {exact:e}, differences {fd:e}, rel {rel:e}");
        assert!(
            rel < 1e-6,
            "{name}: adjoint {exact}, differences {fd}, rel {rel:e}"
        );
    };
    for j in 0..3 {
        let (mut a, mut b) = (p, p);
        a[j] += d;
        b[j] -= d;
        check(
            &format!("p{j}"),
            g.dp[j],
            run(a, q0, v0).0,
            run(b, q0, v0).0,
        );
    }
    for j in 0..2 {
        let (mut a, mut b) = (q0, q0);
        a[j] += d;
        b[j] -= d;
        check(
            &format!("q0[{j}]"),
            g.dq0[j],
            run(p, a, v0).0,
            run(p, b, v0).0,
        );
        let (mut a, mut b) = (v0, v0);
        a[j] += d;
        b[j] -= d;
        check(
            &format!("qd0[{j}]"),
            g.dqd0[j],
            run(p, q0, a).0,
            run(p, q0, b).0,
        );
    }
}

#[test]
fn other_integrators_are_refused_by_name() {
    let (_, tape) = run([1.0, 0.1, 0.0], [0.1, 0.0], [0.0, 0.0]);
    let mut sys = Forced { p: [1.0, 0.1, 0.0] };
    let e = adjoint_second_order(&mut sys, Integrator::Rosenbrock, &tape, &mut |_, _, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("rosenbrock") && e.contains("(supported: esdirk, esdirk5, radau5)"),
        "{e}"
    );
}

/// An adaptive radau5 run's adjoint is the gradient of its own discrete
/// map: the recorded steps replayed one by one (each a fixed step of the
/// recorded size, the stage equations solved far below the differences'
/// step) with the parameters moved give central differences that agree
/// with it to the differences' truncation and round-off.
#[test]
fn radau5_adaptive_adjoint_matches_differences_of_its_recorded_steps() {
    let (p, q0, v0) = ([3.0, 0.4, 0.7], [0.5, -0.3], [0.2, 0.1]);
    let mut opts = Options::tol(1e-6, 1e-8);
    opts.iteration = Iteration::Newton {
        tol: 1e-5,
        max_iter: 40,
    };
    let mut sys = Forced { p };
    let (q, v) = (DVector::from_row_slice(&q0), DVector::from_row_slice(&v0));
    let mut rec = Record(Tape::new(0.0, &q0, &v0));
    integrate_second_order(
        &mut sys,
        Integrator::Radau5,
        (0.0, T1),
        &q,
        &v,
        &opts,
        &mut rec,
    )
    .unwrap();
    let tape = rec.0;
    // Steps of several sizes: not a fixed-step run in disguise.
    let (hmin, hmax) = (0..tape.steps()).fold((f64::INFINITY, 0.0f64), |(a, b), k| {
        (a.min(tape.step_size(k)), b.max(tape.step_size(k)))
    });
    assert!(hmax > 2.0 * hmin, "steps {hmin:e}..{hmax:e}");
    let loss_at = |q: &[f64], v: &[f64]| q[0].powi(2) + 0.5 * v[1].powi(2);
    let replay = |p: [f64; 3], q0: [f64; 2], v0: [f64; 2]| {
        let mut sys = Forced { p };
        let (mut q, mut v) = (DVector::from_row_slice(&q0), DVector::from_row_slice(&v0));
        let mut loss = loss_at(q.as_slice(), v.as_slice());
        for k in 0..tape.steps() {
            let mut o = Options::fixed(tape.step_size(k));
            o.rtol = opts.rtol;
            o.atol = opts.atol;
            o.iteration = Iteration::Newton {
                tol: 1e-8,
                max_iter: 40,
            };
            let mut one = Record(Tape::new(tape.time(k), q.as_slice(), v.as_slice()));
            let span = (tape.time(k), tape.time(k + 1));
            integrate_second_order(&mut sys, Integrator::Radau5, span, &q, &v, &o, &mut one)
                .unwrap();
            assert_eq!(one.0.steps(), 1, "step {k} replayed in one step");
            q.copy_from_slice(one.0.q(1));
            v.copy_from_slice(one.0.qd(1));
            loss += loss_at(q.as_slice(), v.as_slice());
        }
        loss
    };
    let g = adjoint_second_order(
        &mut Forced { p },
        Integrator::Radau5,
        &tape,
        &mut |k, lq, lv| {
            lq[0] += 2.0 * tape.q(k)[0];
            lv[1] += tape.qd(k)[1];
        },
    )
    .unwrap();
    let d = 1e-6;
    let check = |name: &str, exact: f64, plus: f64, minus: f64| {
        let fd = (plus - minus) / (2.0 * d);
        let rel = (exact - fd).abs() / fd.abs().max(1e-3);
        eprintln!("{name}: adjoint {exact:e}, differences {fd:e}, rel {rel:e}");
        assert!(
            rel < 1e-6,
            "{name}: adjoint {exact}, differences {fd}, rel {rel:e}"
        );
    };
    for j in 0..3 {
        let (mut a, mut b) = (p, p);
        a[j] += d;
        b[j] -= d;
        check(
            &format!("p{j}"),
            g.dp[j],
            replay(a, q0, v0),
            replay(b, q0, v0),
        );
    }
    for j in 0..2 {
        let (mut a, mut b) = (q0, q0);
        a[j] += d;
        b[j] -= d;
        check(
            &format!("q0[{j}]"),
            g.dq0[j],
            replay(p, a, v0),
            replay(p, b, v0),
        );
        let (mut a, mut b) = (v0, v0);
        a[j] += d;
        b[j] -= d;
        check(
            &format!("qd0[{j}]"),
            g.dqd0[j],
            replay(p, q0, a),
            replay(p, q0, b),
        );
    }
}
