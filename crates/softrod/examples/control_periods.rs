//! The integrator's cost per control period of a learning loop (issue 29):
//! the two-cable reach arm of `softrod/Reach-v0`
//! (crates/softrod-py/python/softrod/envs/scenes/reach_arm.toml, the scene's
//! recommended settings) stepped in periods of 0.05 s (20 Hz) under random
//! tensions in [0, 3] N held over each period, episodes of 100 periods from
//! the scene's initial state — once with every period started cold (first
//! step `dt`, what `Simulation.step` does), once carrying the step size from
//! one period to the next (`Solution::h_next`), once with the integrator's
//! own estimate of the first step (`h0: None`).
//! Prints periods per second (best of `--repeat`), the work per period, and
//! the largest tip distance at the period ends from the same loop at
//! rtol 1e-9 (the accuracy both keep).
//!
//! `cargo run --release -p softrod --example control_periods -- [--periods 2000] [--repeat 3]`

use std::time::Instant;

use softrod::integrate::{NoHooks, RodSystem, Stats, StepControl, integrate_second_order};
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

/// How a period's first step is chosen.
#[derive(Clone, Copy, PartialEq)]
enum Start {
    /// The settings' `dt`.
    Cold,
    /// The step proposed at the end of the previous period.
    Warm,
    /// The integrator's own estimate from the derivatives at the start
    /// (Hairer–Nørsett–Wanner's starting-step algorithm).
    Estimated,
}

/// Runs the loop; returns the wall time, the summed stats and the tip
/// positions at the period ends.
fn run_loop(
    sim: &Simulation,
    settings: &Settings,
    periods: usize,
    start: Start,
) -> (f64, Stats, Vec<[f64; 3]>) {
    let mut sys = RodSystem::new(sim.model().clone());
    sys.jacobian = settings.stiff_jacobian();
    let (method, base) = settings.method_and_options(PERIOD).expect("settings");
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
        .expect("a period");
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
    (wall, stats, tips)
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
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../softrod-py/python/softrod/envs/scenes/reach_arm.toml"
    );
    let (sim, _, _) = Simulation::from_scene_file(path).expect("the reach scene");
    let settings = sim.settings().clone();
    let tight = settings.clone().with_rtol(1e-9);
    let (_, _, reference) = run_loop(&sim, &tight, periods, Start::Cold);
    println!(
        "reach arm, {periods} periods of {PERIOD} s, {} rtol {:e} atol {:e}",
        settings.integrator.name(),
        settings.rtol,
        settings.atol
    );
    println!(
        "| start of a period | periods/s | steps | rejected | Newton | Jacobians | factorizations | rhs | max tip error m |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for start in [Start::Cold, Start::Warm, Start::Estimated] {
        let mut best = f64::INFINITY;
        let mut last = None;
        for _ in 0..repeat.max(1) {
            let (wall, stats, tips) = run_loop(&sim, &settings, periods, start);
            best = best.min(wall);
            last = Some((stats, tips));
        }
        let (s, tips) = last.expect("one repeat");
        let err = tips
            .iter()
            .zip(&reference)
            .map(|(a, b)| {
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max);
        let per = |x: usize| x as f64 / periods as f64;
        println!(
            "| {} | {:.0} | {:.2} | {:.2} | {:.1} | {:.2} | {:.2} | {:.1} | {err:.2e} |",
            match start {
                Start::Cold => "cold (first step dt)",
                Start::Warm => "warm (carried h)",
                Start::Estimated => "estimated first step",
            },
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
