//! Trajectory gradients with respect to a joint actuator's force values
//! (`ELEMENT.actuator`, docs/theory-control.md G29) against central
//! differences of whole runs: a soft rod with a tip body on an actuated
//! revolute joint (a torque table of four rows), a universal joint with a
//! constant two-coordinate torque under a clamped rod, and the crank of a
//! closed soft four-bar (G22's projection). The differenced runs are
//! separate scenes with one value changed in the text, run with the same
//! fixed step sequence; the adjoint must agree with them to ~1e-7 and with
//! the forward sensitivities to round-off.

use softrod::{GradientMethod, GradientOptions, LossTerm, Simulation};

mod gradient_support;
use gradient_support::{FOUR_BAR, FourBar, agree, central, options_for};

const OPTIONS: GradientOptions = GradientOptions {
    fixed_step: Some(0.004),
    newton_tol: Some(1e-3),
    method: GradientMethod::Adjoint,
};
const DURATION: f64 = 0.1;

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "actuator gradient test")
        .unwrap()
        .0
}

/// The tip of `rod` tracked to fixed points plus a quadratic form.
fn loss(rod: &str, n: usize) -> Vec<LossTerm<'static>> {
    vec![
        LossTerm::Position {
            rod: rod.into(),
            s: None,
            times: vec![0.03, 0.07, 0.1],
            targets: vec![[0.2, 0.01, 0.05], [0.25, 0.0, -0.02], [0.22, -0.01, 0.0]],
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

/// Checks `name`'s gradient of `scene(x)` against central differences in
/// each entry of `x` and against the forward sensitivities.
fn check<const K: usize>(scene: impl Fn([f64; K]) -> String, x: [f64; K], name: &str, rod: &str) {
    let mut s = sim(&scene(x));
    let n = s.n_dof();
    let options = options_for(&s, OPTIONS);
    let g = s
        .value_and_gradient(&mut loss(rod, n), &[name], DURATION, &options)
        .unwrap();
    let ga = g.get(name).unwrap().to_vec();
    assert_eq!(ga.len(), K);
    for k in 0..K {
        let d = central(x[k], 1e-4 * x[k].abs().max(1e-2), |v| {
            let mut xk = x;
            xk[k] = v;
            let mut sk = sim(&scene(xk));
            sk.value_and_gradient(&mut loss(rod, n), &[], DURATION, &options)
                .unwrap()
                .value
        });
        agree(&format!("{name}[{k}]"), ga[k], d, 0.0);
    }
    let f = s
        .value_and_gradient(
            &mut loss(rod, n),
            &[name],
            DURATION,
            &GradientOptions {
                method: GradientMethod::Forward,
                ..options
            },
        )
        .unwrap();
    let gf = f.get(name).unwrap();
    let scale = ga.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (k, (a, b)) in ga.iter().zip(gf).enumerate() {
        assert!(
            (a - b).abs() <= 1e-8 * scale,
            "{name}[{k}]: adjoint {a:e}, forward {b:e}"
        );
    }
}

/// A rod with a tip body on an actuated revolute joint, its torque a table
/// at 0, 0.03, 0.06, 0.09 s (held after).
fn turning(values: [f64; 4]) -> String {
    format!(
        r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "arm"
joint = {{ type = "revolute", axis = [0, 1, 0], stiffness = 0.5, damping = 0.002, actuator = {{ force = {{ times = [0.0, 0.03, 0.06, 0.09], values = [{:e}, {:e}, {:e}, {:e}] }} }} }}
length = 0.3
pieces = 3
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 500.0 }}
[[body]]
name = "tip"
parent = "arm"
mass = 0.02
inertia = [2e-6, 2e-6, 2e-6]
center_of_mass = [0.01, 0.0, 0.0]
[run]
rtol = 1e-8
atol = 1e-10
"#,
        values[0], values[1], values[2], values[3]
    )
}

#[test]
fn a_torque_tables_values_match_central_differences() {
    check(turning, [0.0, 0.05, -0.02, 0.08], "arm.actuator", "arm");
}

/// A clamped rod, then a rod on an actuated universal joint at its tip
/// with a constant torque per coordinate; Radau IIA.
fn wrist(values: [f64; 2]) -> String {
    format!(
        r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "upper"
length = 0.25
pieces = 2
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1100.0, young = 2.0e6, poisson = 0.5, viscosity = 2.0e3 }}
[[rod]]
name = "lower"
parent = "upper"
base = {{ position = [0.01, 0.0, 0.0] }}
joint = {{ type = "universal", axes = [[0, 1, 0], [0, 0, 1]], stiffness = 0.2, actuator = {{ force = [{:e}, {:e}] }} }}
length = 0.2
pieces = 2
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.008 }}
material = {{ density = 1000.0, young = 2.0e6, poisson = 0.5, viscosity = 2.0e3 }}
[run]
rtol = 1e-8
atol = 1e-10
integrator = "radau5"
"#,
        values[0], values[1]
    )
}

#[test]
fn a_universal_joints_constant_torques_match_central_differences_with_radau5() {
    check(wrist, [0.01, -0.02], "lower.actuator", "lower");
}

/// A soft four-bar whose crank is driven by a torque table (the closure
/// projection P M⁻¹ of G22 on the actuator's columns).
fn four_bar(values: [f64; 3]) -> String {
    let joint = format!(
        ", damping = 0.001, actuator = {{ force = {{ times = [0.0, 0.05, 0.1], values = [{:e}, {:e}, {:e}] }} }}",
        values[0], values[1], values[2]
    );
    FourBar {
        crank_joint: &joint,
        ..FOUR_BAR
    }
    .toml()
}

#[test]
fn a_closed_loops_crank_torque_matches_central_differences() {
    check(four_bar, [0.0, 0.1, -0.05], "a.actuator", "a");
}

#[test]
fn an_unactuated_joint_is_refused_by_name() {
    let text = turning([0.0; 4]).replace(
        ", actuator = { force = { times = [0.0, 0.03, 0.06, 0.09], values = [0e0, 0e0, 0e0, 0e0] } }",
        "",
    );
    assert!(!text.contains("actuator"), "{text}");
    let mut s = sim(&text);
    let n = s.n_dof();
    let m = s
        .value_and_gradient(&mut loss("arm", n), &["arm.actuator"], DURATION, &OPTIONS)
        .unwrap_err()
        .to_string();
    assert!(
        m.contains("arm.actuator") && m.contains("no actuator"),
        "{m}"
    );
    let m = s
        .value_and_gradient(
            &mut loss("arm", n),
            &["nothing.actuator"],
            DURATION,
            &OPTIONS,
        )
        .unwrap_err()
        .to_string();
    assert!(
        m.contains("nothing.actuator") && m.contains("no rod or body"),
        "{m}"
    );
}
