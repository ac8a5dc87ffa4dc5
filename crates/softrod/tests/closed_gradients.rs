//! Trajectory gradients of a closed model (docs/theory-control.md G22–G24):
//! a four-bar of two soft rods on revolute joints, the crank's tip held by a
//! ball closure to a body at the rocker's tip, a cable with a tension table
//! on the crank. Checked against central differences of whole runs on
//! every parameter kind (moduli, density, viscosity, a body's mass, the
//! tension table, q0, qdot0), the adjoint against forward sensitivities
//! (fixed and adaptive steps, and with a redundant closure row), and
//! `∂q̈/∂p = −P M⁻¹ ∂ID/∂p` itself against central differences of the
//! constrained forward dynamics.

use softrod::dynamics::{
    ClosedDerivatives, Data, closed_force_response, forward_dynamics, open_tree_inverse_dynamics,
};
use softrod::{GradientMethod, GradientOptions, LossTerm, Simulation};

mod gradient_support;
use gradient_support::{FourBar, agree, central, options_for};

const OPTIONS: GradientOptions = GradientOptions {
    fixed_step: Some(0.004),
    newton_tol: Some(1e-3),
    method: GradientMethod::Adjoint,
};
const DURATION: f64 = 0.1;
const TIMES: [f64; 3] = [0.03, 0.07, 0.1];

/// The four-bar's parameters.
#[derive(Clone, Copy)]
struct P {
    young: f64,
    density: f64,
    viscosity: f64,
    shear: f64,
    mass: f64,
    tension: [f64; 2],
}

const BASE: P = P {
    young: 1.0e6,
    density: 1000.0,
    viscosity: 300.0,
    shear: 6.0e5,
    mass: 0.01,
    tension: [0.5, 2.0],
};

/// Ground pins at (0, 0, 0) and (0.3, 0, −0.15); the crank `a` (0.3 m)
/// along x, the rocker `b` (0.15 m) along z; their tips meet at
/// (0.3, 0, 0), where `hand` sits on `b` and the ball closure holds `a`'s
/// tip to it. `a_strains`: `["ky", "qx"]` leaves the closure's y row
/// without a column (every coordinate moves in the x-z plane): a redundant
/// row the forward solve drops.
fn four_bar(p: P, a_strains: &str) -> String {
    let material = format!(
        "density = {:e}, young = {:e}, poisson = 0.5, viscosity = {:e}",
        p.density, p.young, p.viscosity
    );
    let cable = format!(
        "[[cable]]\nrod = \"a\"\noffset = [0.0, 0.006]\ntension = {{ times = [0.0, 0.1], values = [{:e}, {:e}] }}",
        p.tension[0], p.tension[1]
    );
    FourBar {
        crank_joint: ", damping = 0.001",
        a_strains,
        a_material: &material,
        after_a: &cable,
        b_shear: p.shear,
        hand_mass: p.mass,
        hand_extra: "center_of_mass = [0.005, 0.0, 0.0]",
    }
    .toml()
}

/// A parameter's name, value and the model with it moved.
type Moved = Box<dyn Fn(f64) -> P>;

const FULL: &str = r#"["ky", "kz", "qx"]"#;
const PLANAR: &str = r#"["ky", "qx"]"#;

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "closed gradient test")
        .unwrap()
        .0
}

/// The crank's middle tracked to fixed points, plus a quadratic form.
fn loss(n: usize) -> Vec<LossTerm<'static>> {
    vec![
        LossTerm::Position {
            rod: "a".into(),
            s: Some(0.15),
            times: TIMES.to_vec(),
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

fn value(mut s: Simulation) -> f64 {
    let n = s.n_dof();
    s.value_and_gradient(&mut loss(n), &[], DURATION, &OPTIONS)
        .unwrap()
        .value
}

/// G22: `∂q̈/∂p = −P M⁻¹ (ID(p + Δ) − ID(p))/Δ` (the open tree's inverse
/// dynamics, exact for the affine `ID`) against central differences of the
/// constrained forward dynamics itself, off the constraint manifold (the
/// Baumgarte terms count) and moving, for a modulus, a density, a mass and
/// a tension value; with a full-rank and a redundant closure.
#[test]
fn closed_parameter_derivative_matches_differences_of_the_constrained_dynamics() {
    for strains in [FULL, PLANAR] {
        let base = sim(&four_bar(BASE, strains));
        let model = base.model().clone();
        let n = model.n_dof();
        let q: Vec<f64> = (0..n).map(|i| 0.02 * ((i as f64) * 1.3).sin()).collect();
        let qd: Vec<f64> = (0..n).map(|i| 0.3 * ((i as f64) * 0.7).cos()).collect();
        let t = 0.04;
        let mut data = Data::new(&model);
        let qdd = forward_dynamics(&model, &mut data, t, &q, &qd, None)
            .unwrap()
            .clone();
        let id0 = open_tree_inverse_dynamics(&model, &mut data, t, &q, &qd, qdd.as_slice())
            .unwrap()
            .clone();
        let moved: [(&str, f64, Moved); 4] = [
            ("young", BASE.young, Box::new(|x| P { young: x, ..BASE })),
            (
                "density",
                BASE.density,
                Box::new(|x| P { density: x, ..BASE }),
            ),
            ("mass", BASE.mass, Box::new(|x| P { mass: x, ..BASE })),
            (
                "tension[1]",
                BASE.tension[1],
                Box::new(|x| P {
                    tension: [BASE.tension[0], x],
                    ..BASE
                }),
            ),
        ];
        let mut work = ClosedDerivatives::new(&model);
        for (name, p0, at) in &moved {
            // −P M⁻¹ ∂ID/∂p with ∂ID/∂p from a step of the value itself.
            let m2 = sim(&four_bar(at(2.0 * p0), strains)).model().clone();
            let mut d2 = Data::new(&m2);
            let id = open_tree_inverse_dynamics(&m2, &mut d2, t, &q, &qd, qdd.as_slice()).unwrap();
            let mut x =
                nalgebra::DMatrix::from_iterator(n, 1, (0..n).map(|r| -(id[r] - id0[r]) / p0));
            closed_force_response(&model, &mut data, &mut work, t, &q, &qd, None, &mut x).unwrap();
            // Central differences of the constrained q̈.
            // Step 1e-4 of the value: truncation (∝ step²) and the
            // rounding of the violent off-manifold q̈ (∝ 1/step) balance
            // near it (the mass: 2e-7 of the derivative at 1e-3, 1e-8 at
            // 1e-4, 3e-6 at 1e-6).
            let h = 1e-4 * p0;
            let a = |p: f64| {
                let m = sim(&four_bar(at(p), strains)).model().clone();
                let mut d = Data::new(&m);
                forward_dynamics(&m, &mut d, t, &q, &qd, None)
                    .unwrap()
                    .clone()
            };
            let fd = (a(p0 + h) - a(p0 - h)) / (2.0 * h);
            let err = (x.column(0) - &fd).amax() / fd.amax();
            eprintln!(
                "{strains} {name}: |dqdd/dp| {:e}, relative {err:e}",
                fd.amax()
            );
            assert!(fd.amax() > 0.0 && err < 1e-6, "{strains} {name}: {err:e}");
        }
    }
}

#[test]
fn closed_chain_gradients_match_central_differences() {
    let mut s = sim(&four_bar(BASE, FULL));
    let n = s.n_dof();
    let names = [
        "a.young",
        "a.density",
        "a.viscosity",
        "b.shear_modulus",
        "hand.mass",
        "cable0.tension",
        "q0",
        "qdot0",
    ];
    let g = s
        .value_and_gradient(&mut loss(n), &names, DURATION, &OPTIONS)
        .unwrap();
    assert!(g.value > 0.0);
    let l = |p: P| value(sim(&four_bar(p, FULL)));
    let one = |name: &str| g.get(name).unwrap()[0];
    let d = central(BASE.young, 0.0, |x| l(P { young: x, ..BASE }));
    agree("a.young", one("a.young"), d, 0.0);
    let d = central(BASE.density, 0.0, |x| l(P { density: x, ..BASE }));
    agree("a.density", one("a.density"), d, 0.0);
    let d = central(BASE.viscosity, 0.0, |x| {
        l(P {
            viscosity: x,
            ..BASE
        })
    });
    agree("a.viscosity", one("a.viscosity"), d, 0.0);
    // Shear moves this linkage little: a longer step keeps the
    // differences' round-off below the tolerance.
    let shear = |x: f64| l(P { shear: x, ..BASE });
    let d =
        (shear(BASE.shear * (1.0 + 1e-4)) - shear(BASE.shear * (1.0 - 1e-4))) / (2e-4 * BASE.shear);
    agree("b.shear_modulus", one("b.shear_modulus"), d, 0.0);
    let d = central(BASE.mass, 0.0, |x| l(P { mass: x, ..BASE }));
    agree("hand.mass", one("hand.mass"), d, 0.0);
    for k in 0..2 {
        let d = central(BASE.tension[k], 0.0, |x| {
            let mut tension = BASE.tension;
            tension[k] = x;
            l(P { tension, ..BASE })
        });
        agree(
            &format!("cable0.tension[{k}]"),
            g.get("cable0.tension").unwrap()[k],
            d,
            0.0,
        );
    }
    // The initial state: a few components, off the constraint manifold
    // (the Baumgarte terms pull the loop closed again).
    let gq = g.get("q0").unwrap();
    let gv = g.get("qdot0").unwrap();
    let scale = gq.iter().chain(gv).map(|v| v.abs()).fold(0.0, f64::max);
    for c in [0, 3, n - 1] {
        let at = |x: f64, velocity: bool| {
            let mut s = sim(&four_bar(BASE, FULL));
            let (mut q, mut v) = (vec![0.0; n], vec![0.0; n]);
            if velocity {
                v[c] = x;
            } else {
                q[c] = x;
            }
            s.set_initial_state(&q, &v).unwrap();
            value(s)
        };
        agree(
            &format!("q0[{c}]"),
            gq[c],
            central(0.0, 1e-6, |x| at(x, false)),
            1e-3 * scale,
        );
        agree(
            &format!("qdot0[{c}]"),
            gv[c],
            central(0.0, 1e-6, |x| at(x, true)),
            1e-3 * scale,
        );
    }
}

/// G21 on the closed model: forward sensitivities give the adjoint's
/// gradient to round-off (both use the same closed-chain Jacobians, so
/// their difference-step error does not enter), fixed and adaptive steps,
/// and with the redundant closure row; the adaptive gradient agrees with
/// the fixed-step one to the discretization error.
#[test]
fn closed_chain_forward_sensitivities_equal_the_adjoint() {
    let names = [
        "a.young",
        "a.density",
        "a.viscosity",
        "b.shear_modulus",
        "hand.mass",
        "cable0.tension",
        "q0",
        "qdot0",
    ];
    let fixed = OPTIONS;
    let adaptive = GradientOptions {
        fixed_step: None,
        ..OPTIONS
    };
    let mut by_steps = Vec::new();
    for (strains, options) in [(FULL, fixed), (FULL, adaptive), (PLANAR, fixed)] {
        let mut s = sim(&four_bar(BASE, strains));
        let n = s.n_dof();
        let a = s
            .value_and_gradient(&mut loss(n), &names, DURATION, &options)
            .unwrap();
        let forward = GradientOptions {
            method: GradientMethod::Forward,
            ..options
        };
        let f = s
            .value_and_gradient(&mut loss(n), &names, DURATION, &forward)
            .unwrap();
        assert_eq!(a.value, f.value, "one recorded run, one loss");
        let scale = a
            .gradients
            .iter()
            .flat_map(|(_, g)| g.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for ((name, ga), (_, gf)) in a.gradients.iter().zip(&f.gradients) {
            assert_eq!(ga.len(), gf.len(), "{name}");
            for (k, (x, y)) in ga.iter().zip(gf).enumerate() {
                // Relative to the entry, or for entries far below the
                // largest to 1e-2 of it: the closed Jacobians' differences
                // of the closure rows (CD4) carry rounding ~1e-10 relative
                // that is not smooth in the point, and the two algorithms'
                // stages agree to round-off, not bitwise (measured: 1.3e-9
                // on a q0 entry of 5e-3 with the largest 2e2).
                let err = (x - y).abs() / x.abs().max(1e-2 * scale);
                worst = worst.max(err);
                assert!(
                    err < 1e-8,
                    "{strains} {:?}: {name}[{k}]: adjoint {x:e}, forward {y:e}, {err:e}",
                    options.fixed_step
                );
            }
        }
        eprintln!(
            "{strains} {:?}: {} steps, adjoint vs forward ≤ {worst:e}",
            options.fixed_step, a.steps
        );
        if strains == FULL {
            by_steps.push(a);
        }
    }
    let (f, a) = (&by_steps[0], &by_steps[1]);
    for name in ["a.young", "hand.mass"] {
        let (x, y) = (f.get(name).unwrap()[0], a.get(name).unwrap()[0]);
        assert!((x - y).abs() < 1e-3 * x.abs(), "{name}: {x:e} vs {y:e}");
    }
}

/// The closed four-bar run with Radau IIA (G25, G26): its adjoint against
/// central differences of whole radau5 runs on a modulus, the mass, a
/// tension value and a velocity, and against its forward sensitivities
/// (fixed and adaptive steps).
#[test]
fn radau5_closed_chain_gradients_match_differences_and_forward_sensitivities() {
    let radau = |p: P| four_bar(p, FULL).replace("[run]", "[run]\nintegrator = \"radau5\"");
    let mut s = sim(&radau(BASE));
    let n = s.n_dof();
    let options = options_for(&s, OPTIONS);
    let names = [
        "a.young",
        "a.density",
        "a.viscosity",
        "b.shear_modulus",
        "hand.mass",
        "cable0.tension",
        "q0",
        "qdot0",
    ];
    let g = s
        .value_and_gradient(&mut loss(n), &names, DURATION, &options)
        .unwrap();
    let l = |p: P| {
        let mut s = sim(&radau(p));
        s.value_and_gradient(&mut loss(n), &[], DURATION, &options)
            .unwrap()
            .value
    };
    let one = |name: &str| g.get(name).unwrap()[0];
    let d = central(BASE.young, 0.0, |x| l(P { young: x, ..BASE }));
    agree("a.young", one("a.young"), d, 0.0);
    let d = central(BASE.viscosity, 0.0, |x| {
        l(P {
            viscosity: x,
            ..BASE
        })
    });
    agree("a.viscosity", one("a.viscosity"), d, 0.0);
    let d = central(BASE.mass, 0.0, |x| l(P { mass: x, ..BASE }));
    agree("hand.mass", one("hand.mass"), d, 0.0);
    let d = central(BASE.tension[1], 0.0, |x| {
        l(P {
            tension: [BASE.tension[0], x],
            ..BASE
        })
    });
    agree(
        "cable0.tension[1]",
        g.get("cable0.tension").unwrap()[1],
        d,
        0.0,
    );
    let gv = g.get("qdot0").unwrap();
    let scale = gv.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let d = central(0.0, 1e-6, |x| {
        let mut s = sim(&radau(BASE));
        let mut v = vec![0.0; n];
        v[0] = x;
        s.set_initial_state(&vec![0.0; n], &v).unwrap();
        s.value_and_gradient(&mut loss(n), &[], DURATION, &options)
            .unwrap()
            .value
    });
    agree("qdot0[0]", gv[0], d, 1e-3 * scale);
    for options in [
        options,
        GradientOptions {
            fixed_step: None,
            ..options
        },
    ] {
        let a = s
            .value_and_gradient(&mut loss(n), &names, DURATION, &options)
            .unwrap();
        let f = s
            .value_and_gradient(
                &mut loss(n),
                &names,
                DURATION,
                &GradientOptions {
                    method: GradientMethod::Forward,
                    ..options
                },
            )
            .unwrap();
        let scale = a
            .gradients
            .iter()
            .flat_map(|(_, g)| g.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for ((name, ga), (_, gf)) in a.gradients.iter().zip(&f.gradients) {
            for (k, (x, y)) in ga.iter().zip(gf).enumerate() {
                // As the ESDIRK comparison above: the closure rows'
                // differenced Jacobians carry ~1e-10 of non-smooth rounding.
                let err = (x - y).abs() / x.abs().max(1e-2 * scale);
                worst = worst.max(err);
                assert!(
                    err < 1e-8,
                    "{:?}: {name}[{k}]: adjoint {x:e}, forward {y:e}, {err:e}",
                    options.fixed_step
                );
            }
        }
        eprintln!(
            "radau5 {:?}: {} steps, adjoint vs forward ≤ {worst:e}",
            options.fixed_step, a.steps
        );
    }
}

/// The redundant closure row (PLANAR: the ball's y row has no column):
/// the adjoint against central differences of whole runs, for a modulus
/// and the mass.
#[test]
fn closed_chain_with_a_redundant_row_matches_central_differences() {
    let mut s = sim(&four_bar(BASE, PLANAR));
    let n = s.n_dof();
    let g = s
        .value_and_gradient(&mut loss(n), &["a.young", "hand.mass"], DURATION, &OPTIONS)
        .unwrap();
    let l = |p: P| value(sim(&four_bar(p, PLANAR)));
    let d = central(BASE.young, 0.0, |x| l(P { young: x, ..BASE }));
    agree("a.young", g.get("a.young").unwrap()[0], d, 0.0);
    let d = central(BASE.mass, 0.0, |x| l(P { mass: x, ..BASE }));
    agree("hand.mass", g.get("hand.mass").unwrap()[0], d, 0.0);
}
