//! Inverse statics (`Simulation::solve_actuation`, docs/theory-control.md
//! IS1–IS12) against independent references: tensions of a forward statics
//! solve recovered, the constant-curvature law `κ = T d / EI` of a cable at
//! constant offset, the nearest reachable point of a dense scan of
//! tensions, the least-effort point of a redundant family known in closed
//! form, and the errors of bad input.

use std::f64::consts::PI;

use softrod::control::{Actuation, ActuationOptions, Bound, Target};
use softrod::{Error, Simulation};

const RADIUS: f64 = 0.01;
const YOUNG: f64 = 1.0e6;
const LENGTH: f64 = 0.5;
/// Cable offset from the centreline \[m\].
const D: f64 = 0.008;

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// A 10-piece arm with three cables at 120° around the centreline.
fn three_cable_arm(strains: &str, gravity: bool) -> Simulation {
    let mut text = String::new();
    if gravity {
        text.push_str("[world]\ngravity = [0.0, 0.0, -9.81]\n");
    }
    text.push_str(&format!(
        "[[rod]]\nname = \"arm\"\nlength = {LENGTH}\npieces = 10\nstrains = {strains}\n\
         section = {{ shape = \"circle\", radius = {RADIUS} }}\n\
         material = {{ density = 1000.0, young = {YOUNG}, poisson = 0.5 }}\n"
    ));
    for a in [90.0f64, 210.0, 330.0] {
        let (y, z) = (D * a.to_radians().cos(), D * a.to_radians().sin());
        text.push_str(&format!(
            "[[cable]]\nrod = \"arm\"\noffset = [{y}, {z}]\ntension = 0.0\n"
        ));
    }
    sim(&text)
}

/// A planar arm bending about y only (inextensible, unshearable), one
/// cable at constant offset `D` along local z, no gravity.
fn planar_arm() -> Simulation {
    sim(&format!(
        "[[rod]]\nname = \"arm\"\nlength = {LENGTH}\npieces = 10\nstrains = [\"ky\"]\n\
         section = {{ shape = \"circle\", radius = {RADIUS} }}\n\
         material = {{ density = 1000.0, young = {YOUNG}, poisson = 0.5 }}\n\
         [[cable]]\nrod = \"arm\"\noffset = [0.0, {D}]\ntension = 0.0\n"
    ))
}

fn ei() -> f64 {
    YOUNG * PI * RADIUS.powi(4) / 4.0
}

/// Tip of the planar arm bent to uniform curvature `κ` about y: the arc
/// `(sin κL/κ, 0, −(1 − cos κL)/κ)` (bending about +y turns x toward −z).
fn arc_tip(kappa: f64) -> [f64; 3] {
    [
        (kappa * LENGTH).sin() / kappa,
        0.0,
        -(1.0 - (kappa * LENGTH).cos()) / kappa,
    ]
}

/// Forward statics at tensions `t`: the equilibrium `q`.
fn forward(s: &mut Simulation, t: &[f64]) -> Vec<f64> {
    s.set_cable_tensions(Some(t)).unwrap();
    let q = s.statics().unwrap().q.as_slice().to_vec();
    s.set_cable_tensions(None).unwrap();
    q
}

fn solve(s: &mut Simulation, targets: &[Target], options: &ActuationOptions) -> Actuation {
    s.solve_actuation(targets, options)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// (1) Tensions of a forward statics solve under gravity are recovered
/// from the tip pose and the midpoint it produced, and so is the shape.
/// The stretch makes the three tensions determined (equal tensions
/// compress the arm), so the effort term is off and the answer is exact
/// up to the solvers' tolerances (statics 1e-12 relative, steps 1e-10).
#[test]
fn recovers_forward_tensions_and_shape() {
    const T_TOL: f64 = 1e-7; // N, tensions of order 1 N
    const Q_TOL: f64 = 1e-8;
    let mut s = three_cable_arm("[\"kx\", \"ky\", \"kz\", \"qx\"]", true);
    let truth = [1.2, 0.5, 0.2];
    let q = forward(&mut s, &truth);
    let tip = s.pose("arm", LENGTH, &q).unwrap();
    let mid = s.pose("arm", 0.25, &q).unwrap();
    let targets = [
        Target::position(0, LENGTH, tip.translation.into()).with_rotation(tip.rotation),
        Target::position(0, 0.25, mid.translation.into()),
    ];
    let options = ActuationOptions {
        effort_weight: 0.0,
        ..ActuationOptions::default()
    };
    let a = solve(&mut s, &targets, &options);
    assert!(a.converged && a.reached, "{}", a.message);
    for c in 0..3 {
        assert!(
            (a.tensions[c] - truth[c]).abs() < T_TOL,
            "{:?} vs {truth:?}",
            a.tensions
        );
    }
    let dq = (&a.q - nalgebra::DVector::from_vec(q)).amax();
    assert!(dq < Q_TOL, "shape off by {dq:e}");
    assert!(a.bounds.iter().all(|b| *b == Bound::Free));
    assert!(a.residuals[0].position_error < 1e-9 && a.residuals[0].rotation_error < 1e-9);
}

/// Without stretch the three tensions are redundant: equal tensions add a
/// force along the centreline that no strain responds to, so every
/// `T_true + c(1, 1, 1)` gives the same shape. The least-effort member in
/// `T ≥ 0` is `T_true − min(T_true)` (the norm falls as `c` falls until a
/// tension hits 0), which the solver must return to the accuracy the
/// effort weight allows: `JᵀJ` carries round-off of 1e-16 of its largest
/// eigenvalue, the effort term is 1e-9 of it, so ~1e-7 relative.
#[test]
fn redundant_cables_take_the_least_effort() {
    const T_TOL: f64 = 1e-6;
    let mut s = three_cable_arm("[\"ky\", \"kz\"]", false);
    let truth = [1.3, 0.6, 0.3];
    let q = forward(&mut s, &truth);
    let tip = s.pose("arm", LENGTH, &q).unwrap();
    let targets = [Target::position(0, LENGTH, tip.translation.into())];
    let a = solve(&mut s, &targets, &ActuationOptions::default());
    assert!(a.converged && a.reached, "{}", a.message);
    let want = [1.0, 0.3, 0.0];
    for c in 0..3 {
        assert!(
            (a.tensions[c] - want[c]).abs() < T_TOL,
            "{:?} vs {want:?}",
            a.tensions
        );
    }
    assert_eq!(a.bounds[2], Bound::Lower);
}

/// (2) One cable at constant offset `d` in a planar arm without gravity
/// bends it to the uniform curvature `κ = −T d / EI` (the moment `T d` is
/// the same at every section; negative about y for a cable on +z), so the
/// tension that puts the tip on the arc of curvature `κ*` is
/// `T* = −κ* EI / d` in closed form.
#[test]
fn constant_offset_cable_gives_the_closed_form_tension() {
    const T_TOL: f64 = 1e-9; // relative
    let mut s = planar_arm();
    for kappa in [-0.5, -2.0, -5.0] {
        let want = -kappa * ei() / D;
        let targets = [Target::position(0, LENGTH, arc_tip(kappa))];
        let options = ActuationOptions {
            effort_weight: 0.0,
            ..ActuationOptions::default()
        };
        let a = solve(&mut s, &targets, &options);
        assert!(a.converged && a.reached, "{}", a.message);
        let rel = (a.tensions[0] - want).abs() / want;
        assert!(
            rel < T_TOL,
            "κ = {kappa}: T = {} vs {want} ({rel:e})",
            a.tensions[0]
        );
        for v in a.q.iter() {
            assert!((v - kappa).abs() < 1e-9 * kappa.abs(), "q = {}", a.q);
        }
    }
}

/// The reported rotation error resolves small angles: the tip target of
/// the closed-form test above, turned by `α = 1e-8` rad about the tip's own
/// axis — a twist the planar arm cannot make, so `α` is what remains, and
/// the tension is still the closed form's. (The angle from `acos` of the
/// trace read 0 here: `cos α = 1 − 5e-17` rounds to 1.)
#[test]
fn a_small_rotation_error_is_reported_as_it_is() {
    use nalgebra::{Rotation3, Vector3};
    let mut s = planar_arm();
    let (kappa, alpha) = (-2.0, 1e-8);
    let rotation = Rotation3::from_axis_angle(&Vector3::y_axis(), kappa * LENGTH)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), alpha);
    let targets = [Target::position(0, LENGTH, arc_tip(kappa)).with_rotation(*rotation.matrix())];
    let options = ActuationOptions {
        effort_weight: 0.0,
        ..ActuationOptions::default()
    };
    let a = solve(&mut s, &targets, &options);
    assert!(a.converged, "{}", a.message);
    let want = -kappa * ei() / D;
    assert!((a.tensions[0] - want).abs() < 1e-9 * want, "{a:?}");
    let e = a.residuals[0].rotation_error;
    assert!(
        (e - alpha).abs() < 1e-6 * alpha,
        "rotation error {e:e}, want {alpha:e}"
    );
}

/// (3) A target off the arm's one-parameter workspace: the solver's point
/// is the nearest of a dense scan of `T ∈ [0, T_max]` (2001 forward statics
/// solves), and the result says the target is not reachable.
#[test]
fn unreachable_target_gives_the_nearest_reachable_point() {
    let mut s = planar_arm();
    let t_max = 3.0;
    // Off the one-parameter workspace (the tips of the arcs κ ∈ [−3.06, 0]):
    // 3 cm from the tip at κ = −1.5 along the workspace curve's normal, so
    // the nearest workspace point is inside the range.
    let (a, b) = (arc_tip(-1.5 - 1e-4), arc_tip(-1.5 + 1e-4));
    let (tx, tz) = (b[0] - a[0], b[2] - a[2]);
    let norm = tx.hypot(tz);
    let p0 = arc_tip(-1.5);
    let target = [p0[0] - 0.03 * tz / norm, 0.0, p0[2] + 0.03 * tx / norm];
    let n = 2001;
    let mut best = (f64::INFINITY, 0.0);
    for k in 0..n {
        let t = t_max * k as f64 / (n - 1) as f64;
        let q = forward(&mut s, &[t]);
        let p = s.pose("arm", LENGTH, &q).unwrap().translation;
        let dist = ((p[0] - target[0]).powi(2) + (p[2] - target[2]).powi(2)).sqrt();
        if dist < best.0 {
            best = (dist, t);
        }
    }
    let spacing = t_max / (n - 1) as f64;
    assert!(
        best.1 > spacing && best.1 < t_max - spacing,
        "scan optimum {best:?} at a bound"
    );
    let options = ActuationOptions {
        max_tension: vec![t_max],
        ..ActuationOptions::default()
    };
    let a = solve(&mut s, &[Target::position(0, LENGTH, target)], &options);
    assert!(a.converged && !a.reached, "{}", a.message);
    assert!(a.message.contains("not reachable"), "{}", a.message);
    let err = a.residuals[0].position_error;
    // Never worse than the scan, and no better than the scan can resolve:
    // within the distance change of one scan step (|dp/dT| ≤ 0.2 m/N here).
    assert!(err <= best.0 + 1e-12, "{err} vs scan {}", best.0);
    assert!(best.0 - err < 0.2 * spacing, "{err} vs scan {}", best.0);
    assert!(
        (a.tensions[0] - best.1).abs() <= spacing,
        "{} vs {}",
        a.tensions[0],
        best.1
    );
    assert_eq!(a.bounds, vec![Bound::Free]);
}

/// (4) Targets that need more than `T_max`, or a cable that pushes, end at
/// the bound, reported as such, with the bound's shape (the arc of
/// `κ = −T_max d / EI`, or straight).
#[test]
fn bounds_are_reported_when_active() {
    let mut s = planar_arm();
    let t_max = 1.0;
    let kappa_max = -t_max * D / ei();
    let options = ActuationOptions {
        max_tension: vec![t_max],
        ..ActuationOptions::default()
    };
    let far = Target::position(0, LENGTH, arc_tip(1.5 * kappa_max));
    let a = solve(&mut s, &[far], &options);
    assert!(a.converged && !a.reached, "{}", a.message);
    assert_eq!(a.bounds, vec![Bound::Upper]);
    assert_eq!(a.tensions[0], t_max);
    assert!(a.message.contains("upper bound"), "{}", a.message);
    let tip = a.residuals[0].position;
    let want = arc_tip(kappa_max);
    assert!(
        (0..3).all(|c| (tip[c] - want[c]).abs() < 1e-10),
        "{tip:?} vs {want:?}"
    );
    // Bending the other way needs a push.
    let push = Target::position(0, LENGTH, arc_tip(-kappa_max));
    let a = solve(&mut s, &[push], &options);
    assert!(a.converged && !a.reached, "{}", a.message);
    assert_eq!(a.bounds, vec![Bound::Lower]);
    assert_eq!(a.tensions[0], 0.0);
}

/// A warm start from a nearby solution converges in a few iterations to
/// the same answer as a cold start.
#[test]
fn warm_start_from_a_nearby_target() {
    let mut s = three_cable_arm("[\"kx\", \"ky\", \"kz\", \"qx\"]", true);
    let q = forward(&mut s, &[1.0, 0.4, 0.1]);
    let tip = s.pose("arm", LENGTH, &q).unwrap().translation;
    let first = solve(
        &mut s,
        &[Target::position(0, LENGTH, tip.into())],
        &ActuationOptions::default(),
    );
    assert!(first.converged && first.reached, "{}", first.message);
    let moved = [tip[0] - 0.002, tip[1] + 0.003, tip[2] + 0.001];
    let cold = solve(
        &mut s,
        &[Target::position(0, LENGTH, moved)],
        &ActuationOptions::default(),
    );
    let warm = solve(
        &mut s,
        &[Target::position(0, LENGTH, moved)],
        &ActuationOptions::default().warm_start(&first),
    );
    assert!(warm.converged && warm.reached, "{}", warm.message);
    assert!(warm.iterations <= 4, "{} iterations", warm.iterations);
    assert!(warm.iterations < cold.iterations);
    assert!((&warm.tensions - &cold.tensions).amax() < 1e-6);
}

/// (5) Bad input: each refusal names the key.
#[test]
fn bad_input_names_the_key() {
    let mut s = planar_arm();
    let ok = Target::position(0, LENGTH, [0.4, 0.0, -0.1]);
    let key = |targets: &[Target], options: &ActuationOptions| match s
        .clone()
        .solve_actuation(targets, options)
    {
        Err(Error::Actuation { key, .. }) => key,
        other => panic!("expected an input error, got {other:?}"),
    };
    let d = ActuationOptions::default();
    assert_eq!(key(&[], &d), "target");
    let mut t = ok.clone();
    t.rod = 3;
    assert_eq!(key(&[t], &d), "target[0].element");
    let mut t = ok.clone();
    t.s = 0.6;
    assert_eq!(key(&[ok.clone(), t], &d), "target[1].s");
    let mut t = ok.clone();
    t.position = Some([0.1, f64::NAN, 0.0].into());
    assert_eq!(key(&[t], &d), "target[0].position[1]");
    assert_eq!(key(&[ok.clone().with_weight(-1.0)], &d), "target[0].weight");
    let neg = ActuationOptions {
        max_tension: vec![-1.0],
        ..ActuationOptions::default()
    };
    assert_eq!(key(std::slice::from_ref(&ok), &neg), "cable[0].max_tension");
    let nan = ActuationOptions {
        max_tension: vec![f64::NAN],
        ..ActuationOptions::default()
    };
    assert_eq!(key(std::slice::from_ref(&ok), &nan), "cable[0].max_tension");
    let e = s.solve_actuation(&[], &d).unwrap_err();
    assert!(e.is_input());
}
