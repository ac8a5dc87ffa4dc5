//! What a trajectory gradient of a closed model costs (docs/performance.md,
//! "Trajectory gradients", closed chain): the four-bar of
//! crates/softrod/tests/closed_gradients.rs (two soft rods on revolute
//! joints, a ball closure to a body, a cable table; 0.1 s, fixed steps of
//! 4 ms and the scene's adaptive ESDIRK), the recorded forward run alone
//! (`value_and_gradient` with no parameters) against `value_and_gradient`
//! with respect to 7 scalar parameters plus `q0`, `qdot0`, by the adjoint
//! and by forward sensitivities (G21–G24). Run with
//!
//! ```sh
//! cargo run --release -p softrod --example closed_gradient_cost
//! ```
//!
//! Each time is the fastest of 5 calls. Errors print their whole chain
//! and exit 1.

use std::process::ExitCode;
use std::time::Instant;

use softrod::{GradientMethod, GradientOptions, LossTerm, Simulation};

const SCENE: &str = r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "a"
joint = { type = "revolute", axis = [0, 1, 0], damping = 0.001 }
length = 0.3
pieces = 2
strains = ["ky", "kz", "qx"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 300.0 }
[[cable]]
rod = "a"
offset = [0.0, 0.006]
tension = { times = [0.0, 0.1], values = [0.5, 2.0] }
[[rod]]
name = "b"
base = { position = [0.3, 0.0, -0.15], rotation = [[0, 0, -1], [0, 1, 0], [1, 0, 0]] }
joint = { type = "revolute", axis = [0, 1, 0] }
length = 0.15
pieces = 2
strains = ["ky", "qx", "qz"]
section = { shape = "circle", radius = 0.008 }
material = { density = 1100.0, young = 2.0e6, shear_modulus = 6.0e5, viscosity = 1.0e3 }
[[body]]
name = "hand"
parent = "b"
mass = 0.01
inertia = [1e-6, 1e-6, 1e-6]
center_of_mass = [0.005, 0.0, 0.0]
[[closure]]
type = "ball"
a = { element = "a" }
b = { element = "hand" }
[run]
rtol = 1e-8
atol = 1e-10
"#;

const NAMES: [&str; 8] = [
    "a.young",
    "a.density",
    "a.viscosity",
    "b.shear_modulus",
    "hand.mass",
    "cable0.tension",
    "q0",
    "qdot0",
];

fn main() -> ExitCode {
    println!(
        "| steps | n_dof | recorded forward | adjoint (7 + q0, qdot0) | adjoint / forward | forward sensitivities | sensitivities / forward |"
    );
    println!("|---|---|---|---|---|---|---|");
    for fixed_step in [Some(0.004), None] {
        if let Err(e) = measure(fixed_step) {
            eprintln!("error: {}", e.report());
            return ExitCode::FAILURE;
        }
    }
    ExitCode::SUCCESS
}

fn loss(n: usize) -> Vec<LossTerm<'static>> {
    vec![
        LossTerm::Position {
            rod: "a".into(),
            s: Some(0.15),
            times: vec![0.03, 0.07, 0.1],
            targets: vec![[0.15, 0.01, 0.02], [0.14, 0.0, -0.02], [0.15, -0.01, 0.0]],
            weight: 100.0,
        },
        LossTerm::Quadratic {
            times: vec![0.0, 0.05, 0.1],
            q_weights: (0..n).map(|i| 0.1 + 0.01 * i as f64).collect(),
            qdot_weights: vec![1e-3; n],
            q_ref: None,
        },
    ]
}

fn measure(fixed_step: Option<f64>) -> softrod::Result<()> {
    let (mut sim, _, _) = Simulation::from_toml(SCENE, "four-bar")?;
    let n = sim.n_dof();
    let mut best = |names: &[&str], method: GradientMethod| -> softrod::Result<(f64, usize)> {
        let options = GradientOptions {
            fixed_step,
            newton_tol: Some(1e-3),
            method,
        };
        let mut t = f64::INFINITY;
        let mut steps = 0;
        for _ in 0..5 {
            let start = Instant::now();
            let g = sim.value_and_gradient(&mut loss(n), names, 0.1, &options)?;
            t = t.min(start.elapsed().as_secs_f64());
            steps = g.steps;
        }
        Ok((t, steps))
    };
    let (forward, steps) = best(&[], GradientMethod::Adjoint)?;
    let (adjoint, _) = best(&NAMES, GradientMethod::Adjoint)?;
    let (sens, _) = best(&NAMES, GradientMethod::Forward)?;
    println!(
        "| {steps} ({}) | {n} | {:.2} ms | {:.2} ms | {:.1} | {:.2} ms | {:.1} |",
        fixed_step.map_or("adaptive".to_string(), |h| format!("fixed {h} s")),
        forward * 1e3,
        adjoint * 1e3,
        adjoint / forward,
        sens * 1e3,
        sens / forward
    );
    Ok(())
}
