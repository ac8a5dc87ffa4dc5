//! What a trajectory gradient costs (docs/performance.md, "Trajectory
//! gradients"): on examples/arm_with_payload.toml (two rods, a joint, two
//! bodies, a cable table; 0.5 s, the scene's adaptive ESDIRK), the time of
//! one plain run, of the recorded forward run alone (`value_and_gradient`
//! with no parameters), of `value_and_gradient` with respect to 7 scalar
//! parameters plus `q0`, `qdot0`, and of the central differences that
//! would give the same 7 parameters (14 forward runs; `q0`, `qdot0` by
//! differences would need `4·n_dof` more). Run with
//!
//! ```sh
//! cargo run --release -p softrod --example gradient_cost [-- PIECES...]
//! ```
//!
//! With `PIECES` (numbers), the same arm with that many pieces in each of
//! its two rods, one line each; without, the scene as shipped (4 each).
//! Each time is the fastest of `reps` calls (3, 1 above 300 coordinates).
//! Errors print their whole chain (`Error::report`) and exit 1.
//!
//! `prescribed`: a soft rod (8 pieces, six strains) with a tip body, turned
//! at its base by a prescribed revolute joint through 11 samples over
//! 0.5 s (the scene's adaptive ESDIRK, a tip tracking loss at `0.05·k`):
//! the gradient by `tip.mass` alone against `tip.mass` and the 11 samples
//! `arm.prescribed` (docs/theory-control.md G17–G20), and the recorded
//! forward run.
//!
//! `planar [RTOL...]`: instead, the planar release of
//! examples/cantilever_gravity.toml (1 s) with the loss of the soromox
//! side by side (crates/softrod-py/bench/gradient_side_by_side.py: the
//! tip against `(0.25, 0, −0.25)` at `0.05·k`, `k = 1…20`) and the
//! parameters `cantilever.young`, `cantilever.density`, at each `RTOL`
//! (`atol = 1e-3·rtol`; default the scene's 1e-3).
//!
//! `--integrator NAME` (anywhere): run both scenes with that integrator
//! instead of the scene's (`radau5`: its discrete adjoint, G25).

use std::process::ExitCode;
use std::time::Instant;

use softrod::{GradientOptions, LossTerm, Simulation};

const SCENE: &str = include_str!("../../../examples/arm_with_payload.toml");
const PLANAR: &str = include_str!("../../../examples/cantilever_gravity.toml");

/// The arguments without `--integrator NAME`, and the integrator named.
fn args() -> Result<(Vec<String>, Option<softrod::Integrator>), String> {
    let mut rest = Vec::new();
    let mut integrator = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        if a == "--integrator" {
            let name = it.next().ok_or("--integrator needs a name")?;
            integrator = Some(name.parse().map_err(|e| format!("{e}"))?);
        } else {
            rest.push(a);
        }
    }
    Ok((rest, integrator))
}

/// `sim` with the integrator of `--integrator`, if any.
fn with_integrator(sim: &mut Simulation) -> softrod::Result<()> {
    if let Ok((_, Some(integrator))) = args() {
        let settings = sim.settings().clone().with_integrator(integrator);
        sim.set_settings(settings)?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let args = match args() {
        Ok((a, _)) => a,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    if args.first().map(String::as_str) == Some("planar") {
        return planar_main(&args[1..]);
    }
    if args.first().map(String::as_str) == Some("prescribed") {
        return match measure_prescribed() {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {}", e.report());
                ExitCode::FAILURE
            }
        };
    }
    let pieces: Vec<usize> = match args
        .iter()
        .map(|a| a.parse::<usize>().map_err(|_| a.clone()))
        .collect()
    {
        Ok(p) => p,
        Err(a) => {
            eprintln!("error: '{a}' is not a number of pieces");
            return ExitCode::from(2);
        }
    };
    println!(
        "| pieces per rod | n_dof | steps | plain run | recorded forward | gradient (7 + q0, qdot0) | gradient / forward | central differences, 7 params | Jacobians / dense LUs |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let sizes: Vec<Option<usize>> = if pieces.is_empty() {
        vec![None]
    } else {
        pieces.into_iter().map(Some).collect()
    };
    for n in sizes {
        if let Err(e) = measure(n) {
            eprintln!("error: {}", e.report());
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}

fn measure(pieces: Option<usize>) -> softrod::Result<()> {
    let text = match pieces {
        Some(n) => SCENE.replace("pieces = 4", &format!("pieces = {n}")),
        None => SCENE.to_string(),
    };
    let (mut sim, _, _) = Simulation::from_toml(&text, "examples/arm_with_payload.toml")?;
    with_integrator(&mut sim)?;
    let duration = 0.5;
    let times: Vec<f64> = (1..=10).map(|k| 0.05 * k as f64).collect();
    let loss = || {
        vec![LossTerm::Position {
            rod: "lower".into(),
            s: None,
            times: times.clone(),
            targets: vec![[0.4, 0.0, -0.1]; times.len()],
            weight: 1.0,
        }]
    };
    let params = [
        "upper.young",
        "upper.viscosity",
        "lower.density",
        "connector.mass",
        "gripper.mass",
        "cable0.tension",
        "q0",
        "qdot0",
    ];
    let options = GradientOptions::default();
    let reps = if sim.n_dof() > 300 { 1 } else { 3 };
    let best = |f: &mut dyn FnMut() -> softrod::Result<()>| -> softrod::Result<f64> {
        let mut fastest = f64::INFINITY;
        for _ in 0..reps {
            let t = Instant::now();
            f()?;
            fastest = fastest.min(t.elapsed().as_secs_f64());
        }
        Ok(fastest)
    };
    let mut s = sim.clone();
    let forward = best(&mut || {
        s.value_and_gradient(&mut loss(), &[], duration, &options)
            .map(|g| drop(std::hint::black_box(g)))
    })?;
    let mut s = sim.clone();
    let plain = best(&mut || s.simulate(duration).map(|r| drop(std::hint::black_box(r))))?;
    let mut steps = 0;
    let mut work = (0, 0);
    let gradient = best(&mut || {
        let g = sim.value_and_gradient(&mut loss(), &params, duration, &options)?;
        steps = g.steps;
        work = (g.jacobian_evaluations, g.dense_factorizations);
        Ok(())
    })?;
    let scalar_params = 7; // five scalars + the two tension values
    let ms = |s: f64| format!("{:.1} ms", 1e3 * s);
    println!(
        "| {} | {} | {steps} | {} | {} | {} | {:.1} | {} | {} / {} |",
        pieces.map_or("4 (as shipped)".to_string(), |n| n.to_string()),
        sim.n_dof(),
        ms(plain),
        ms(forward),
        ms(gradient),
        gradient / forward,
        ms(2.0 * scalar_params as f64 * forward),
        work.0,
        work.1,
    );
    Ok(())
}

fn planar_main(args: &[String]) -> ExitCode {
    let rtols: Vec<f64> = match args
        .iter()
        .map(|a| a.parse::<f64>().map_err(|_| a.clone()))
        .collect::<Result<Vec<f64>, String>>()
    {
        Ok(r) if r.is_empty() => vec![1e-3],
        Ok(r) => r,
        Err(a) => {
            eprintln!("error: '{a}' is not a tolerance");
            return ExitCode::from(2);
        }
    };
    println!(
        "| rtol | n_dof | steps | plain run | recorded forward | gradient (young, density) | gradient / forward | dL/dE | dL/drho | Jacobians / dense LUs |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for rtol in rtols {
        if let Err(e) = measure_planar(rtol) {
            eprintln!("error: {}", e.report());
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}

fn measure_planar(rtol: f64) -> softrod::Result<()> {
    let (mut sim, _, _) = Simulation::from_toml(PLANAR, "examples/cantilever_gravity.toml")?;
    let settings = sim.settings().clone().with_rtol(rtol);
    sim.set_settings(softrod::Settings {
        atol: 1e-3 * rtol,
        ..settings
    })?;
    with_integrator(&mut sim)?;
    let duration = 1.0;
    let times: Vec<f64> = (1..=20).map(|k| 0.05 * k as f64).collect();
    let loss = || {
        vec![LossTerm::Position {
            rod: "cantilever".into(),
            s: None,
            times: times.clone(),
            targets: vec![[0.25, 0.0, -0.25]; times.len()],
            weight: 1.0,
        }]
    };
    let params = ["cantilever.young", "cantilever.density"];
    let options = GradientOptions::default();
    let reps = 3;
    let best = |f: &mut dyn FnMut() -> softrod::Result<()>| -> softrod::Result<f64> {
        let mut fastest = f64::INFINITY;
        for _ in 0..reps {
            let t = Instant::now();
            f()?;
            fastest = fastest.min(t.elapsed().as_secs_f64());
        }
        Ok(fastest)
    };
    let mut s = sim.clone();
    let forward = best(&mut || {
        s.value_and_gradient(&mut loss(), &[], duration, &options)
            .map(|g| drop(std::hint::black_box(g)))
    })?;
    let mut s = sim.clone();
    let plain = best(&mut || s.simulate(duration).map(|r| drop(std::hint::black_box(r))))?;
    let mut steps = 0;
    let mut grads = (f64::NAN, f64::NAN);
    let mut work = (0, 0);
    let gradient = best(&mut || {
        let g = sim.value_and_gradient(&mut loss(), &params, duration, &options)?;
        steps = g.steps;
        work = (g.jacobian_evaluations, g.dense_factorizations);
        grads = (
            g.get(params[0]).map_or(f64::NAN, |v| v[0]),
            g.get(params[1]).map_or(f64::NAN, |v| v[0]),
        );
        Ok(())
    })?;
    let ms = |s: f64| format!("{:.1} ms", 1e3 * s);
    println!(
        "| {rtol:e} | {} | {steps} | {} | {} | {} | {:.1} | {:.9e} | {:.9e} | {} / {} |",
        sim.n_dof(),
        ms(plain),
        ms(forward),
        ms(gradient),
        gradient / forward,
        grads.0,
        grads.1,
        work.0,
        work.1,
    );
    Ok(())
}

/// The rod of `prescribed` mode.
const TURNED: &str = r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "arm"
joint = { type = "revolute", axis = [0, 1, 0], prescribed = { times = [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5], values = [0.0, 0.1, 0.3, 0.6, 0.8, 0.9, 0.8, 0.6, 0.5, 0.45, 0.4] } }
length = 0.3
pieces = 8
section = { shape = "circle", radius = 0.01 }
material = { density = 1100.0, young = 3.0e6, poisson = 0.45, viscosity = 1.0e3 }
[[body]]
name = "tip"
parent = "arm"
mass = 0.02
inertia = [2e-6, 2e-6, 2e-6]
"#;

fn measure_prescribed() -> softrod::Result<()> {
    let (sim, _, _) = Simulation::from_toml(TURNED, "prescribed")?;
    let duration = 0.5;
    let times: Vec<f64> = (1..=10).map(|k| 0.05 * k as f64).collect();
    let loss = || {
        vec![LossTerm::Position {
            rod: "arm".into(),
            s: None,
            times: times.clone(),
            targets: vec![[0.2, 0.0, -0.1]; times.len()],
            weight: 1.0,
        }]
    };
    let options = GradientOptions::default();
    println!(
        "| parameters | n_dof | steps | time (fastest of 5) | linearizations | GMRES iterations |"
    );
    println!("|---|---|---|---|---|---|");
    for params in [
        &[][..],
        &["tip.mass"][..],
        &["tip.mass", "arm.prescribed"][..],
    ] {
        let mut fastest = f64::INFINITY;
        let mut last = None;
        for _ in 0..5 {
            let mut s = sim.clone();
            let t = Instant::now();
            let g = s.value_and_gradient(&mut loss(), params, duration, &options)?;
            fastest = fastest.min(t.elapsed().as_secs_f64());
            last = Some(g);
        }
        let g = last.expect("five runs");
        println!(
            "| {} | {} | {} | {:.1} ms | {} | {} |",
            if params.is_empty() {
                "none (forward run)".to_string()
            } else {
                params.join(", ")
            },
            sim.n_dof(),
            g.steps,
            1e3 * fastest,
            g.jacobian_evaluations,
            g.krylov_iterations
        );
    }
    Ok(())
}
