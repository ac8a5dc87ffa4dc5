//! Point loads as unknowns of inverse statics (docs/theory-control.md
//! IS13) against independent references: a force and tensions of a
//! forward statics solve recovered with the shape (open and with a
//! slider closure), a cantilever's tip
//! force against Euler–Bernoulli `P = 3EIδ/L³` corrected by the known
//! error of piecewise-constant curvature, and the errors of bad input.

use std::f64::consts::PI;

use softrod::control::{ActuationOptions, Bound, Target, UnknownLoad};
use softrod::{Error, Simulation};

const RADIUS: f64 = 0.01;
const YOUNG: f64 = 1.0e6;
const LENGTH: f64 = 0.5;
const PIECES: usize = 10;
/// Cable offset from the centreline \[m\].
const D: f64 = 0.008;

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

fn rod(strains: &str) -> String {
    format!(
        "[[rod]]\nname = \"arm\"\nlength = {LENGTH}\npieces = {PIECES}\nstrains = {strains}\n\
         section = {{ shape = \"circle\", radius = {RADIUS} }}\n\
         material = {{ density = 1000.0, young = {YOUNG}, poisson = 0.5 }}\n"
    )
}

/// The 3-cable arm of `inverse_statics.rs` under gravity, with `extra`
/// scene text (a `[[load]]`) appended.
fn three_cable_arm(extra: &str) -> Simulation {
    let mut text = String::from("[world]\ngravity = [0.0, 0.0, -9.81]\n");
    text.push_str(&rod("[\"kx\", \"ky\", \"kz\", \"qx\"]"));
    for a in [90.0f64, 210.0, 330.0] {
        let (y, z) = (D * a.to_radians().cos(), D * a.to_radians().sin());
        text.push_str(&format!(
            "[[cable]]\nrod = \"arm\"\noffset = [{y}, {z}]\ntension = 0.0\n"
        ));
    }
    text.push_str(extra);
    sim(&text)
}

fn statics_q(s: &mut Simulation) -> Vec<f64> {
    s.statics().unwrap().q.as_slice().to_vec()
}

/// (a) Tensions and a 3D point force of a forward statics solve (the
/// force a scene `[[load]]`, a code path independent of IS13's columns)
/// are recovered from positions of four sections and the tip's
/// orientation, and so is the shape. Six unknowns, fifteen residuals, all
/// determined (the stretch separates equal tensions), so the effort term
/// is off and the answer is exact to the solvers' tolerances.
#[test]
fn recovers_forward_force_tensions_and_shape() {
    const S_LOAD: f64 = 0.35;
    let force = [0.05, -0.08, 0.12];
    let tensions = [1.2, 0.5, 0.2];
    let mut truth = three_cable_arm(&format!(
        "[[load]]\nrod = \"arm\"\ns = {S_LOAD}\nforce = [{}, {}, {}]\nframe = \"world\"\n",
        force[0], force[1], force[2]
    ));
    truth.set_cable_tensions(Some(&tensions)).unwrap();
    let q = statics_q(&mut truth);
    let mut targets = Vec::new();
    for s in [0.15, S_LOAD, 0.42, LENGTH] {
        let g = truth.pose("arm", s, &q).unwrap();
        targets.push(Target::position(0, s, g.translation.into()));
    }
    let tip = truth.pose("arm", LENGTH, &q).unwrap();
    targets[3] = targets[3].clone().with_rotation(tip.rotation);

    let mut s = three_cable_arm("");
    let options = ActuationOptions {
        effort_weight: 0.0,
        unknown_loads: vec![UnknownLoad::new(0, S_LOAD, f64::INFINITY)],
        ..ActuationOptions::default()
    };
    let a = s.solve_actuation(&targets, &options).unwrap();
    assert!(a.converged && a.reached, "{}", a.message);
    for c in 0..3 {
        assert!(
            (a.tensions[c] - tensions[c]).abs() < 1e-7,
            "{:?} vs {tensions:?}",
            a.tensions
        );
    }
    assert_eq!(a.forces.len(), 1);
    for k in 0..3 {
        assert!(
            (a.forces[0][k] - force[k]).abs() < 1e-8,
            "{:?} vs {force:?}",
            a.forces[0]
        );
    }
    let dq = (&a.q - nalgebra::DVector::from_vec(q.clone())).amax();
    // The shape along the whole rod: section positions every L/50.
    let mut dp = 0.0f64;
    for k in 0..=50 {
        let sk = LENGTH * k as f64 / 50.0;
        let want = truth.pose("arm", sk, &q).unwrap().translation;
        let got = s.pose("arm", sk, a.q.as_slice()).unwrap().translation;
        dp = dp.max((got - want).norm());
    }
    // Measured: positions 4e-10 m, q 8.7e-8 (in the coordinates the
    // targets see least; the tensions' own 1e-7 N moves curvatures by
    // ~1e-7 through d/EI ≈ 1 /N).
    assert!(dp < 1e-9, "shape off by {dp:e} m");
    assert!(dq < 2e-7, "coordinates off by {dq:e}");
    assert!(a.bounds.iter().all(|b| *b == Bound::Free));
    assert_eq!(a.force_bounds, vec![[Bound::Free; 3]]);
}

/// A planar cantilever bending about y (inextensible, unshearable, no
/// gravity, no cables).
fn cantilever(extra: &str) -> Simulation {
    let text = rod("[\"ky\"]").replace(
        &format!("young = {YOUNG}"),
        &format!("young = {CANTILEVER_YOUNG}"),
    );
    sim(&format!("{text}{extra}"))
}

/// Stiff enough that the tip force for δ/L = 1e-3 is ~1 N: the solver's
/// step tolerance, `1e-10 (1 + max |x|)` N, is then 1e-10 of it.
const CANTILEVER_YOUNG: f64 = 1.0e10;

/// (b) Only an unknown tip force (x and y held at 0 by their bounds, so
/// the z component is the one unknown) for a tip position in the linear
/// range (δ/L = 1e-3). Two references: the forward statics at a known
/// force, recovered to 1e-9 relative; and Euler–Bernoulli `δ = PL³/3EI`,
/// which piecewise-constant curvature (each piece's curvature the mean of
/// `M/EI` over it, the Galerkin projection on constant strains) shortens by `P Σ h³/12EI` to
/// `δ_N = (PL³/3EI)(1 − 1/4N²)`: the recovered `P` matches
/// `3EIδ/L³ / (1 − 1/4N²)` to the geometric nonlinearity `O((δ/L)²)`.
#[test]
fn cantilever_tip_force_against_euler_bernoulli() {
    let ei = CANTILEVER_YOUNG * PI * RADIUS.powi(4) / 4.0;
    let delta = 1e-3 * LENGTH;
    let bounded = UnknownLoad {
        rod: 0,
        s: LENGTH,
        min: [0.0, 0.0, -10.0],
        max: [0.0, 0.0, 10.0],
    };
    let options = ActuationOptions {
        effort_weight: 0.0,
        unknown_loads: vec![bounded],
        ..ActuationOptions::default()
    };

    // Forward statics at a known force, then recovered.
    let p_true = -3.0 * ei * delta / LENGTH.powi(3);
    let mut fwd = cantilever(&format!(
        "[[load]]\nrod = \"arm\"\ns = {LENGTH}\nforce = [0.0, 0.0, {p_true}]\nframe = \"world\"\n"
    ));
    let q = statics_q(&mut fwd);
    let tip = fwd.pose("arm", LENGTH, &q).unwrap();
    let mut s = cantilever("");
    let a = s
        .solve_actuation(
            &[Target::position(0, LENGTH, tip.translation.into())],
            &options,
        )
        .unwrap();
    assert!(a.converged && a.reached, "{}", a.message);
    let rel = (a.forces[0].z - p_true).abs() / p_true.abs();
    assert!(
        rel < 1e-9,
        "forward force off by {rel:e} ({} iterations)",
        a.iterations
    );
    assert_eq!(a.forces[0].x, 0.0);
    assert_eq!(a.forces[0].y, 0.0);
    // min = max = 0: at a bound (the lower one is reported first).
    assert_ne!(a.force_bounds[0][0], Bound::Free);

    // Euler–Bernoulli: the tip at z = −δ and x at the bent cantilever's
    // foreshortening `3δ²/5L` (second order: 3e-7 m here), so that the
    // target is reachable and the fit exact.
    let x_tip = LENGTH - 0.6 * delta * delta / LENGTH;
    let a = s
        .solve_actuation(
            &[Target::position(0, LENGTH, [x_tip, 0.0, -delta])],
            &options,
        )
        .unwrap();
    assert!(a.converged, "{}", a.message);
    let n = PIECES as f64;
    let p_eb = 3.0 * ei * delta / LENGTH.powi(3);
    let p_pcs = p_eb / (1.0 - 1.0 / (4.0 * n * n));
    let rel = (-a.forces[0].z - p_pcs).abs() / p_pcs;
    assert!(
        rel < 1e-5,
        "tip force {} vs PCS-corrected Euler–Bernoulli {p_pcs} (plain {p_eb}): {rel:e}",
        -a.forces[0].z
    );
    assert!(a.residuals[0].position_error < 1e-7 * LENGTH);
}

/// (a) on a closed model (IS13 with IS9's bordered system): the tip of
/// the arm slides on the world's x axis; tensions and a 3D force at
/// `s = 0.3` of a forward constrained statics solve are recovered from
/// four section positions, and so is the shape.
#[test]
fn closed_arm_recovers_forward_force() {
    const SLIDER: &str = "[[closure]]\ntype = \"slider\"\naxis = [1, 0, 0]\n\
                          a = { element = \"arm\" }\nb = { element = \"world\" }\n";
    const S_LOAD: f64 = 0.3;
    let force = [0.04, 0.06, -0.1];
    let tensions = [1.2, 0.5, 0.2];
    let mut truth = three_cable_arm(&format!(
        "{SLIDER}[[load]]\nrod = \"arm\"\ns = {S_LOAD}\nforce = [{}, {}, {}]\nframe = \"world\"\n",
        force[0], force[1], force[2]
    ));
    truth.set_cable_tensions(Some(&tensions)).unwrap();
    let q = statics_q(&mut truth);
    let targets: Vec<Target> = [0.15, S_LOAD, 0.42, LENGTH]
        .iter()
        .map(|&s| Target::position(0, s, truth.pose("arm", s, &q).unwrap().translation.into()))
        .collect();
    let mut s = three_cable_arm(SLIDER);
    let options = ActuationOptions {
        effort_weight: 0.0,
        unknown_loads: vec![UnknownLoad::new(0, S_LOAD, 10.0)],
        ..ActuationOptions::default()
    };
    let a = s.solve_actuation(&targets, &options).unwrap();
    assert!(a.converged && a.reached, "{}", a.message);
    for c in 0..3 {
        assert!(
            (a.tensions[c] - tensions[c]).abs() < 1e-7,
            "{:?} vs {tensions:?}",
            a.tensions
        );
    }
    for k in 0..3 {
        assert!(
            (a.forces[0][k] - force[k]).abs() < 1e-8,
            "{:?} vs {force:?}",
            a.forces[0]
        );
    }
    let mut dp = 0.0f64;
    for k in 0..=50 {
        let sk = LENGTH * k as f64 / 50.0;
        let want = truth.pose("arm", sk, &q).unwrap().translation;
        let got = s.pose("arm", sk, a.q.as_slice()).unwrap().translation;
        dp = dp.max((got - want).norm());
    }
    assert!(
        dp < 1e-9,
        "shape off by {dp:e} m ({} iterations)",
        a.iterations
    );
}

/// Bad unknown loads: an error naming the key.
#[test]
fn bad_unknown_loads_are_named() {
    let s = cantilever("");
    let target = [Target::position(0, LENGTH, [LENGTH, 0.0, -1e-3])];
    let key = |u: UnknownLoad| match s.clone().solve_actuation(
        &target,
        &ActuationOptions {
            unknown_loads: vec![u],
            ..ActuationOptions::default()
        },
    ) {
        Err(Error::Actuation { key, .. }) => key,
        other => panic!("expected an input error, got {other:?}"),
    };
    assert_eq!(
        key(UnknownLoad::new(0, LENGTH, -1.0)),
        "unknown_load[0].max[0]"
    );
    assert_eq!(
        key(UnknownLoad::new(0, LENGTH, f64::NAN)),
        "unknown_load[0].min[0]"
    );
    let mut u = UnknownLoad::new(0, LENGTH, 1.0);
    u.max[2] = f64::NAN;
    assert_eq!(key(u), "unknown_load[0].max[2]");
    assert_eq!(
        key(UnknownLoad::new(0, 2.0 * LENGTH, 1.0)),
        "unknown_load[0].s"
    );
    assert_eq!(key(UnknownLoad::new(4, LENGTH, 1.0)), "unknown_load[0].rod");
    // No cables and no unknown loads: nothing to solve for.
    match s
        .clone()
        .solve_actuation(&target, &ActuationOptions::default())
    {
        Err(Error::Actuation { key, .. }) => assert_eq!(key, "cable"),
        other => panic!("expected an input error, got {other:?}"),
    }
}
