//! Prescribed-joint targets through the facade
//! (`Simulation::command_prescribed`, docs/envs.md, PT1 of
//! `softrod::control::targets`), against closed forms: the commanded
//! cubic from rest and from a motion in force, and a rigid link's equation
//! of motion about its hinge for the drive's torque along it.

use softrod::{Error, Simulation};

/// A rigid link hinged to the world on a prescribed revolute joint about
/// world y (beside a clamped rod, which a model needs): mass `M`, centre
/// of mass at `ELL` along the link's x, inertia `IC_YY` about it.
const M: f64 = 0.2;
const ELL: f64 = 0.15;
const IC_YY: f64 = 3.0e-4;
const G: f64 = 9.81;

fn link(prescribed: &str) -> Simulation {
    let text = format!(
        "[world]\ngravity = [0.0, 0.0, -{G}]\n\
         [[rod]]\nname = \"post\"\nlength = 0.1\npieces = 1\nstrains = [\"ky\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n\
         [[body]]\nname = \"link\"\nparent = \"world\"\nbase = {{ position = [0.5, 0.0, 0.0] }}\n\
         joint = {{ type = \"revolute\", axis = [0, 1, 0], prescribed = {prescribed} }}\n\
         mass = {M}\ninertia = [2.0e-4, {IC_YY}, 2.0e-4]\ncenter_of_mass = [{ELL}, 0.0, 0.0]\n"
    );
    Simulation::from_toml(&text, "link.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

const HELD: &str = "{ times = [0.0], values = [0.1], bounds = [-1.0, 1.0] }";

/// The cubic Hermite from `(x0, v0)` at 0 to `(x1, 0)` at `h`: value,
/// rate, acceleration at `tau`, written out in the Hermite basis.
fn hermite(x0: f64, v0: f64, x1: f64, h: f64, tau: f64) -> (f64, f64, f64) {
    let s = tau / h;
    let (h00, h10, h01) = (
        2.0 * s.powi(3) - 3.0 * s * s + 1.0,
        s.powi(3) - 2.0 * s * s + s,
        -2.0 * s.powi(3) + 3.0 * s * s,
    );
    let (d00, d10, d01) = (
        6.0 * s * s - 6.0 * s,
        3.0 * s * s - 4.0 * s + 1.0,
        -6.0 * s * s + 6.0 * s,
    );
    let (e00, e10, e01) = (12.0 * s - 6.0, 6.0 * s - 4.0, -12.0 * s + 6.0);
    (
        h00 * x0 + h10 * h * v0 + h01 * x1,
        (d00 * x0 + d10 * h * v0 + d01 * x1) / h,
        (e00 * x0 + e10 * h * v0 + e01 * x1) / (h * h),
    )
}

fn state(s: &Simulation, t: f64) -> (f64, f64, f64) {
    s.model()
        .prescribed_curve(0)
        .expect("one prescribed coordinate")
        .eval(t)
}

fn close(what: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol * want.abs().max(1.0),
        "{what}: {got:e} against {want:e}"
    );
}

#[test]
fn commanded_targets_follow_the_cubic_and_are_held_at_rest() {
    let mut s = link(HELD);
    assert_eq!(s.prescribed_names(), ["link.joint.theta"]);
    let h = 0.05;
    let mut x0 = 0.1;
    for (k, target) in [0.5, -0.2, 0.9].into_iter().enumerate() {
        let t0 = k as f64 * h;
        s.command_prescribed(t0, h, &[target]).unwrap();
        for i in 0..=8 {
            let tau = h * i as f64 / 8.0;
            let (x, v, a) = state(&s, t0 + tau);
            let (xe, ve, ae) = hermite(x0, 0.0, target, h, tau);
            close("value", x, xe, 1e-14);
            close("rate", v, ve, 1e-12);
            close("acceleration", a, ae, 1e-10);
        }
        let (x, v, a) = state(&s, t0 + 3.0 * h);
        assert_eq!(
            (x, v, a),
            (target, 0.0, 0.0),
            "held at rest after the period"
        );
        x0 = target;
    }
    s.reset_prescribed();
    assert_eq!(state(&s, 1.0).0, 0.1, "the scene's curve is back");
}

#[test]
fn a_command_starts_with_the_rate_of_the_motion_in_force() {
    // From a scene sinusoid x = A sin(ωt): C¹ at the period's start.
    let mut s = link("{ sine = { amplitude = 0.3, frequency = 2.0 }, bounds = [-1.0, 1.0] }");
    let (t0, h) = (0.1, 0.04);
    let w = 2.0 * std::f64::consts::PI * 2.0;
    let (x0, v0) = (0.3 * (w * t0).sin(), 0.3 * w * (w * t0).cos());
    s.command_prescribed(t0, h, &[0.25]).unwrap();
    for i in 0..=6 {
        let tau = h * i as f64 / 6.0;
        let (x, v, _) = state(&s, t0 + tau);
        let (xe, ve, _) = hermite(x0, v0, 0.25, h, tau);
        close("value", x, xe, 1e-14);
        close("rate", v, ve, 1e-12);
    }
    // A second command inside the first period starts from where the
    // first one's cubic is, at its rate.
    let t1 = t0 + 0.3 * h;
    let (x1, v1, _) = state(&s, t1);
    s.command_prescribed(t1, h, &[-0.4]).unwrap();
    let (x, v, _) = state(&s, t1);
    close("value at the new start", x, x1, 1e-14);
    close("rate at the new start", v, v1, 1e-12);
    close("end", state(&s, t1 + h).0, -0.4, 1e-15);
}

#[test]
fn the_drive_torque_along_a_command_is_the_links_equation_of_motion() {
    // I θ̈ = τ + m g ℓ cos θ about +y (centre of mass at
    // R_y(θ)(ℓ, 0, 0) = (ℓ cos θ, 0, −ℓ sin θ)), I = Ic + m ℓ².
    let mut s = link(HELD);
    let h = 0.05;
    s.command_prescribed(0.0, h, &[0.7]).unwrap();
    let (q, qd) = {
        let (q, qd) = s.initial_state();
        (q.clone(), qd.clone())
    };
    let inertia = IC_YY + M * ELL * ELL;
    for i in 0..=8 {
        let tau = h * i as f64 / 8.0;
        let (th, _, thdd) = hermite(0.1, 0.0, 0.7, h, tau);
        let want = inertia * thdd - M * G * ELL * th.cos();
        let f = s
            .prescribed_forces(tau, q.as_slice(), qd.as_slice(), None)
            .unwrap();
        close("drive torque", f[0], want, 1e-10);
    }
    // A step through the period runs on the commanded drive, which ends
    // at the target.
    let (q1, _) = s.step(0.0, q.as_slice(), qd.as_slice(), h).unwrap();
    assert!(q1.iter().all(|x| x.is_finite()));
    close("joint at the period's end", state(&s, h).0, 0.7, 1e-15);
}

#[test]
fn bad_targets_are_refused_by_name_and_command_nothing() {
    let mut s = link(HELD);
    let msg = |e: Error| e.to_string();
    let e = msg(s.command_prescribed(0.0, 0.05, &[f64::NAN]).unwrap_err());
    assert!(
        e.contains("link.joint.theta") && e.contains("finite"),
        "{e}"
    );
    let e = msg(s.command_prescribed(0.0, 0.05, &[1.5]).unwrap_err());
    assert!(
        e.contains("link.joint.theta") && e.contains("bounds"),
        "{e}"
    );
    let e = msg(s.command_prescribed(0.0, 0.05, &[0.1, 0.2]).unwrap_err());
    assert!(e.contains("prescribed_targets"), "{e}");
    let e = msg(s.command_prescribed(0.0, 0.0, &[0.2]).unwrap_err());
    assert!(e.contains("dt"), "{e}");
    assert!(s.prescribed_transitions().is_empty(), "nothing commanded");
    assert_eq!(state(&s, 0.5).0, 0.1, "the scene's curve in force");
}
