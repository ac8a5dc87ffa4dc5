//! The integrator's cost per control period of a learning loop (issue 29):
//! the two-cable reach arm of `softrod/Reach-v0`
//! (crates/softrod-py/python/softrod/envs/scenes/reach_arm.toml, the scene's
//! recommended settings) stepped in periods of 0.05 s (20 Hz) under random
//! tensions in [0, 3] N held over each period, episodes of 100 periods from
//! the scene's initial state — once with every period started cold (first
//! step `dt`, what `Simulation.step` does), once carrying the step size from
//! one period to the next (`Solution::h_next`), once with the integrator's
//! own estimate of the first step (`h0: None`); then with a fixed number
//! `k` of steps of an L-stable implicit method per period (ESDIRK, Radau
//! IIA, Rosenbrock–W: `Simulation.step(..., substeps=k)`, the envs'
//! `substeps`), the scene's rtol and atol then only weighting the Newton
//! test.
//! Prints periods per second (best of `--repeat`), the work per period, and
//! the largest and the mean tip distance at the period ends from the same
//! loop (same tensions) at ESDIRK rtol 1e-9 (the accuracy each keeps).
//!
//! `cargo run --release -p softrod --example control_periods -- [--periods 2000] [--repeat 3] [--only TEXT]`
//! (`--only`: the rows whose label contains `TEXT`, e.g. `rtol 1e-2`)

use std::time::Instant;

use softrod::integrate::{
    Integrator, NoHooks, RodJacobian, RodSystem, Stats, StepControl, integrate_second_order,
};
use softrod::prelude::*;

const PERIOD: f64 = 0.05;
const EPISODE: usize = 100;
const MAX_TENSION: f64 = 3.0;

/// Uniform numbers in [0, 1) (a fixed LCG: the same actions every run).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// How a period is integrated: adaptive steps and how the period's first
/// step is chosen, or a fixed number of steps.
#[derive(Clone, Copy, PartialEq)]
enum Start {
    /// The settings' `dt`.
    Cold,
    /// The step proposed at the end of the previous period.
    Warm,
    /// The integrator's own estimate from the derivatives at the start
    /// (Hairer–Nørsett–Wanner's starting-step algorithm).
    Estimated,
    /// `k` fixed steps of the method per period.
    Fixed(Integrator, usize),
    /// `k` fixed steps of the method per period with the exact Jacobian
    /// evaluated at every step (Rosenbrock–W as a true Rosenbrock method).
    FixedExact(Integrator, usize),
    /// Adaptive steps of the method at this rtol (cold start).
    Adaptive(Integrator, f64),
    /// `k` fixed steps of linearly implicit generalized-α (one evaluation
    /// and one solve per step, the IMEX scheme).
    Imex(usize),
}

/// Runs the loop; returns the wall time, the summed stats and the tip
/// positions at the period ends, or the first failure.
fn run_loop(
    sim: &Simulation,
    settings: &Settings,
    periods: usize,
    start: Start,
) -> Result<(f64, Stats, Vec<[f64; 3]>), String> {
    let settings = match start {
        Start::Fixed(method, _) | Start::FixedExact(method, _) => {
            settings.clone().with_integrator(method)
        }
        Start::Adaptive(method, rtol) => settings.clone().with_integrator(method).with_rtol(rtol),
        Start::Imex(k) => Settings {
            linearly_implicit: true,
            dt: PERIOD / k as f64,
            ..settings
                .clone()
                .with_integrator(Integrator::GeneralizedAlpha)
        },
        _ => settings.clone(),
    };
    let mut sys = RodSystem::new(sim.model().clone());
    sys.jacobian = settings.stiff_jacobian();
    let (method, mut base) = settings.method_and_options(PERIOD).expect("settings");
    if let Start::Fixed(_, k) | Start::FixedExact(_, k) = start {
        base.step = StepControl::Fixed(PERIOD / k as f64);
        base.max_steps = 2 * k + 100;
    }
    if let Start::FixedExact(..) = start {
        sys.jacobian = RodJacobian::Exact;
        base.jacobian_max_age = 1;
    }
    let (q0, qd0) = sim.initial_state();
    let (mut q, mut qd) = (q0.clone(), qd0.clone());
    let mut h: f64 = 0.0;
    let mut rng = Lcg(7);
    let mut stats = Stats::default();
    let mut ends = Vec::with_capacity(periods);
    let mut t = 0.0;
    let clock = Instant::now();
    for k in 0..periods {
        if k % EPISODE == 0 {
            q.copy_from(q0);
            qd.copy_from(qd0);
            t = 0.0;
            h = 0.0;
        }
        let u = [MAX_TENSION * rng.next(), MAX_TENSION * rng.next()];
        sys.data
            .set_cable_tensions(&sys.model, Some(&u))
            .expect("tensions");
        let mut opts = base.clone();
        opts.t_eval = Some(Vec::new());
        match start {
            Start::Cold => {}
            Start::Warm if h > 0.0 => {
                opts.step = StepControl::Adaptive {
                    h0: Some(h.min(PERIOD)),
                };
            }
            Start::Warm => {}
            Start::Estimated => opts.step = StepControl::Adaptive { h0: None },
            Start::Fixed(..) | Start::FixedExact(..) | Start::Adaptive(..) | Start::Imex(_) => {}
        }
        let sol = integrate_second_order(
            &mut sys,
            method,
            (t, t + PERIOD),
            &q,
            &qd,
            &opts,
            &mut NoHooks,
        )
        .map_err(|e| format!("period {k}: {e}"))?;
        let n = q.len();
        q.copy_from(&sol.y_final.rows(0, n));
        qd.copy_from(&sol.y_final.rows(n, n));
        h = sol.h_next;
        t += PERIOD;
        let s = sol.stats;
        stats.steps += s.steps;
        stats.rejected_steps += s.rejected_steps;
        stats.rhs_evaluations += s.rhs_evaluations;
        stats.jacobian_evaluations += s.jacobian_evaluations;
        stats.factorizations += s.factorizations;
        stats.newton_iterations += s.newton_iterations;
        ends.push(q.as_slice().to_vec());
    }
    let wall = clock.elapsed().as_secs_f64();
    let tips = ends
        .iter()
        .map(|q| {
            let p = sim.tip_pose(0, q).expect("tip").translation;
            [p[0], p[1], p[2]]
        })
        .collect();
    Ok((wall, stats, tips))
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |key: &str, default: usize| {
        args.iter()
            .position(|a| a == key)
            .and_then(|i| args.get(i + 1))
            .map_or(default, |v| v.parse().expect("a number"))
    };
    let periods = value("--periods", 2000);
    let repeat = value("--repeat", 3);
    // `--only TEXT`: only the rows whose label contains TEXT.
    let only = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1))
        .cloned();
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../softrod-py/python/softrod/envs/scenes/reach_arm.toml"
    );
    let (sim, _, _) = Simulation::from_scene_file(path).expect("the reach scene");
    let settings = sim.settings().clone();
    let tight = Settings {
        rtol: 1e-9,
        atol: 1e-12,
        ..settings.clone()
    };
    // `--no-reference`: skip the tight run (for profiling; errors print NaN).
    let reference = if args.iter().any(|a| a == "--no-reference") {
        vec![[f64::NAN; 3]; periods]
    } else {
        run_loop(&sim, &tight, periods, Start::Cold)
            .expect("the reference")
            .2
    };
    println!(
        "reach arm, {periods} periods of {PERIOD} s, {} rtol {:e} atol {:e}",
        settings.integrator.name(),
        settings.rtol,
        settings.atol
    );
    println!(
        "| a period | periods/s | steps | rejected | Newton | Jacobians | factorizations | rhs | max tip error m | mean tip error m |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut modes = vec![Start::Cold, Start::Warm, Start::Estimated];
    for k in [1, 2, 4] {
        modes.push(Start::Fixed(Integrator::Esdirk, k));
    }
    for k in [1, 2] {
        modes.push(Start::Fixed(Integrator::Radau5, k));
    }
    for k in [1, 2, 4, 8] {
        modes.push(Start::Fixed(Integrator::Rosenbrock, k));
    }
    for k in [1, 2, 4] {
        modes.push(Start::FixedExact(Integrator::Rosenbrock, k));
    }
    for k in [2, 5] {
        modes.push(Start::Fixed(Integrator::GeneralizedAlpha, k));
    }
    for k in [5, 10, 20] {
        modes.push(Start::Imex(k));
    }
    modes.push(Start::Adaptive(Integrator::Esdirk, 1e-2));
    modes.push(Start::Adaptive(Integrator::Esdirk, 3e-2));
    modes.push(Start::Adaptive(Integrator::Esdirk, 1e-1));
    for rtol in [3e-2, 1e-1, 3e-1] {
        modes.push(Start::Adaptive(Integrator::Esdirk5, rtol));
    }
    modes.push(Start::Adaptive(Integrator::Radau5, 1e-3));
    modes.push(Start::Adaptive(Integrator::Radau5, 1e-2));
    modes.push(Start::Adaptive(Integrator::Rosenbrock, 1e-3));
    for start in modes {
        let label = match start {
            Start::Cold => "adaptive, cold (first step dt)".to_string(),
            Start::Warm => "adaptive, warm (carried h)".to_string(),
            Start::Estimated => "adaptive, estimated first step".to_string(),
            Start::FixedExact(m, k) => format!(
                "{k} fixed {} step{}, exact Jacobian each",
                m.name(),
                if k > 1 { "s" } else { "" }
            ),
            Start::Adaptive(m, rtol) => format!("adaptive {}, rtol {rtol:e}", m.name()),
            Start::Imex(k) => format!("{k} fixed linearly implicit generalized-alpha steps"),
            Start::Fixed(m, k) => format!(
                "{k} fixed {} step{}",
                m.name(),
                if k > 1 { "s" } else { "" }
            ),
        };
        if only.as_ref().is_some_and(|o| !label.contains(o.as_str())) {
            continue;
        }
        let mut best = f64::INFINITY;
        let mut last = None;
        let mut failed = None;
        for _ in 0..repeat.max(1) {
            match run_loop(&sim, &settings, periods, start) {
                Ok((wall, stats, tips)) => {
                    best = best.min(wall);
                    last = Some((stats, tips));
                }
                Err(e) => {
                    failed = Some(e);
                    break;
                }
            }
        }
        if let Some(e) = failed {
            println!("| {label} | failed: {e} |");
            continue;
        }
        let (s, tips) = last.expect("one repeat");
        let errs: Vec<f64> = tips
            .iter()
            .zip(&reference)
            .map(|(a, b)| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .collect();
        let err = errs.iter().copied().fold(0.0, f64::max);
        let mean = errs.iter().sum::<f64>() / errs.len() as f64;
        let per = |x: usize| x as f64 / periods as f64;
        println!(
            "| {} | {:.0} | {:.2} | {:.2} | {:.1} | {:.2} | {:.2} | {:.1} | {err:.2e} | {mean:.2e} |",
            label,
            periods as f64 / best,
            per(s.steps),
            per(s.rejected_steps),
            per(s.newton_iterations),
            per(s.jacobian_evaluations),
            per(s.factorizations),
            per(s.rhs_evaluations),
        );
    }
}
