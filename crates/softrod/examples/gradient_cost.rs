//! What a trajectory gradient costs (docs/performance.md, "Trajectory
//! gradients"): on examples/arm_with_payload.toml (two rods, a joint, two
//! bodies, a cable table; 0.5 s, the scene's adaptive ESDIRK), the time of
//! one forward run, of `value_and_gradient` with respect to 7 parameters
//! plus `q0`, `qdot0`, and of the central differences that would give the
//! same 7 parameters (14 runs; `q0`, `qdot0` by differences would need
//! 4·n_dof more). Run with
//! `cargo run --release -p softrod --example gradient_cost`.

use std::time::Instant;

use softrod::{GradientOptions, LossTerm, Simulation};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/arm_with_payload.toml"
    );
    let (mut sim, _, _) = Simulation::from_scene_file(path)?;
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
    let best = |f: &mut dyn FnMut() -> f64| {
        (0..3)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(f());
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let mut s = sim.clone();
    let forward = best(&mut || {
        s.value_and_gradient(&mut loss(), &[], duration, &options)
            .unwrap()
            .value
    });
    let plain = best(&mut || sim.simulate(duration).unwrap().t.len() as f64);
    let g = sim.value_and_gradient(&mut loss(), &params, duration, &options)?;
    let gradient = best(&mut || {
        sim.value_and_gradient(&mut loss(), &params, duration, &options)
            .unwrap()
            .value
    });
    let scalar_params = 7; // five scalars + the two tension values
    println!(
        "arm_with_payload, {duration} s, n_dof = {}, {} steps, {} Jacobians in the backward pass",
        sim.n_dof(),
        g.steps,
        g.jacobian_evaluations
    );
    println!("plain run (simulate):               {:8.2} ms", 1e3 * plain);
    println!(
        "recorded forward run (loss only):   {:8.2} ms",
        1e3 * forward
    );
    println!(
        "value_and_gradient ({} params + q0, qdot0): {:8.2} ms = {:.1} forward runs",
        scalar_params,
        1e3 * gradient,
        gradient / forward
    );
    println!(
        "central differences, {} params:    {:8.2} ms (2 runs each), q0/qdot0: {:8.2} ms",
        scalar_params,
        1e3 * 2.0 * scalar_params as f64 * forward,
        1e3 * 4.0 * sim.n_dof() as f64 * forward
    );
    Ok(())
}
