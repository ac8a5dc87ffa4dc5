//! Trajectory gradients with respect to the samples of prescribed joints
//! (`ELEMENT.prescribed`, docs/theory-control.md G17–G20) against central
//! differences of whole runs: a soft rod with a tip body on a prescribed
//! revolute joint (its base driven through a spline of four samples), a
//! soft rod hanging from a body on a prescribed prismatic joint, and
//! a rod hanging from a clamped one by a prescribed universal joint (two
//! coordinates, free coordinates before and after it). The differenced
//! runs are separate scenes with one sample changed in the text, run with
//! the same fixed step sequence and their stage equations solved far below
//! the differences' step; the adjoint and the forward sensitivities must
//! agree with them to ~1e-7 and with each other to round-off.

use softrod::{GradientMethod, GradientOptions, LossTerm, Simulation};

mod gradient_support;
use gradient_support::{FOUR_BAR, FourBar, agree, central, options_for};

const OPTIONS: GradientOptions = GradientOptions {
    fixed_step: Some(0.004),
    newton_tol: Some(1e-3),
    method: GradientMethod::Adjoint,
};
const FORWARD: GradientOptions = GradientOptions {
    method: GradientMethod::Forward,
    ..OPTIONS
};
const DURATION: f64 = 0.1;
const TIMES: [f64; 3] = [0.03, 0.07, 0.1];

/// A rod with a tip body whose base turns by a prescribed revolute joint
/// through `values` at 0, 0.03, 0.06, 0.09 s (held after).
fn turning(values: [f64; 4]) -> String {
    format!(
        r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "arm"
joint = {{ type = "revolute", axis = [0, 1, 0], prescribed = {{ times = [0.0, 0.03, 0.06, 0.09], values = [{:e}, {:e}, {:e}, {:e}] }} }}
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

/// A clamped rod, then a rod on a prescribed universal joint at its tip
/// (`values[i]` the two angles at 0, 0.05, 0.1 s), a young modulus to
/// differentiate beside, and a cable on the upper rod.
fn wrist(values: [[f64; 2]; 3], young: f64) -> String {
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
material = {{ density = 1100.0, young = {young:e}, poisson = 0.5, viscosity = 2.0e3 }}
[[rod]]
name = "lower"
parent = "upper"
base = {{ position = [0.01, 0.0, 0.0] }}
joint = {{ type = "universal", axes = [[0, 1, 0], [0, 0, 1]], prescribed = {{ times = [0.0, 0.05, 0.1], values = [[{:e}, {:e}], [{:e}, {:e}], [{:e}, {:e}]] }} }}
length = 0.2
pieces = 2
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.008 }}
material = {{ density = 1000.0, young = 2.0e6, poisson = 0.5, viscosity = 2.0e3 }}
[[cable]]
rod = "upper"
offset = [0.0, 0.006]
tension = {{ times = [0.0, 0.1], values = [1.0, 3.0] }}
[run]
rtol = 1e-8
atol = 1e-10
"#,
        values[0][0], values[0][1], values[1][0], values[1][1], values[2][0], values[2][1]
    )
}

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "prescribed gradient test")
        .unwrap()
        .0
}

/// The tip of `rod` tracked to fixed points (it depends on the prescribed
/// coordinates directly, G19) plus a quadratic form in q and q̇.
fn loss(rod: &str, n: usize) -> Vec<LossTerm<'static>> {
    vec![
        LossTerm::Position {
            rod: rod.into(),
            s: None,
            times: TIMES.to_vec(),
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

fn value(text: &str, rod: &str) -> f64 {
    let mut s = sim(text);
    let n = s.n_dof();
    s.value_and_gradient(&mut loss(rod, n), &[], DURATION, &OPTIONS)
        .unwrap()
        .value
}

/// The adjoint and the forward sensitivities agree to round-off.
fn same(name: &str, a: &[f64], f: &[f64]) {
    assert_eq!(a.len(), f.len(), "{name}");
    let scale = a.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for (i, (x, y)) in a.iter().zip(f).enumerate() {
        assert!(
            (x - y).abs() <= 1e-9 * scale,
            "{name}[{i}]: adjoint {x:e}, forward {y:e}"
        );
    }
}

#[test]
fn revolute_samples_match_central_differences() {
    let x = [0.0, 0.3, 0.2, 0.5];
    let mut s = sim(&turning(x));
    let n = s.n_dof();
    let names = ["arm.prescribed", "tip.mass"];
    let g = s
        .value_and_gradient(&mut loss("arm", n), &names, DURATION, &OPTIONS)
        .unwrap();
    let gp = g.get("arm.prescribed").unwrap();
    assert_eq!(gp.len(), 4);
    for k in 0..4 {
        let d = central(x[k], 1e-6, |v| {
            let mut xk = x;
            xk[k] = v;
            value(&turning(xk), "arm")
        });
        agree(&format!("arm.prescribed[{k}]"), gp[k], d, 0.0);
    }
    let f = s
        .value_and_gradient(&mut loss("arm", n), &names, DURATION, &FORWARD)
        .unwrap();
    assert_eq!(g.value, f.value);
    for name in names {
        same(name, g.get(name).unwrap(), f.get(name).unwrap());
    }
}

#[test]
fn universal_samples_match_central_differences() {
    let x = [[0.0, 0.0], [0.4, -0.2], [0.1, 0.3]];
    let young = 2.0e6;
    let mut s = sim(&wrist(x, young));
    let n = s.n_dof();
    // Interleaved with a model parameter: the entries keep their places.
    let names = ["upper.young", "lower.prescribed", "cable0.tension"];
    let g = s
        .value_and_gradient(&mut loss("lower", n), &names, DURATION, &OPTIONS)
        .unwrap();
    let gp = g.get("lower.prescribed").unwrap();
    assert_eq!(gp.len(), 6);
    for i in 0..3 {
        for c in 0..2 {
            let d = central(x[i][c], 1e-6, |v| {
                let mut xk = x;
                xk[i][c] = v;
                value(&wrist(xk, young), "lower")
            });
            agree(
                &format!("lower.prescribed[{i}][{c}]"),
                gp[2 * i + c],
                d,
                0.0,
            );
        }
    }
    let d = central(young, 0.0, |v| value(&wrist(x, v), "lower"));
    agree("upper.young", g.get("upper.young").unwrap()[0], d, 0.0);
    let f = s
        .value_and_gradient(&mut loss("lower", n), &names, DURATION, &FORWARD)
        .unwrap();
    for name in names {
        same(name, g.get(name).unwrap(), f.get(name).unwrap());
    }
}

#[test]
fn bad_prescribed_requests_name_what_is_wrong() {
    let mut s = sim(&wrist([[0.0, 0.0], [0.4, -0.2], [0.1, 0.3]], 2.0e6));
    let n = s.n_dof();
    let message = |s: &mut Simulation, p: &str| {
        s.value_and_gradient(&mut loss("lower", n), &[p], DURATION, &OPTIONS)
            .unwrap_err()
            .to_string()
    };
    let m = message(&mut s, "elbow.prescribed");
    assert!(
        m.contains("elbow.prescribed") && m.contains("no rod or body named 'elbow'"),
        "{m}"
    );
    let m = message(&mut s, "upper.prescribed");
    assert!(
        m.contains("upper.prescribed") && m.contains("not prescribed"),
        "{m}"
    );
    let sine = sim(&turning([0.0; 4]).replace(
        "prescribed = { times = [0.0, 0.03, 0.06, 0.09], values = [0e0, 0e0, 0e0, 0e0] }",
        "prescribed = { sine = { amplitude = 0.1, frequency = 5.0 } }",
    ));
    let mut sine = sine;
    let n = sine.n_dof();
    let m = sine
        .value_and_gradient(&mut loss("arm", n), &["arm.prescribed"], DURATION, &OPTIONS)
        .unwrap_err()
        .to_string();
    assert!(
        m.contains("arm.prescribed") && m.contains("sinusoid"),
        "{m}"
    );
}

/// A closed loop whose crank is driven: a soft rod on a prescribed
/// revolute joint (samples at 0, 0.05, 0.1 s), a second soft rod on a
/// free revolute joint, their tips held together by a ball closure. The
/// closure rows depend on the prescribed coordinate (G28).
fn crank(values: [f64; 3]) -> String {
    let joint = format!(
        ", prescribed = {{ times = [0.0, 0.05, 0.1], values = [{:e}, {:e}, {:e}] }}",
        values[0], values[1], values[2]
    );
    FourBar {
        crank_joint: &joint,
        ..FOUR_BAR
    }
    .toml()
}

#[test]
fn closed_loop_samples_match_central_differences() {
    let x = [0.0, 0.15, 0.05];
    let names = ["a.prescribed", "hand.mass"];
    for integrator in ["esdirk", "radau5"] {
        let scene = |x: [f64; 3]| format!("{}integrator = \"{integrator}\"\n", crank(x));
        let mut s = sim(&scene(x));
        let n = s.n_dof();
        let options = options_for(&s, OPTIONS);
        let g = s
            .value_and_gradient(&mut loss("a", n), &names, DURATION, &options)
            .unwrap();
        let gp = g.get("a.prescribed").unwrap();
        assert_eq!(gp.len(), 3);
        // Not the first sample: it moves the crank at t = 0, and a scene
        // whose loop is not assembled at its start is refused (the
        // gradient holds the start `q0` fixed).
        for k in 1..3 {
            let d = central(x[k], 1e-6, |v| {
                let mut xk = x;
                xk[k] = v;
                let mut sk = sim(&scene(xk));
                sk.value_and_gradient(&mut loss("a", n), &[], DURATION, &options)
                    .unwrap()
                    .value
            });
            agree(&format!("{integrator} a.prescribed[{k}]"), gp[k], d, 0.0);
        }
        let f = s
            .value_and_gradient(
                &mut loss("a", n),
                &names,
                DURATION,
                &GradientOptions {
                    method: GradientMethod::Forward,
                    ..options
                },
            )
            .unwrap();
        // As in tests/closed_gradients.rs: the closed model's differenced
        // closure rows (CD4, G28) carry rounding ~1e-10 relative that is
        // not smooth in the point, so the two algorithms agree to ~1e-9
        // relative to each entry, not to the round-off of an open model.
        for name in names {
            for (k, (x, y)) in g
                .get(name)
                .unwrap()
                .iter()
                .zip(f.get(name).unwrap())
                .enumerate()
            {
                let err = (x - y).abs() / x.abs();
                eprintln!("{integrator} {name}[{k}]: adjoint {x:e}, forward {y:e}, {err:e}");
                assert!(
                    err < 1e-8,
                    "{integrator} {name}[{k}]: adjoint {x:e}, forward {y:e}"
                );
            }
        }
    }
}

/// A body on a prescribed prismatic joint (a linear stage), a soft rod
/// hanging from it: the samples of a body's joint.
fn stage(values: [f64; 3]) -> String {
    format!(
        r#"
[world]
gravity = [0.0, 0.0, -9.81]
[[body]]
name = "carriage"
parent = "world"
joint = {{ type = "prismatic", axis = [1, 0, 0], prescribed = {{ times = [0.0, 0.04, 0.08], values = [{:e}, {:e}, {:e}] }} }}
mass = 0.1
inertia = [1e-5, 1e-5, 1e-5]
[[rod]]
name = "arm"
parent = "carriage"
base = {{ rotation = [[0, 0, -1], [0, 1, 0], [1, 0, 0]] }}
length = 0.25
pieces = 3
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.008 }}
material = {{ density = 1000.0, young = 5.0e5, poisson = 0.5, viscosity = 300.0 }}
[run]
rtol = 1e-8
atol = 1e-10
"#,
        values[0], values[1], values[2]
    )
}

#[test]
fn a_bodys_prismatic_samples_match_central_differences() {
    let x = [0.0, 0.02, 0.05];
    let mut s = sim(&stage(x));
    let n = s.n_dof();
    let g = s
        .value_and_gradient(
            &mut loss("arm", n),
            &["carriage.prescribed"],
            DURATION,
            &OPTIONS,
        )
        .unwrap();
    let gp = g.get("carriage.prescribed").unwrap();
    assert_eq!(gp.len(), 3);
    for k in 0..3 {
        let d = central(x[k], 1e-6, |v| {
            let mut xk = x;
            xk[k] = v;
            value(&stage(xk), "arm")
        });
        agree(&format!("carriage.prescribed[{k}]"), gp[k], d, 0.0);
    }
    let f = s
        .value_and_gradient(
            &mut loss("arm", n),
            &["carriage.prescribed"],
            DURATION,
            &FORWARD,
        )
        .unwrap();
    same(
        "carriage.prescribed",
        gp,
        f.get("carriage.prescribed").unwrap(),
    );
}

/// The revolute samples with Radau IIA (its own adjoint, G25): the
/// companion model's products enter its collocation system's parameter
/// products as they enter ESDIRK's stages.
#[test]
fn revolute_samples_with_radau5_match_central_differences() {
    let scene = |x: [f64; 4]| format!("{}integrator = \"radau5\"\n", turning(x));
    let x = [0.0, 0.3, 0.2, 0.5];
    let mut s = sim(&scene(x));
    let n = s.n_dof();
    let options = options_for(&s, OPTIONS);
    let g = s
        .value_and_gradient(&mut loss("arm", n), &["arm.prescribed"], DURATION, &options)
        .unwrap();
    let gp = g.get("arm.prescribed").unwrap();
    for k in 0..4 {
        let d = central(x[k], 1e-6, |v| {
            let mut xk = x;
            xk[k] = v;
            let mut sk = sim(&scene(xk));
            sk.value_and_gradient(&mut loss("arm", n), &[], DURATION, &options)
                .unwrap()
                .value
        });
        agree(&format!("radau5 arm.prescribed[{k}]"), gp[k], d, 0.0);
    }
    let f = s
        .value_and_gradient(
            &mut loss("arm", n),
            &["arm.prescribed"],
            DURATION,
            &GradientOptions {
                method: GradientMethod::Forward,
                ..options
            },
        )
        .unwrap();
    same(
        "radau5 arm.prescribed",
        gp,
        f.get("arm.prescribed").unwrap(),
    );
}
