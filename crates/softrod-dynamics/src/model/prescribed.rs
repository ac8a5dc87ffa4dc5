//! Prescribed joint motion (docs/theory.md §11, D59): a joint coordinate
//! that is a given C² function of time instead of a degree of freedom — a
//! moving or driven base, a driven clamp.
//!
//! Two kinds of curve, one per coordinate:
//! - a cubic spline through samples `(t_i, x_i)` with *not-a-knot* end
//!   conditions (the third derivative is continuous at `t_1` and
//!   `t_{n−2}`): C² everywhere inside `[t_0, t_{n−1}]`, and exact for every
//!   polynomial of degree ≤ 3 — a constant acceleration `x = ½at²` given by
//!   three or more samples is reproduced exactly. Two samples give the
//!   straight line, three the parabola, one a constant. Outside the sampled
//!   interval the coordinate holds its end value (rate and acceleration
//!   zero): C² there only if the curve ends at rest.
//! - a sinusoid `x(t) = c + A sin(2πft + φ)`, with exact derivatives.

use crate::error::DynamicsError;

/// One prescribed coordinate as a function of time: value, rate and
/// acceleration in the joint's units (rad or m, per s, per s²).
#[derive(Clone, Debug, PartialEq)]
pub enum Curve {
    /// Not-a-knot cubic spline through samples (see the module
    /// documentation).
    Spline(Spline),
    /// `offset + amplitude · sin(2π frequency t + phase)`.
    Sine {
        /// `A` (rad or m).
        amplitude: f64,
        /// `f` \[Hz\].
        frequency: f64,
        /// `φ` \[rad\].
        phase: f64,
        /// `c` (rad or m).
        offset: f64,
    },
}

impl Curve {
    /// `(x, ẋ, ẍ)` at time `t` \[s\].
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        match self {
            Curve::Spline(s) => s.eval(t),
            Curve::Sine {
                amplitude,
                frequency,
                phase,
                offset,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency;
                let (s, c) = (w * t + phase).sin_cos();
                (
                    offset + amplitude * s,
                    amplitude * w * c,
                    -amplitude * w * w * s,
                )
            }
        }
    }

    /// Checks the parameters of a sinusoid (a spline is checked when
    /// built): finite, frequency ≥ 0.
    fn validate(&self) -> Result<(), String> {
        if let Curve::Sine {
            amplitude,
            frequency,
            phase,
            offset,
        } = self
        {
            for (what, v) in [
                ("amplitude", amplitude),
                ("frequency", frequency),
                ("phase", phase),
                ("offset", offset),
            ] {
                if !v.is_finite() {
                    return Err(format!("{what} = {v} is not finite"));
                }
            }
            if *frequency < 0.0 {
                return Err(format!("frequency = {frequency} must be >= 0"));
            }
        }
        Ok(())
    }
}

/// A cubic spline with not-a-knot end conditions: knots `t_i` (strictly
/// increasing), values `x_i` and second derivatives `m_i` at the knots.
#[derive(Clone, Debug, PartialEq)]
pub struct Spline {
    t: Vec<f64>,
    x: Vec<f64>,
    m: Vec<f64>,
}

impl Spline {
    /// The spline through `(times[i], values[i])`.
    ///
    /// Errors (as text, for the caller to name the key): no sample, lengths
    /// that differ, a value that is not finite, times not strictly
    /// increasing.
    pub fn new(times: &[f64], values: &[f64]) -> Result<Self, String> {
        let n = times.len();
        if n == 0 {
            return Err("needs at least one sample".into());
        }
        if values.len() != n {
            return Err(format!("{} times but {} values", n, values.len()));
        }
        for (i, (t, x)) in times.iter().zip(values).enumerate() {
            if !t.is_finite() {
                return Err(format!("times[{i}] = {t} is not finite"));
            }
            if !x.is_finite() {
                return Err(format!("values[{i}] = {x} is not finite"));
            }
            if i > 0 && *t <= times[i - 1] {
                return Err(format!(
                    "times must increase strictly: times[{i}] = {t} after {}",
                    times[i - 1]
                ));
            }
        }
        let m = match n {
            1 | 2 => vec![0.0; n],
            // The parabola through three points: one constant second
            // derivative (the not-a-knot spline of three points).
            3 => {
                let d0 = (values[1] - values[0]) / (times[1] - times[0]);
                let d1 = (values[2] - values[1]) / (times[2] - times[1]);
                vec![2.0 * (d1 - d0) / (times[2] - times[0]); 3]
            }
            _ => not_a_knot(times, values)?,
        };
        Ok(Self {
            t: times.to_vec(),
            x: values.to_vec(),
            m,
        })
    }

    /// The one cubic on `[t0, t1]` with the end values and rates
    /// `x(t0) = x0`, `ẋ(t0) = v0`, `x(t1) = x1`, `ẋ(t1) = v1` (cubic Hermite
    /// interpolation), held at `x1` at rest after `t1` and at `x0` at rest
    /// before `t0` like any spline. In this form's second derivatives at
    /// the two knots, with `h = t1 − t0` and `d = (x1 − x0)/h`, the end
    /// rates give `2m0 + m1 = 6(d − v0)/h` and `m0 + 2m1 = 6(v1 − d)/h`.
    ///
    /// Errors (as text): `t1 ≤ t0`, a value that is not finite.
    pub fn hermite(
        t0: f64,
        t1: f64,
        (x0, v0): (f64, f64),
        (x1, v1): (f64, f64),
    ) -> Result<Self, String> {
        for (what, v) in [
            ("t0", t0),
            ("t1", t1),
            ("x0", x0),
            ("v0", v0),
            ("x1", x1),
            ("v1", v1),
        ] {
            if !v.is_finite() {
                return Err(format!("{what} = {v} is not finite"));
            }
        }
        if t1 <= t0 {
            return Err(format!("t1 = {t1} must come after t0 = {t0}"));
        }
        let h = t1 - t0;
        let d = (x1 - x0) / h;
        let a = 6.0 * (d - v0) / h;
        let b = 6.0 * (v1 - d) / h;
        let (m0, m1) = ((2.0 * a - b) / 3.0, (2.0 * b - a) / 3.0);
        if !(m0.is_finite() && m1.is_finite()) {
            return Err(format!("the cubic over [{t0}, {t1}] is not finite"));
        }
        Ok(Self {
            t: vec![t0, t1],
            x: vec![x0, x1],
            m: vec![m0, m1],
        })
    }

    /// The sample times \[s\].
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// The sample values (rad or m).
    pub fn values(&self) -> &[f64] {
        &self.x
    }

    /// First and last knot \[s\].
    pub fn span(&self) -> (f64, f64) {
        (self.t[0], self.t[self.t.len() - 1])
    }

    /// `(x, ẋ, ẍ)` at `t`; outside `[t_0, t_{n−1}]`, the end value at rest.
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        let n = self.t.len();
        if n == 1 || t < self.t[0] {
            return (self.x[0], 0.0, 0.0);
        }
        if t > self.t[n - 1] {
            return (self.x[n - 1], 0.0, 0.0);
        }
        // The interval [t_i, t_{i+1}] holding t (the closed end intervals
        // include the end knots: the curve's own rates there).
        let i = (self.t.partition_point(|&k| k <= t) - 1).min(n - 2);
        let h = self.t[i + 1] - self.t[i];
        let (a, b) = (self.t[i + 1] - t, t - self.t[i]);
        let (m0, m1) = (self.m[i], self.m[i + 1]);
        let (x0, x1) = (self.x[i], self.x[i + 1]);
        let x = (m0 * a * a * a + m1 * b * b * b) / (6.0 * h)
            + (x0 / h - m0 * h / 6.0) * a
            + (x1 / h - m1 * h / 6.0) * b;
        let v = (-m0 * a * a + m1 * b * b) / (2.0 * h) + (x1 - x0) / h - (m1 - m0) * h / 6.0;
        let acc = (m0 * a + m1 * b) / h;
        (x, v, acc)
    }
}

/// Second derivatives of the not-a-knot spline (n ≥ 4): the interior
/// continuity equations
/// `h_{i−1}m_{i−1} + 2(h_{i−1}+h_i)m_i + h_i m_{i+1} = 6(d_i − d_{i−1})`
/// with `m_0`, `m_{n−1}` eliminated by the end conditions
/// `(m_1 − m_0)/h_0 = (m_2 − m_1)/h_1` (and its mirror), a tridiagonal
/// system in `m_1 … m_{n−2}` solved by elimination.
fn not_a_knot(t: &[f64], x: &[f64]) -> Result<Vec<f64>, String> {
    let n = t.len();
    let h: Vec<f64> = (0..n - 1).map(|i| t[i + 1] - t[i]).collect();
    let d: Vec<f64> = (0..n - 1).map(|i| (x[i + 1] - x[i]) / h[i]).collect();
    let k = n - 2;
    let mut lo = vec![0.0; k];
    let mut di = vec![0.0; k];
    let mut up = vec![0.0; k];
    let mut r = vec![0.0; k];
    for j in 0..k {
        let i = j + 1;
        lo[j] = h[i - 1];
        di[j] = 2.0 * (h[i - 1] + h[i]);
        up[j] = h[i];
        r[j] = 6.0 * (d[i] - d[i - 1]);
    }
    // m_0 = (1 + h0/h1) m_1 − (h0/h1) m_2 into the first equation.
    let q0 = h[0] / h[1];
    di[0] += lo[0] * (1.0 + q0);
    up[0] -= lo[0] * q0;
    // m_{n−1} = (1 + h_{n−2}/h_{n−3}) m_{n−2} − (h_{n−2}/h_{n−3}) m_{n−3}.
    let q1 = h[n - 2] / h[n - 3];
    di[k - 1] += up[k - 1] * (1.0 + q1);
    lo[k - 1] -= up[k - 1] * q1;
    // Thomas elimination (k ≥ 2).
    for j in 1..k {
        if di[j - 1] == 0.0 {
            return Err("the spline's equations are singular".into());
        }
        let f = lo[j] / di[j - 1];
        di[j] -= f * up[j - 1];
        r[j] -= f * r[j - 1];
    }
    let mut m = vec![0.0; n];
    for j in (0..k).rev() {
        let next = if j + 1 < k { m[j + 2] } else { 0.0 };
        let v = (r[j] - up[j] * next) / di[j];
        if !v.is_finite() {
            return Err("the spline's equations are singular".into());
        }
        m[j + 1] = v;
    }
    m[0] = (1.0 + q0) * m[1] - q0 * m[2];
    m[n - 1] = (1.0 + q1) * m[n - 2] - q1 * m[n - 3];
    Ok(m)
}

impl crate::model::Model {
    /// The curve of prescribed coordinate `i` (model order, the order of
    /// [`crate::Data::prescribed_q`]), `None` past the last.
    pub fn prescribed_curve(&self, i: usize) -> Option<&Curve> {
        let e = self
            .elements
            .iter()
            .find(|e| e.prescribed_dofs.contains(&i))?;
        let p = e.attachment.joint.prescribed.as_ref()?;
        p.curves.get(i - e.prescribed_dofs.start)
    }

    /// The target bounds `[lo, hi]` of prescribed coordinate `i` (the
    /// scene's `prescribed.bounds`), `None` when its joint has none or
    /// past the last coordinate.
    pub fn prescribed_bounds(&self, i: usize) -> Option<[f64; 2]> {
        let e = self
            .elements
            .iter()
            .find(|e| e.prescribed_dofs.contains(&i))?;
        let p = e.attachment.joint.prescribed.as_ref()?;
        p.bounds.as_ref()?.get(i - e.prescribed_dofs.start).copied()
    }

    /// Replaces the curve of prescribed coordinate `i` (model order): a
    /// drive commanded while the model runs (the learning environments'
    /// prescribed-joint targets). The layout of `q` does not change, nor the
    /// tree: only the motion the coordinate follows. Errors: no prescribed
    /// coordinate `i`, a sinusoid with parameters that are not finite.
    pub fn set_prescribed_curve(&mut self, i: usize, curve: Curve) -> Result<(), DynamicsError> {
        let n = self.n_prescribed;
        let e = self
            .elements
            .iter_mut()
            .find(|e| e.prescribed_dofs.contains(&i))
            .ok_or(DynamicsError::InvalidJoint {
                element: String::new(),
                reason: format!("no prescribed coordinate {i} (the model has {n})"),
            })?;
        curve
            .validate()
            .map_err(|reason| DynamicsError::InvalidJoint {
                element: e.name.clone(),
                reason: format!("prescribed motion: {reason}"),
            })?;
        let k = i - e.prescribed_dofs.start;
        let p = e
            .attachment
            .joint
            .prescribed
            .as_mut()
            .expect("an element with prescribed coordinates has a prescribed joint");
        p.curves[k] = curve;
        Ok(())
    }
}

impl Curve {
    /// The times where the motion's rate or acceleration may jump \[s\]: a
    /// spline's first and last sample times, where it starts from and
    /// returns to holding its end values (a drive that stops moving there
    /// is an impulse unless its rate is zero). A sinusoid has none.
    pub fn breakpoints(&self) -> Vec<f64> {
        match self {
            Curve::Spline(s) if s.t.len() > 1 => vec![s.t[0], s.t[s.t.len() - 1]],
            _ => Vec::new(),
        }
    }
}

impl crate::model::Model {
    /// The times where a drive of the model changes abruptly, sorted and
    /// without repeats \[s\]: the ends of the prescribed joints' spline
    /// curves ([`Curve::breakpoints`]), the times of the cables' tension
    /// tables (piecewise linear, [`softrod_mechanics::Tension::breakpoints`])
    /// and of the joint actuators' force tables.
    /// The solution is not smooth there; an adaptive integrator ends its
    /// steps at these times instead of stepping across them
    /// (`softrod_integrate::Options::breakpoints`).
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut times: Vec<f64> = self
            .elements
            .iter()
            .filter_map(|e| e.attachment.joint.prescribed.as_ref())
            .flat_map(|p| p.curves.iter().flat_map(Curve::breakpoints))
            .chain(self.rods.iter().flat_map(|r| {
                r.spec
                    .cables
                    .iter()
                    .flat_map(|c| c.tension.breakpoints().iter().copied())
            }))
            .chain(
                self.elements
                    .iter()
                    .filter_map(|e| e.attachment.joint.actuator.as_ref())
                    .flat_map(|a| a.force.breakpoints().iter().copied()),
            )
            .collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        times
    }
}

/// The prescribed motion of a joint: one curve per joint coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Prescribed {
    /// One curve per coordinate of the joint, in the joint's order.
    pub curves: Vec<Curve>,
    /// The range `[lo, hi]` (rad or m) of each coordinate a commanded
    /// target may take (the scene's `prescribed.bounds`), or `None`: no
    /// range given. Not a constraint on the curves: the bounds of the
    /// actions that set targets (docs/envs.md).
    pub bounds: Option<Vec<[f64; 2]>>,
}

impl Prescribed {
    /// One curve per coordinate, no bounds.
    pub fn new(curves: Vec<Curve>) -> Self {
        Self {
            curves,
            bounds: None,
        }
    }

    /// The same motion with target bounds `[lo, hi]` per coordinate.
    pub fn with_bounds(mut self, bounds: Vec<[f64; 2]>) -> Self {
        self.bounds = Some(bounds);
        self
    }

    /// A spline per coordinate through `values[i][c]` at `times[i]` (one
    /// row per sample, one column per coordinate).
    pub fn samples(times: &[f64], values: &[Vec<f64>]) -> Result<Self, String> {
        let cols = values.first().map_or(0, Vec::len);
        if let Some((i, row)) = values.iter().enumerate().find(|(_, r)| r.len() != cols) {
            return Err(format!(
                "values[{i}] has {} entries, values[0] has {cols}",
                row.len()
            ));
        }
        let curves = (0..cols)
            .map(|c| {
                let col: Vec<f64> = values.iter().map(|r| r[c]).collect();
                Spline::new(times, &col).map(Curve::Spline)
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self::new(curves))
    }

    /// Checks the curve count against the joint's coordinates and each
    /// curve's parameters.
    pub(crate) fn validate(&self, dof: usize, element: &str) -> Result<(), DynamicsError> {
        let bad = |reason: String| DynamicsError::InvalidJoint {
            element: element.to_string(),
            reason: format!("prescribed motion: {reason}"),
        };
        if dof == 0 {
            return Err(bad("a fixed joint has no coordinate to prescribe".into()));
        }
        if self.curves.len() != dof {
            return Err(bad(format!(
                "{} curves for a joint of {dof} coordinates",
                self.curves.len()
            )));
        }
        for (i, c) in self.curves.iter().enumerate() {
            c.validate()
                .map_err(|e| bad(format!("coordinate {i}: {e}")))?;
        }
        if let Some(b) = &self.bounds {
            if b.len() != dof {
                return Err(bad(format!(
                    "{} bounds for a joint of {dof} coordinates",
                    b.len()
                )));
            }
            for (i, [lo, hi]) in b.iter().enumerate() {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return Err(bad(format!(
                        "coordinate {i}: bounds [{lo}, {hi}] must be finite with lo < hi"
                    )));
                }
            }
        }
        Ok(())
    }

    /// Values, rates and accelerations at `t` into the three slices (one
    /// entry per coordinate).
    pub(crate) fn eval_into(&self, t: f64, x: &mut [f64], v: &mut [f64], a: &mut [f64]) {
        for (i, c) in self.curves.iter().enumerate() {
            (x[i], v[i], a[i]) = c.eval(t);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_spline_breaks_where_it_starts_and_stops() {
        let ramp = Spline::new(&[1.0, 2.0, 4.0], &[0.0, 1.0, 3.0]).unwrap();
        assert_eq!(Curve::Spline(ramp).breakpoints(), vec![1.0, 4.0]);
        let held = Spline::new(&[2.0], &[0.5]).unwrap();
        assert!(Curve::Spline(held).breakpoints().is_empty());
        let sine = Curve::Sine {
            amplitude: 1.0,
            frequency: 1.0,
            phase: 0.0,
            offset: 0.0,
        };
        assert!(sine.breakpoints().is_empty());
    }

    #[test]
    fn spline_reproduces_a_cubic_and_its_derivatives() {
        let f = |t: f64| {
            (
                1.0 - 2.0 * t + 0.5 * t * t - 0.3 * t * t * t,
                -2.0 + t - 0.9 * t * t,
                1.0 - 1.8 * t,
            )
        };
        let times = [0.0, 0.3, 0.5, 1.1, 1.2, 2.0];
        let values: Vec<f64> = times.iter().map(|&t| f(t).0).collect();
        let s = Spline::new(&times, &values).unwrap();
        for k in 0..=40 {
            let t = 2.0 * k as f64 / 40.0;
            let (x, v, a) = s.eval(t);
            let (xe, ve, ae) = f(t);
            assert!((x - xe).abs() < 1e-12, "x at {t}: {x} vs {xe}");
            assert!((v - ve).abs() < 1e-11, "v at {t}: {v} vs {ve}");
            assert!((a - ae).abs() < 1e-10, "a at {t}: {a} vs {ae}");
        }
    }

    #[test]
    fn hermite_is_the_cubic_through_its_end_values_and_rates() {
        // The cubic Hermite basis in closed form, s = (t − t0)/h.
        let (t0, t1, x0, v0, x1, v1) = (0.3, 0.35, 0.2, -1.5, -0.4, 0.7);
        let h = t1 - t0;
        let f = |t: f64| {
            let s = (t - t0) / h;
            let (s2, s3) = (s * s, s * s * s);
            let x = (2.0 * s3 - 3.0 * s2 + 1.0) * x0
                + (s3 - 2.0 * s2 + s) * h * v0
                + (-2.0 * s3 + 3.0 * s2) * x1
                + (s3 - s2) * h * v1;
            let v = (6.0 * s2 - 6.0 * s) * x0 / h
                + (3.0 * s2 - 4.0 * s + 1.0) * v0
                + (-6.0 * s2 + 6.0 * s) * x1 / h
                + (3.0 * s2 - 2.0 * s) * v1;
            let a = (12.0 * s - 6.0) * x0 / (h * h)
                + (6.0 * s - 4.0) * v0 / h
                + (-12.0 * s + 6.0) * x1 / (h * h)
                + (6.0 * s - 2.0) * v1 / h;
            (x, v, a)
        };
        let sp = Spline::hermite(t0, t1, (x0, v0), (x1, v1)).unwrap();
        for k in 0..=20 {
            let t = t0 + h * k as f64 / 20.0;
            let (x, v, a) = sp.eval(t);
            let (xe, ve, ae) = f(t);
            assert!((x - xe).abs() < 1e-14, "x at {t}: {x} vs {xe}");
            assert!((v - ve).abs() < 1e-12, "v at {t}: {v} vs {ve}");
            assert!(
                (a - ae).abs() < 1e-9 * ae.abs().max(1.0),
                "a at {t}: {a} vs {ae}"
            );
        }
        assert!(Spline::hermite(1.0, 1.0, (0.0, 0.0), (1.0, 0.0)).is_err());
        assert!(Spline::hermite(0.0, 1.0, (0.0, f64::NAN), (1.0, 0.0)).is_err());
    }

    #[test]
    fn three_samples_give_the_parabola() {
        let s = Spline::new(&[0.0, 0.4, 1.0], &[0.0, 0.5 * 3.0 * 0.16, 1.5]).unwrap();
        let (x, v, a) = s.eval(0.7);
        assert!((x - 1.5 * 0.49).abs() < 1e-14);
        assert!((v - 3.0 * 0.7).abs() < 1e-13);
        assert!((a - 3.0).abs() < 1e-13);
    }

    #[test]
    fn spline_is_c2_at_interior_knots_and_holds_outside() {
        let times = [0.0, 0.1, 0.35, 0.4, 0.9];
        let values = [0.0, 0.3, -0.2, 0.1, 0.05];
        let s = Spline::new(&times, &values).unwrap();
        for (i, &tk) in times.iter().enumerate() {
            assert!((s.eval(tk).0 - values[i]).abs() < 1e-14, "knot {i}");
        }
        for &tk in &times[1..4] {
            let (l, r) = (s.eval(tk - 1e-9), s.eval(tk + 1e-9));
            assert!(
                (l.1 - r.1).abs() < 1e-6 && (l.2 - r.2).abs() < 1e-5,
                "{l:?} {r:?}"
            );
        }
        assert_eq!(s.eval(-1.0), (0.0, 0.0, 0.0));
        assert_eq!(s.eval(5.0), (0.05, 0.0, 0.0));
    }

    #[test]
    fn sine_derivatives_match_central_differences() {
        let c = Curve::Sine {
            amplitude: 0.02,
            frequency: 3.0,
            phase: 0.4,
            offset: 0.1,
        };
        let h = 1e-5;
        for &t in &[0.0, 0.13, 0.71] {
            let (_, v, a) = c.eval(t);
            let (xp, vp, _) = c.eval(t + h);
            let (xm, vm, _) = c.eval(t - h);
            assert!((v - (xp - xm) / (2.0 * h)).abs() < 1e-7);
            assert!((a - (vp - vm) / (2.0 * h)).abs() < 1e-5);
        }
    }

    #[test]
    fn bad_samples_are_refused() {
        assert!(Spline::new(&[], &[]).is_err());
        assert!(Spline::new(&[0.0, 0.0], &[1.0, 2.0]).is_err());
        assert!(Spline::new(&[0.0, 1.0], &[1.0]).is_err());
        assert!(Spline::new(&[0.0, 1.0], &[1.0, f64::NAN]).is_err());
        assert!(Prescribed::samples(&[0.0, 1.0], &[vec![1.0, 2.0], vec![1.0]]).is_err());
    }
}
