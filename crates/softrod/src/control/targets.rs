//! Prescribed-joint targets as inputs: the drive of a prescribed joint
//! (docs/theory.md D59) commanded one control period at a time, as the
//! learning environments do (docs/envs.md, "Actions").
//!
//! **(PT1)** Commanding the target `x₁` over the period `[t₀, t₀ + h]`
//! replaces the coordinate's curve by the cubic Hermite transition
//!
//! ```text
//! x(t) = (2s³ − 3s² + 1) x₀ + (s³ − 2s² + s) h v₀ + (3s² − 2s³) x₁,   s = (t − t₀)/h,
//! ```
//!
//! from the position and rate `(x₀, v₀)` the curve in force gives at `t₀`
//! (the scene's curve before the first command, else the last transition)
//! to `x₁` reached **at rest** at `t₀ + h`, held there at rest afterwards.
//! It is C¹ across period boundaries (the rate is continuous, zero at each
//! period's end once a target has been commanded; the acceleration jumps
//! there, where the integrator restarts anyway), its rate is
//! `6 (x₁ − x₀) s (1 − s) / h` from rest, at most `1.5 (x₁ − x₀)/h` at
//! mid-period, and its acceleration `6 (x₁ − x₀)(1 − 2s)/h²` (from rest):
//! the drive's forces (D60) follow from it.
//!
//! The transition is a [`Spline::hermite`] installed with
//! [`Model::set_prescribed_curve`]; the end of the period is a breakpoint of
//! the model, so the adaptive integrators end a step there.

use softrod_dynamics::{Curve, Model, Spline};

use crate::error::{Error, Result};

/// The commanded motion of one prescribed coordinate over one control
/// period (PT1): from `(x0, v0)` at `t0` to `x1` at rest at `t1`. Plain
/// numbers, so that a record of it (a pickle) rebuilds the same curve to
/// the bit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    /// Start of the period \[s\].
    pub t0: f64,
    /// End of the period \[s\] (`> t0`).
    pub t1: f64,
    /// Position at `t0` (rad or m).
    pub x0: f64,
    /// Rate at `t0` (rad/s or m/s).
    pub v0: f64,
    /// The target, reached at rest at `t1` (rad or m).
    pub x1: f64,
}

impl Transition {
    /// The curve of (PT1).
    ///
    /// Errors: the numbers do not make a curve (times not increasing, a
    /// value that is not finite).
    pub fn curve(&self, name: &str) -> Result<Curve> {
        Spline::hermite(self.t0, self.t1, (self.x0, self.v0), (self.x1, 0.0))
            .map(Curve::Spline)
            .map_err(|message| Error::Actuation {
                key: format!("prescribed target of {name}"),
                message,
            })
    }
}

/// Checks `targets` (one per prescribed coordinate, in
/// `Simulation::prescribed_names` order `names`) against `model`: the count,
/// finite values, and each within its joint's `prescribed.bounds` when the
/// scene gives them. `what` names the argument in messages. Errors name the
/// coordinate (`prescribed_targets[0] (arm.joint.theta)`).
pub fn check_prescribed_targets(
    model: &Model,
    names: &[String],
    what: &str,
    targets: &[f64],
) -> Result<()> {
    let np = model.n_prescribed();
    if np == 0 {
        return Err(Error::Actuation {
            key: what.to_owned(),
            message: "this model has no prescribed joint (give a joint `prescribed = { times, \
                      values, bounds }` in the scene)"
                .into(),
        });
    }
    if targets.len() != np {
        return Err(Error::Actuation {
            key: what.to_owned(),
            message: format!(
                "must have shape ({np},) (one target per prescribed joint coordinate: {names:?}), \
                 got ({},)",
                targets.len()
            ),
        });
    }
    for (i, &x) in targets.iter().enumerate() {
        let key = || format!("{what}[{i}] ({})", names[i]);
        if !x.is_finite() {
            return Err(Error::Actuation {
                key: key(),
                message: format!("{x}: a target must be finite"),
            });
        }
        if let Some([lo, hi]) = model.prescribed_bounds(i) {
            if !(lo..=hi).contains(&x) {
                return Err(Error::Actuation {
                    key: key(),
                    message: format!("{x} is outside the joint's prescribed.bounds [{lo}, {hi}]"),
                });
            }
        }
    }
    Ok(())
}

/// Commands `targets` over `[t, t + dt]` on `model` (PT1): for each
/// prescribed coordinate, the transition from its curve's position and
/// rate at `t` to the target at rest at `t + dt`, installed as its curve.
/// The targets must have passed [`check_prescribed_targets`]. Returns the
/// transitions (written into `out`, cleared first).
///
/// Errors: `t` or `dt` not finite, `dt ≤ 0`.
pub fn command_prescribed_targets(
    model: &mut Model,
    names: &[String],
    t: f64,
    dt: f64,
    targets: &[f64],
    out: &mut Vec<Transition>,
) -> Result<()> {
    if !(t.is_finite() && dt.is_finite() && dt > 0.0) {
        return Err(Error::Actuation {
            key: "dt".into(),
            message: format!("a period needs a finite t and dt > 0, got t = {t}, dt = {dt}"),
        });
    }
    out.clear();
    for (i, &x1) in targets.iter().enumerate() {
        let (x0, v0, _) = model
            .prescribed_curve(i)
            .expect("checked: one target per prescribed coordinate")
            .eval(t);
        out.push(Transition {
            t0: t,
            t1: t + dt,
            x0,
            v0,
            x1,
        });
    }
    install(model, names, out)
}

/// Installs `transitions` (one per prescribed coordinate) as the curves of
/// `model`.
pub fn install(model: &mut Model, names: &[String], transitions: &[Transition]) -> Result<()> {
    for (i, tr) in transitions.iter().enumerate() {
        let curve = tr.curve(&names[i])?;
        model.set_prescribed_curve(i, curve)?;
    }
    Ok(())
}

/// Makes the prescribed curves of `dst` those of `src` (the same model
/// otherwise): a stepper's copy of a model follows its simulation's drive.
pub fn copy_prescribed_curves(src: &Model, dst: &mut Model) -> Result<()> {
    for i in 0..src.n_prescribed() {
        let c = src.prescribed_curve(i).expect("i < n_prescribed");
        if dst.prescribed_curve(i) != Some(c) {
            dst.set_prescribed_curve(i, c.clone())?;
        }
    }
    Ok(())
}
