//! Work per accuracy of the integrators (issue 30): for each method and
//! tolerance, the integration alone (no output files, no energy watch, 51
//! samples) on the planar release (examples/cantilever_gravity.toml, 1 s),
//! the 3-D 32-piece all-strain release (0.3 s) and the steel wire
//! (examples/steel_wire.toml, 0.5 s). Prints one CSV row per run: wall time
//! (best of `--repeat`), the work counters (steps, rejected steps, Newton
//! iterations, Jacobian evaluations, factorizations, linear solves,
//! right-hand sides) and the largest tip distance over the samples from a
//! Radau IIA reference at rtol 1e-10 of the same model.
//!
//! `cargo run --release -p softrod --example work_precision -- [--repeat 3] [--scene planar,3d,steel] [--method esdirk,...] [--rtol 1e-2,...] [--cache DIR]`
//!
//! scripts/work_precision.py turns the CSV into docs/performance.md's table
//! and the work-precision diagrams.

use std::time::Instant;

use softrod::prelude::*;
use softrod::{Flow, Observer, Sample};

/// The coordinates at the samples (tips computed after the timed run).
struct Samples(Vec<Vec<f64>>);

impl Observer for Samples {
    fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
        self.0.push(s.q.to_vec());
        Ok(Flow::Continue)
    }
}

const RELEASE_3D: &str = r#"
[world]
gravity = [0.0, 0.0, -9.81]

[[rod]]
name = "arm"
length = 0.5
pieces = 32
strains = "all"
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }
"#;

fn scene(name: &str) -> (String, f64) {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/");
    let read = |f: &str| std::fs::read_to_string(format!("{root}{f}")).expect("example scene");
    match name {
        "planar" => (read("cantilever_gravity.toml"), 1.0),
        "3d" => (RELEASE_3D.to_string(), 0.3),
        "steel" => (read("steel_wire.toml"), 0.5),
        _ => panic!("unknown scene {name}"),
    }
}

/// One run: wall time, stats, tips.
fn run(
    text: &str,
    duration: f64,
    settings: &Settings,
    repeat: usize,
) -> Result<(f64, softrod::integrate::Stats, Vec<[f64; 3]>), softrod::Error> {
    let (mut sim, _, _) = Simulation::from_toml(text, "scene")?;
    let mut s = settings.clone();
    s.output_every = Some(duration / 50.0);
    s.energy_tolerance = f64::INFINITY;
    sim.set_settings(s)?;
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeat.max(1) {
        let mut samples = Samples(Vec::new());
        let start = Instant::now();
        let summary = sim.simulate_with(duration, &mut samples)?;
        best = best.min(start.elapsed().as_secs_f64());
        out = Some((summary.stats, samples.0));
    }
    let (stats, qs) = out.expect("one repeat");
    let mut tip = Vec::with_capacity(qs.len());
    for q in &qs {
        let p = sim.tip_pose(0, q)?.translation;
        tip.push([p[0], p[1], p[2]]);
    }
    Ok((best, stats, tip))
}

fn distance(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    a.iter()
        .zip(b)
        .map(|(p, r)| {
            ((p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2) + (p[2] - r[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |key: &str| {
        args.iter()
            .position(|a| a == key)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let repeat: usize = value("--repeat").map_or(3, |v| v.parse().expect("--repeat N"));
    let scenes = value("--scene").unwrap_or_else(|| "planar,3d,steel".into());
    let methods = value("--method")
        .unwrap_or_else(|| "esdirk,esdirk5,radau5,rosenbrock,generalized-alpha".into());
    let rtols: Vec<f64> = value("--rtol").map_or_else(
        || vec![1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7],
        |v| {
            v.split(',')
                .map(|r| r.parse().expect("--rtol R,R,..."))
                .collect()
        },
    );
    println!(
        "scene,method,setting,wall_s,steps,rejected,newton,jacobians,factorizations,lu_solves,rhs,error_m,status"
    );
    for name in scenes.split(',') {
        let (text, duration) = scene(name);
        let reference = Settings::tolerances(1e-10, 1e-12).with_integrator(Integrator::Radau5);
        // `--cache DIR`: the reference tips of earlier runs, kept in DIR.
        let cached = value("--cache").map(|d| format!("{d}/reference_{name}.txt"));
        let read = cached
            .as_ref()
            .and_then(|f| std::fs::read_to_string(f).ok());
        let ref_tip: Vec<[f64; 3]> = match read {
            Some(text) => text
                .lines()
                .map(|l| {
                    let v: Vec<f64> = l
                        .split(' ')
                        .map(|x| x.parse().expect("cached tip"))
                        .collect();
                    [v[0], v[1], v[2]]
                })
                .collect(),
            None => {
                let (_, _, tip) = run(&text, duration, &reference, 1).expect("reference run");
                if let Some(f) = &cached {
                    let lines: Vec<String> = tip
                        .iter()
                        .map(|p| format!("{:e} {:e} {:e}", p[0], p[1], p[2]))
                        .collect();
                    std::fs::write(f, lines.join("\n")).expect("writing the reference cache");
                }
                tip
            }
        };
        for method in methods.split(',') {
            let integrator = Integrator::ALL
                .into_iter()
                .find(|i| i.name() == method)
                .expect("a method name");
            let settings: Vec<(String, Settings)> = if integrator.is_adaptive() {
                rtols
                    .iter()
                    .copied()
                    .map(|r| {
                        (
                            format!("rtol {r:e}"),
                            Settings::default().with_rtol(r).with_integrator(integrator),
                        )
                    })
                    .collect()
            } else {
                [1e-3, 5e-4, 2.5e-4, 1.25e-4, 6.25e-5]
                    .into_iter()
                    .map(|dt| {
                        let mut s = Settings::default().with_integrator(integrator);
                        s.dt = dt;
                        (format!("dt {dt:.3e}"), s)
                    })
                    .collect()
            };
            for (label, s) in settings {
                match run(&text, duration, &s, repeat) {
                    Ok((wall, st, tip)) => println!(
                        "{name},{method},{label},{wall:.5},{},{},{},{},{},{},{},{:.3e},ok",
                        st.steps,
                        st.rejected_steps,
                        st.newton_iterations,
                        st.jacobian_evaluations,
                        st.factorizations,
                        st.lu_solves,
                        st.rhs_evaluations,
                        distance(&tip, &ref_tip)
                    ),
                    Err(e) => println!(
                        "{name},{method},{label},,,,,,,,,,\"{}\"",
                        e.to_string().replace('"', "'")
                    ),
                }
            }
        }
    }
}
