//! Inverse statics of closed models and targets on bodies
//! (docs/theory-control.md IS8–IS12) against independent references: the
//! tensions and shape of a forward (constrained) statics solve recovered;
//! the sensitivities `∂q/∂T`, `∂λ/∂T` of the bordered system (IS9) against
//! central differences of forward statics solves; bad body targets.

use nalgebra::{DMatrix, DVector};
use softrod::control::{ActuationOptions, Bound, Target};
use softrod::dynamics::{
    Data, StaticsOptions, actuation_matrix, closure_statics, statics_sensitivity,
};
use softrod::{Error, Simulation};

const LENGTH: f64 = 0.5;

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// A 10-piece arm (bending, torsion, stretch: 40 strain DoF) sagging under
/// gravity with three cables at 120° (8 mm off the centreline), and
/// `extra` appended (closures, bodies).
fn three_cable_arm(extra: &str) -> Simulation {
    let mut text = format!(
        "[world]\ngravity = [0.0, 0.0, -9.81]\n\
         [[rod]]\nname = \"arm\"\nlength = {LENGTH}\npieces = 10\n\
         strains = [\"kx\", \"ky\", \"kz\", \"qx\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n"
    );
    for a in [90.0f64, 210.0, 330.0] {
        let (y, z) = (0.008 * a.to_radians().cos(), 0.008 * a.to_radians().sin());
        text.push_str(&format!(
            "[[cable]]\nrod = \"arm\"\noffset = [{y}, {z}]\ntension = 0.0\n"
        ));
    }
    text.push_str(extra);
    sim(&text)
}

/// The tip slides on the world's x axis (a slider closure: two rows); the
/// cables' common pull shortens the arm along it, so the three tensions
/// are determined by the shape.
const SLIDER: &str = "[[closure]]\ntype = \"slider\"\naxis = [1, 0, 0]\n\
                      a = { element = \"arm\" }\nb = { element = \"world\" }\n";

/// The tip pinned where it rests (a ball closure: three rows).
const BALL: &str = "[[closure]]\ntype = \"ball\"\n\
                    a = { element = \"arm\" }\n\
                    b = { element = \"world\", base = { position = [0.5, 0, 0] } }\n";

/// An end effector at the tip: a 20 g body whose frame is 3 cm beyond
/// the tip and turned 30° about the section's z axis, on a stiff revolute
/// joint about the section's y axis (so the body's pose is not the
/// section's).
const GRIPPER: &str = "[[body]]\nname = \"gripper\"\nparent = \"arm\"\n\
     base = { position = [0.03, 0.0, 0.0], rotation = [[0.8660254037844387, -0.5, 0.0], [0.5, 0.8660254037844387, 0.0], [0.0, 0.0, 1.0]] }\n\
     joint = { type = \"revolute\", axis = [0, 1, 0], stiffness = 0.05 }\n\
     mass = 0.02\ninertia = [4e-6, 4e-6, 4e-6]\ncenter_of_mass = [0.01, 0.0, 0.0]\n";

/// Forward statics at tensions `t`: the equilibrium `q`.
fn forward(s: &mut Simulation, t: &[f64]) -> Vec<f64> {
    s.set_cable_tensions(Some(t)).unwrap();
    let q = s.statics().unwrap().q.as_slice().to_vec();
    s.set_cable_tensions(None).unwrap();
    q
}

/// IS8–IS10: the tensions of a forward statics solve of the slider-closed
/// arm are recovered from two section positions it produced, and so is
/// the (constrained) shape. Effort term off: the tensions are determined.
/// Tolerances as for the open arm (tests/inverse_statics.rs): statics to
/// 1e-12 relative, steps to 1e-10.
#[test]
fn closed_arm_recovers_forward_tensions_and_shape() {
    let mut s = three_cable_arm(SLIDER);
    let truth = [1.2, 0.5, 0.2];
    let q = forward(&mut s, &truth);
    let mid = s.pose("arm", 0.25, &q).unwrap();
    let near_tip = s.pose("arm", 0.4, &q).unwrap();
    let tip = s.pose("arm", LENGTH, &q).unwrap();
    // The closure holds at the forward solution, and the cables moved the
    // tip along the slider (the test is not about the rest shape).
    assert!(tip.translation.y.abs() < 1e-9 && tip.translation.z.abs() < 1e-9);
    assert!((tip.translation.x - LENGTH).abs() > 1e-4, "{tip:?}");
    let targets = [
        Target::position(0, 0.25, mid.translation.into()),
        Target::position(0, 0.4, near_tip.translation.into()),
    ];
    let options = ActuationOptions {
        effort_weight: 0.0,
        ..ActuationOptions::default()
    };
    let a = s
        .solve_actuation(&targets, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(a.converged && a.reached, "{}", a.message);
    for c in 0..3 {
        assert!(
            (a.tensions[c] - truth[c]).abs() < 1e-7,
            "{:?} vs {truth:?}",
            a.tensions
        );
    }
    let dq = (&a.q - DVector::from_vec(q)).amax();
    assert!(dq < 1e-8, "shape off by {dq:e}");
    assert!(a.bounds.iter().all(|b| *b == Bound::Free));
    // Gauss–Newton on a zero-residual problem with the exact sensitivity:
    // a handful of iterations, not a linear crawl.
    assert!(a.iterations <= 12, "{} iterations", a.iterations);
}

/// IS9: `∂q/∂T` and `∂λ/∂T` of the bordered system against central
/// differences of forward constrained statics solves, for a slider (2
/// rows) and a ball (3 rows) at the tip, to 1e-7 relative (measured
/// 3e-9). Steps `h = 1e-4 (1 + T)`: the
/// truncation error is `O(h²)` ~ 1e-8 relative, the statics' tolerance
/// (1e-12 of the balanced force) adds ~1e-8 divided by `h`; the tangent's
/// own differences ~1e-10.
#[test]
fn closed_sensitivities_match_central_differences() {
    for (name, closure) in [("slider", SLIDER), ("ball", BALL)] {
        let s = three_cable_arm(closure);
        let model = s.model();
        let mut data = Data::new(model);
        let t0 = [1.0, 0.6, 0.3];
        let opts = StaticsOptions::default();
        let solve = |data: &mut Data, t: &[f64], q0: &[f64]| {
            data.set_cable_tensions(model, Some(t)).unwrap();
            closure_statics(model, data, q0, &opts).unwrap()
        };
        let rest = vec![0.0; model.n_dof()];
        let (r, lambda) = solve(&mut data, &t0, &rest);
        let q = r.q.as_slice().to_vec();
        assert_eq!(lambda.len(), model.n_constraints());
        let b = actuation_matrix(model, &q).unwrap();
        let sens = statics_sensitivity(model, &mut data, 0.0, &q, lambda.as_slice(), &b)
            .unwrap()
            .expect("a regular bordered matrix");
        let (dq, dl) = (sens.dq, sens.dlambda);
        let mut fq = DMatrix::zeros(model.n_dof(), 3);
        let mut fl = DMatrix::zeros(model.n_constraints(), 3);
        for c in 0..3 {
            let h = 1e-4 * (1.0 + t0[c]);
            let (mut tp, mut tm) = (t0, t0);
            tp[c] += h;
            tm[c] -= h;
            let (rp, lp) = solve(&mut data, &tp, &q);
            let (rm, lm) = solve(&mut data, &tm, &q);
            fq.set_column(c, &((&rp.q - &rm.q) / (2.0 * h)));
            fl.set_column(c, &((&lp - &lm) / (2.0 * h)));
        }
        let eq = (&dq - &fq).amax() / fq.amax();
        let el = (&dl - &fl).amax() / fl.amax();
        eprintln!("{name}: ∂q/∂T {eq:.1e}, ∂λ/∂T {el:.1e} relative to the differences");
        assert!(eq < 1e-7, "{name}: ∂q/∂T off by {eq:e} relative");
        assert!(el < 1e-7, "{name}: ∂λ/∂T off by {el:e} relative");
        // The closure forces matter here: the open tree's K_t⁻¹ B (what
        // IS3 alone gives; the same arm without the closure, same q) is
        // far from the differences.
        let free = three_cable_arm("");
        let open = open_sensitivity(free.model(), &t0, &q, &b);
        let e_open = (&open - &fq).amax() / fq.amax();
        eprintln!("{name}: open K_t⁻¹B off by {e_open:.1e}");
        assert!(e_open > 1e-2, "{name}: open K_t⁻¹B agrees ({e_open:e})");
    }
}

/// `K_t⁻¹ B` of the open `model` at `q` and tensions `t`.
fn open_sensitivity(
    model: &softrod::dynamics::Model,
    t: &[f64],
    q: &[f64],
    b: &DMatrix<f64>,
) -> DMatrix<f64> {
    let mut w = softrod::dynamics::IdDerivatives::new(model);
    w.tensions = Some(DVector::from_column_slice(t));
    let zero = vec![0.0; q.len()];
    softrod::dynamics::inverse_dynamics_derivatives_with(
        model,
        &mut w,
        softrod::dynamics::Forces::at_rest(1.0),
        0.0,
        q,
        &zero,
        &zero,
    )
    .unwrap();
    w.dtau_dq.clone().lu().solve(b).unwrap()
}

/// IS11: a target on the gripper body at the tip of the open arm — its
/// frame's position and orientation from a forward solve — gives back the
/// tensions and the shape.
#[test]
fn body_target_recovers_forward_tensions() {
    let mut s = three_cable_arm(GRIPPER);
    assert_eq!(s.model().bodies()[0].spec.name, "gripper");
    let truth = [0.9, 0.2, 0.6];
    let q = forward(&mut s, &truth);
    let g = s.body_poses(&q).unwrap()[0];
    let tip = s.pose("arm", LENGTH, &q).unwrap();
    // The body's frame is its own, not the tip section's.
    assert!((g.translation - tip.translation).norm() > 0.02);
    let targets = [Target::body_position(0, g.translation.into()).with_rotation(g.rotation)];
    let options = ActuationOptions {
        effort_weight: 0.0,
        ..ActuationOptions::default()
    };
    let a = s
        .solve_actuation(&targets, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(a.converged && a.reached, "{}", a.message);
    for c in 0..3 {
        assert!(
            (a.tensions[c] - truth[c]).abs() < 1e-7,
            "{:?} vs {truth:?}",
            a.tensions
        );
    }
    let dq = (&a.q - DVector::from_vec(q)).amax();
    assert!(dq < 1e-8, "shape off by {dq:e}");
    let r = &a.residuals[0];
    assert!((r.position - g.translation).norm() < 1e-9);
    assert!(r.position_error < 1e-9 && r.rotation_error < 1e-9);
}

/// IS8 + IS11: a body target on a closed model (the gripper's frame, the
/// tip sliding on the x axis).
#[test]
fn body_target_on_a_closed_model() {
    let mut s = three_cable_arm(&format!("{GRIPPER}{SLIDER}"));
    let truth = [0.4, 1.1, 0.7];
    let q = forward(&mut s, &truth);
    let g = s.body_poses(&q).unwrap()[0];
    let mid = s.pose("arm", 0.25, &q).unwrap();
    let targets = [
        Target::body_position(0, g.translation.into()),
        Target::position(0, 0.25, mid.translation.into()),
    ];
    let options = ActuationOptions {
        effort_weight: 0.0,
        ..ActuationOptions::default()
    };
    let a = s
        .solve_actuation(&targets, &options)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(a.converged && a.reached, "{}", a.message);
    for c in 0..3 {
        assert!(
            (a.tensions[c] - truth[c]).abs() < 1e-7,
            "{:?} vs {truth:?}",
            a.tensions
        );
    }
    assert!((&a.q - DVector::from_vec(q)).amax() < 1e-8);
}

/// A body index past the model's bodies: an input error naming the
/// target's element.
#[test]
fn bad_body_target_is_an_input_error() {
    let mut s = three_cable_arm(GRIPPER);
    let e = s
        .solve_actuation(
            &[Target::body_position(1, [0.5, 0.0, 0.0])],
            &ActuationOptions::default(),
        )
        .unwrap_err();
    match &e {
        Error::Actuation { key, message } => {
            assert_eq!(key, "target[0].element", "{e}");
            assert!(message.contains("no body 1"), "{e}");
        }
        other => panic!("{other}"),
    }
}
