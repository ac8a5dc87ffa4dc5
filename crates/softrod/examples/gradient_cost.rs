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

use std::process::ExitCode;
use std::time::Instant;

use softrod::{GradientOptions, LossTerm, Simulation};

const SCENE: &str = include_str!("../../../examples/arm_with_payload.toml");

fn main() -> ExitCode {
    let pieces: Vec<usize> = match std::env::args()
        .skip(1)
        .map(|a| a.parse::<usize>().map_err(|_| a))
        .collect()
    {
        Ok(p) => p,
        Err(a) => {
            eprintln!("error: '{a}' is not a number of pieces");
            return ExitCode::from(2);
        }
    };
    println!(
        "| pieces per rod | n_dof | steps | plain run | recorded forward | gradient (7 + q0, qdot0) | gradient / forward | central differences, 7 params |"
    );
    println!("|---|---|---|---|---|---|---|---|");
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
    let gradient = best(&mut || {
        let g = sim.value_and_gradient(&mut loss(), &params, duration, &options)?;
        steps = g.steps;
        Ok(())
    })?;
    let scalar_params = 7; // five scalars + the two tension values
    let ms = |s: f64| format!("{:.1} ms", 1e3 * s);
    println!(
        "| {} | {} | {steps} | {} | {} | {} | {:.1} | {} |",
        pieces.map_or("4 (as shipped)".to_string(), |n| n.to_string()),
        sim.n_dof(),
        ms(plain),
        ms(forward),
        ms(gradient),
        gradient / forward,
        ms(2.0 * scalar_params as f64 * forward),
    );
    Ok(())
}
