//! The structured backward pass (the force form with GMRES on the
//! structured preconditioner, docs/theory-control.md G11) against the dense
//! one (the acceleration's Jacobians and dense LUs, G5–G7): the same
//! gradient to round-off, on a chain and on a robot with a joint and bodies.

use softrod_integrate::AdjointSolver;

use super::{GradientMethod, GradientOptions, LossTerm};
use crate::Simulation;

/// A cantilever in full 3-D (six strains) with a cable table, released
/// from rest under gravity and the cable: bending, twist and the geometric
/// terms all move.
const CHAIN: &str = r#"
[world]
gravity = [0.0, -3.0, -9.81]
[[rod]]
name = "arm"
length = 0.4
pieces = 6
section = { shape = "circle", radius = 0.01 }
material = { density = 1100.0, young = 3.0e6, poisson = 0.45, viscosity = 1.0e3 }
[[cable]]
rod = "arm"
offset = [0.004, 0.006]
tension = { times = [0.0, 0.1, 0.2], values = [0.0, 2.0, 0.5] }
"#;

const ARM: &str = include_str!("../../../../../examples/arm_with_payload.toml");

fn tip_loss(rod: &str, times: &[f64]) -> Vec<LossTerm<'static>> {
    vec![LossTerm::Position {
        rod: rod.into(),
        s: None,
        times: times.to_vec(),
        targets: vec![[0.2, 0.05, -0.2]; times.len()],
        weight: 1.0,
    }]
}

/// Both backward passes on `scene`; every entry of every gradient agrees
/// to `tol` relative to the largest entry of its parameter (the
/// transposed stage solves are both backward stable to ~ε√n ‖S‖‖ν‖; the
/// difference is that times the conditioning of `S`, accumulated over the
/// steps, and the recomputed stages' own round-off).
fn compare(scene: &str, rod: &str, params: &[&str], duration: f64, options: &GradientOptions) {
    let (mut sim, _, _) = Simulation::from_toml(scene, "test.toml").unwrap();
    let times: Vec<f64> = (1..=4).map(|k| duration * k as f64 / 4.0).collect();
    let structured = sim
        .clone()
        .gradient_with(
            &mut tip_loss(rod, &times),
            params,
            duration,
            options,
            AdjointSolver::Structured,
        )
        .unwrap();
    let dense = sim
        .gradient_with(
            &mut tip_loss(rod, &times),
            params,
            duration,
            options,
            AdjointSolver::Dense,
        )
        .unwrap();
    eprintln!(
        "{} steps; structured: {} LUs, {} GMRES iterations; dense: {} LUs",
        structured.steps,
        structured.dense_factorizations,
        structured.krylov_iterations,
        dense.dense_factorizations
    );
    assert_eq!(structured.value, dense.value);
    // The structured pass took the Krylov path.
    assert!(structured.krylov_iterations > 0);
    for ((name, a), (_, b)) in structured.gradients.iter().zip(&dense.gradients) {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{name}: zero gradient");
        let worst = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        eprintln!(
            "{name}: |structured − dense| = {:.1e} of {scale:.3e}",
            worst / scale
        );
    }
    for ((name, a), (_, b)) in structured.gradients.iter().zip(&dense.gradients) {
        let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = a
            .iter()
            .zip(b)
            .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        assert!(worst <= 1e-9 * scale, "{name}: {worst:e} of {scale:e}");
    }
}

#[test]
fn structured_and_dense_backward_passes_agree_on_a_chain() {
    let params = [
        "arm.young",
        "arm.density",
        "arm.viscosity",
        "cable0.tension",
        "q0",
        "qdot0",
    ];
    // The scene's adaptive steps (long, stiff) and short fixed ones.
    compare(CHAIN, "arm", &params, 0.2, &GradientOptions::default());
    let fixed = GradientOptions {
        fixed_step: Some(0.002),
        newton_tol: None,
        method: GradientMethod::Adjoint,
    };
    compare(CHAIN, "arm", &params, 0.05, &fixed);
}

#[test]
fn structured_and_dense_backward_passes_agree_on_a_robot_with_joints_and_bodies() {
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
    compare(ARM, "lower", &params, 0.3, &GradientOptions::default());
}

/// A rod turned at its base by a prescribed revolute joint (a spline of
/// five samples ending inside the run), a body at its tip.
const TURNED: &str = r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "arm"
joint = { type = "revolute", axis = [0, 1, 0], prescribed = { times = [0.0, 0.05, 0.1, 0.15, 0.2], values = [0.0, 0.2, 0.5, 0.4, 0.6] } }
length = 0.3
pieces = 4
section = { shape = "circle", radius = 0.01 }
material = { density = 1100.0, young = 3.0e6, poisson = 0.45, viscosity = 1.0e3 }
[[body]]
name = "tip"
parent = "arm"
mass = 0.02
inertia = [2e-6, 2e-6, 2e-6]
"#;

#[test]
fn structured_and_dense_backward_passes_agree_on_prescribed_samples() {
    let params = ["arm.prescribed", "arm.young", "tip.mass", "qdot0"];
    compare(TURNED, "arm", &params, 0.3, &GradientOptions::default());
}
