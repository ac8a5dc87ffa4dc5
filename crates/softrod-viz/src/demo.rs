//! Synthetic analytic motions for examples, tests and documentation: rods
//! bent into exact circular arcs (constant curvature, unit stretch).

use crate::data::{BodyShape, BodyTrack, CableTrack, Pose, RodTrack, ViewData, routed_cable};

/// Hamilton product `a ⊗ b` of quaternions `[w, x, y, z]`.
pub fn quat_mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

/// The frame at arc length `s` of a rod with constant curvature `kappa`
/// (1/m) about the local axis `(0, cos φ, sin φ)` and unit stretch, from
/// `base`: the strain `ξ = (0, κ cos φ, κ sin φ, 1, 0, 0)` integrated
/// exactly, `R(s) = R₀ exp(s k̃)`, `p(s) = p₀ + R₀ (sin(κs)/κ e₁ +
/// (1 − cos κs)/κ (a × e₁))` (the closed form of `g' = g ξ^` for a bending
/// axis `a ⟂ e₁`; series for `κs < 1e-4`).
pub fn arc_frame(base: &Pose, kappa: f64, phi: f64, s: f64) -> Pose {
    let th = kappa * s;
    let (sin_over, one_minus_cos_over) = if th.abs() < 1e-4 {
        (s * (1.0 - th * th / 6.0), s * th * (0.5 - th * th / 24.0))
    } else {
        (th.sin() / kappa, (1.0 - th.cos()) / kappa)
    };
    // a × e₁ for a = (0, cos φ, sin φ).
    let axe = [0.0, phi.sin(), -phi.cos()];
    let local = [
        sin_over,
        one_minus_cos_over * axe[1],
        one_minus_cos_over * axe[2],
    ];
    let half = 0.5 * th;
    let qa = [
        half.cos(),
        0.0,
        half.sin() * phi.cos(),
        half.sin() * phi.sin(),
    ];
    Pose {
        position: base.apply(local),
        rotation: quat_mul(base.rotation, qa),
    }
}

/// A demo scene: `rods` rods of length `length` (m) and base radius
/// `radius` (m, tapering to half at the tip), `samples` samples each, over
/// `times` output times in `[0, duration]`. Rod `j` hangs down from a base on
/// a circle and bends with curvature `κ(t) = (π / L) · sin(2π t / duration +
/// j)`, its bending plane turned by `2π j / rods` about the vertical (so
/// several rods make a 3-D scene). With `cable`, the first rod carries a
/// cable from offset `(0, 0.8 r)` to `(0, 0.4 r)`; with `body`, a sphere of
/// radius `2 r` rides on the first rod's tip.
#[derive(Debug, Clone, PartialEq)]
pub struct SwingingRods {
    /// Number of rods.
    pub rods: usize,
    /// Samples per rod (≥ 2).
    pub samples: usize,
    /// Output times (≥ 1).
    pub times: usize,
    /// Rod length, m.
    pub length: f64,
    /// Base radius, m.
    pub radius: f64,
    /// Duration, s.
    pub duration: f64,
    /// Add a cable on the first rod.
    pub cable: bool,
    /// Add a sphere on the first rod's tip.
    pub body: bool,
}

impl Default for SwingingRods {
    /// One 0.5 m rod of radius 1 cm, 41 samples, 201 times over 2 s.
    fn default() -> Self {
        Self {
            rods: 1,
            samples: 41,
            times: 201,
            length: 0.5,
            radius: 0.01,
            duration: 2.0,
            cable: false,
            body: false,
        }
    }
}

impl SwingingRods {
    /// The view data.
    pub fn build(&self) -> ViewData {
        let Self {
            rods,
            samples,
            times,
            length,
            radius,
            duration,
            cable,
            body,
        } = *self;
        let times_v: Vec<f64> = (0..times)
            .map(|k| duration * k as f64 / (times.max(2) - 1) as f64)
            .collect();
        let mut view = ViewData::new(format!("demo: {rods} swinging rods"), times_v.clone());
        for j in 0..rods {
            let ang = std::f64::consts::TAU * j as f64 / rods.max(1) as f64;
            let spacing = if rods > 1 { 0.6 * length } else { 0.0 };
            // Base pointing down (local x → world −z), local z → world x.
            let down = [
                std::f64::consts::FRAC_1_SQRT_2,
                0.0,
                std::f64::consts::FRAC_1_SQRT_2,
                0.0,
            ];
            let spin = [(0.5 * ang).cos(), (0.5 * ang).sin(), 0.0, 0.0];
            let base = Pose {
                position: [spacing * ang.cos(), spacing * ang.sin(), 0.0],
                rotation: quat_mul(down, spin),
            };
            let s: Vec<f64> = (0..samples)
                .map(|i| length * i as f64 / (samples - 1) as f64)
                .collect();
            let r: Vec<f64> = s
                .iter()
                .map(|v| radius * (1.0 - 0.5 * v / length))
                .collect();
            let frames = times_v
                .iter()
                .map(|t| {
                    let kappa = std::f64::consts::PI / length
                        * (std::f64::consts::TAU * t / duration + j as f64).sin();
                    s.iter()
                        .map(|sv| arc_frame(&base, kappa, 0.0, *sv))
                        .collect()
                })
                .collect();
            view.rods.push(RodTrack {
                name: format!("rod {j}"),
                s,
                radius: r,
                frames,
                tip_trace: None,
            });
        }
        if cable && !view.rods.is_empty() {
            let rod = &view.rods[0];
            let path = [[0.0, 0.0, 0.8 * radius], [length, 0.0, 0.4 * radius]];
            view.cables.push(CableTrack {
                name: "cable 0".into(),
                points: routed_cable(rod, &path),
            });
        }
        if body && !view.rods.is_empty() {
            let rod = &view.rods[0];
            let poses = rod.frames.iter().map(|f| f[f.len() - 1]).collect();
            view.bodies.push(BodyTrack {
                name: "tip mass".into(),
                shape: BodyShape::Sphere {
                    radius: 2.0 * radius,
                },
                poses,
            });
        }
        view
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The arc's end point from the closed form equals a fine midpoint-rule
    /// integration of `p' = R(s) e₁` with `R(s)` from the quaternion; and
    /// the series branch agrees with the closed form at the switch.
    #[test]
    fn arc_matches_integrated_tangent() {
        // Midpoint rule with 20 000 steps on a 0.5 m arc: error ~ L h² κ²/24 ≈ 1e-10 m.
        const TOL: f64 = 1e-9;
        let base = Pose::from_matrix(
            [0.1, -0.2, 0.3],
            [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]],
        );
        for (kappa, phi) in [(5.0, 0.3), (0.0, 0.0), (1e-3, 1.0), (20.0, -2.0)] {
            let (l, n) = (0.5, 20_000);
            let mut p = base.position;
            for i in 0..n {
                let s = (i as f64 + 0.5) * l / n as f64;
                let r = arc_frame(&base, kappa, phi, s).matrix();
                for j in 0..3 {
                    p[j] += r[j][0] * l / n as f64;
                }
            }
            let e = arc_frame(&base, kappa, phi, l).position;
            for j in 0..3 {
                assert!((p[j] - e[j]).abs() < TOL, "κ = {kappa}: {p:?} vs {e:?}");
            }
        }
        let a = arc_frame(&base, 1.0, 0.5, 0.999_999e-4);
        let b = arc_frame(&base, 1.0, 0.5, 1.000_001e-4);
        for j in 0..3 {
            // Positions 2e-10 m apart along the tangent; the branches agree to 1e-16.
            assert!((a.position[j] - b.position[j]).abs() < 3e-10);
        }
    }

    #[test]
    fn matrix_quaternion_round_trip() {
        for q in [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
            [0.5, -0.5, 0.5, 0.5],
            [0.9, 0.1, -0.3, 0.2],
        ] {
            let n = q.iter().map(|v: &f64| v * v).sum::<f64>().sqrt();
            let q = q.map(|v| v / n);
            let p = Pose {
                position: [0.0; 3],
                rotation: q,
            };
            let back = Pose::from_matrix([0.0; 3], p.matrix()).rotation;
            let sign = if q[0] < 0.0 { -1.0 } else { 1.0 };
            for j in 0..4 {
                assert!((back[j] - sign * q[j]).abs() < 1e-14, "{q:?} -> {back:?}");
            }
        }
    }
}
