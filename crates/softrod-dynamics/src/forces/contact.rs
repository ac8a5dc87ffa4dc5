//! The contact force law of docs/theory-contact.md: the signed distance of
//! a point to each obstacle shape with its gradient and Hessian (CT1), the
//! smooth penalty with normal damping (CT2–CT4) and the anchored Coulomb
//! friction spring (CT5), each with its derivatives with respect to the
//! contact point's position and velocity (CT6).

use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::contact::Shape;

/// Signed distance of a point to a shape's surface (negative inside), its
/// gradient (the outward unit normal) and its Hessian, world frame (CT1).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Distance {
    pub d: f64,
    pub normal: Vec3,
    pub hessian: Mat3,
}

/// Unit vector along `w`, its length, and `(I − nnᵀ)/|w|` — the
/// derivative of `w/|w|`; along `fallback` for a zero `w` (a point on an
/// axis or centre: any normal is as good, none is smooth there).
fn direction(w: Vec3, fallback: Vec3) -> (Vec3, f64, Mat3) {
    let l = w.norm();
    if l > 0.0 {
        let n = w / l;
        (n, l, (Mat3::identity() - n * n.transpose()) / l)
    } else {
        (fallback, 0.0, Mat3::zeros())
    }
}

/// A unit vector orthogonal to the unit `a`.
fn orthogonal(a: &Vec3) -> Vec3 {
    let t = if a.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    (t - a * a.dot(&t)).normalize()
}

/// [`Distance`] of the world point `p` to `shape` placed by `frame`
/// (the parent's world pose).
pub(crate) fn distance(shape: &Shape, frame: &Pose, p: &Vec3) -> Distance {
    let r = frame.rotation;
    let at = |c: &Vec3| frame.translation + r * c;
    match shape {
        Shape::Plane { point, normal } => {
            let n = r * normal;
            Distance {
                d: (p - at(point)).dot(&n),
                normal: n,
                hessian: Mat3::zeros(),
            }
        }
        Shape::Sphere { center, radius } => {
            let (n, l, h) = direction(p - at(center), Vec3::z());
            Distance {
                d: l - radius,
                normal: n,
                hessian: h,
            }
        }
        Shape::Cylinder {
            point,
            axis,
            radius,
        } => {
            let a = r * axis;
            let v = p - at(point);
            let w = v - a * a.dot(&v);
            let (n, l, h) = direction(w, orthogonal(&a));
            let h = if l > 0.0 {
                h - a * a.transpose() / l
            } else {
                h
            };
            Distance {
                d: l - radius,
                normal: n,
                hessian: h,
            }
        }
        Shape::Capsule {
            center,
            axis,
            length,
            radius,
        } => {
            let a = r * axis;
            let v = p - at(center);
            let t = a.dot(&v);
            let half = 0.5 * length;
            let inside = t.abs() < half;
            let w = v - a * t.clamp(-half, half);
            let (n, l, h) = direction(w, orthogonal(&a));
            let h = if inside && l > 0.0 {
                h - a * a.transpose() / l
            } else {
                h
            };
            Distance {
                d: l - radius,
                normal: n,
                hessian: h,
            }
        }
        Shape::Box {
            center,
            rotation,
            half_extents,
        } => {
            let rb = r * rotation;
            let y = rb.tr_mul(&(p - at(center)));
            let mut w = Vec3::zeros();
            let mut clamped = Mat3::zeros();
            for i in 0..3 {
                if y[i].abs() > half_extents[i] {
                    w[i] = y[i] - half_extents[i].copysign(y[i]);
                    clamped[(i, i)] = 1.0;
                }
            }
            let l = w.norm();
            if l > 0.0 {
                // Outside: the distance to the closest point of the box;
                // only the clamped axes move it.
                let n = w / l;
                let h = (clamped - n * n.transpose()) / l;
                Distance {
                    d: l,
                    normal: rb * n,
                    hessian: rb * h * rb.transpose(),
                }
            } else {
                // Inside: the nearest face (flat: no curvature).
                let mut best = 0;
                let mut depth = f64::INFINITY;
                for i in 0..3 {
                    let di = half_extents[i] - y[i].abs();
                    if di < depth {
                        depth = di;
                        best = i;
                    }
                }
                let mut n = Vec3::zeros();
                n[best] = if y[best] >= 0.0 { 1.0 } else { -1.0 };
                Distance {
                    d: -depth,
                    normal: rb * n,
                    hessian: Mat3::zeros(),
                }
            }
        }
    }
}

/// The parameters `(t, u)` in `[0, 1]²` of the closest points
/// `p0 + t (p1 − p0)` and `q0 + u (q1 − q0)` of two segments (CT8): the
/// unconstrained minimizer clamped to the square edge by edge (each clamp
/// re-solves the other parameter), so crossing segments are found wherever
/// they cross; parallel segments take `t` of the middle of their overlap.
pub(crate) fn closest_on_segments(p0: &Vec3, p1: &Vec3, q0: &Vec3, q1: &Vec3) -> (f64, f64) {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.norm_squared();
    let e = d2.norm_squared();
    let f = d2.dot(&r);
    let tiny = 1e-30;
    if a <= tiny && e <= tiny {
        return (0.0, 0.0);
    }
    if a <= tiny {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(&r);
    if e <= tiny {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(&d2);
    let denom = a * e - b * b;
    let mut t = if denom > 1e-12 * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        // Parallel: the middle of the overlap of the projections of q0, q1.
        let (u0, u1) = ((-c) / a, (b - c) / a);
        let (lo, hi) = (u0.min(u1).max(0.0), u0.max(u1).min(1.0));
        if lo <= hi {
            0.5 * (lo + hi)
        } else {
            u0.min(u1).clamp(0.0, 1.0)
        }
    };
    let mut u = (b * t + f) / e;
    if u < 0.0 {
        u = 0.0;
        t = (-c / a).clamp(0.0, 1.0);
    } else if u > 1.0 {
        u = 1.0;
        t = ((b - c) / a).clamp(0.0, 1.0);
    }
    (t, u)
}

/// The constants of one contact pair (CT3–CT5).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Law {
    /// Normal stiffness \[N/m\].
    pub k: f64,
    /// Normal damping \[N·s/m\].
    pub c: f64,
    /// Width of the quadratic start of the penalty \[m\].
    pub eps: f64,
    /// Coulomb coefficient.
    pub mu: f64,
    /// Penetration at which the penalty starts \[m\] (CT15: zero but
    /// while a raised stiffness heals from its raise).
    pub offset: f64,
}

impl Law {
    /// The constants for a contact point of `mass` \[kg\] and surface
    /// radius `radius` \[m\] (the smaller of the pair), under gravity of
    /// magnitude `g` \[m/s²\], with restitution `e` and friction `mu`
    /// (CT3, CT4).
    pub(crate) fn new(mass: f64, radius: f64, g: f64, e: f64, mu: f64) -> Self {
        Self::pair(mass, mass, radius, g, e, mu)
    }

    /// The constants of a contact whose stiffness is set by `mass` and
    /// whose damping acts on the relative motion of mass `moving` (a rod
    /// pair: the smaller side's mass and the reduced mass, CT11).
    pub(crate) fn pair(mass: f64, moving: f64, radius: f64, g: f64, e: f64, mu: f64) -> Self {
        use crate::model::contact::{IMPACT_PENETRATION, IMPACT_SPEED, REST_PENETRATION};
        // At rest: m g / k at half the rest bound (the other half is the
        // quadratic start). In an impact: ½ m v² = ½ k δ² at the bound.
        let k_rest = mass * g / (0.5 * REST_PENETRATION * radius);
        let k_impact = mass * (IMPACT_SPEED / (IMPACT_PENETRATION * radius)).powi(2);
        let k = k_rest.max(k_impact);
        let zeta = if e <= 0.0 {
            1.0
        } else if e >= 1.0 {
            0.0
        } else {
            let l = -e.ln();
            l / (std::f64::consts::PI.powi(2) + l * l).sqrt()
        };
        Self {
            k,
            c: 2.0 * zeta * (k * moving).sqrt(),
            eps: 0.1 * REST_PENETRATION * radius,
            mu,
            offset: 0.0,
        }
    }

    /// This law with its stiffness raised by `scale` and its penalty
    /// starting at the penetration `offset` (CT15): `k` times `scale`, `c`
    /// times `√scale` (the same damping ratio), the same `ε`.
    pub(crate) fn scaled(self, scale: f64, offset: f64) -> Self {
        Self {
            k: self.k * scale,
            c: self.c * scale.sqrt(),
            offset,
            ..self
        }
    }

    /// The penetration at which the spring of this law (offset aside)
    /// carries `force` ≥ 0 (the inverse of `φ`, CT15).
    pub(crate) fn depth_of(&self, force: f64) -> f64 {
        if force >= 0.5 * self.k * self.eps {
            force / self.k + 0.5 * self.eps
        } else {
            (2.0 * self.eps * force / self.k).sqrt()
        }
    }

    /// Penalty force `φ(δ)` and `φ'(δ)` of the penetration `δ` (CT2): zero
    /// apart, quadratic over `[0, ε]`, then linear of slope `k` (C¹).
    #[inline]
    pub(crate) fn penalty(&self, delta: f64) -> (f64, f64) {
        let delta = delta - self.offset;
        if delta <= 0.0 {
            (0.0, 0.0)
        } else if delta < self.eps {
            (
                0.5 * self.k * delta * delta / self.eps,
                self.k * delta / self.eps,
            )
        } else {
            (self.k * (delta - 0.5 * self.eps), self.k)
        }
    }
}

/// The force on the rod at one contact and its derivatives (CT2–CT6).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ContactForce {
    /// Force on the rod, world \[N\].
    pub f: Vec3,
    /// `∂f/∂p`, `∂f/∂v` (p, v: the rod point's position and velocity
    /// relative to the obstacle).
    pub dp: Mat3,
    pub dv: Mat3,
    /// `∂f/∂e` of the friction stretch alone (`dp` holds it too: there the
    /// stretch moves with `p`); zero without friction (CT14).
    pub de: Mat3,
    pub sticking: bool,
}

/// The force of `law` on a rod point at penetration `δ = r − d` with the
/// distance `dist`, relative velocity `v`, and (with friction) the
/// tangential spring's stretch `p − a` from its anchor (CT2–CT6).
pub(crate) fn force(
    law: &Law,
    dist: &Distance,
    radius: f64,
    v: &Vec3,
    stretch: Option<Vec3>,
) -> ContactForce {
    let n = dist.normal;
    let delta = radius - dist.d;
    let (phi, dphi) = law.penalty(delta);
    // δ̇ = −n·v; the damping is ramped in with φ'/k so the force is
    // continuous at first touch.
    let ramp = dphi / law.k;
    let vn = n.dot(v);
    let mut fn_ = phi - law.c * ramp * vn;
    // ∂fn/∂p = −φ' n − c ramp (H v) − c vn ramp' n ... ramp' = φ''/k.
    let x = delta - law.offset;
    let ddphi = if x > 0.0 && x < law.eps {
        law.k / law.eps
    } else {
        0.0
    };
    let hv = dist.hessian * v;
    let mut dfn_dp = -dphi * n - law.c * ramp * hv + law.c * vn * (ddphi / law.k) * n;
    let mut dfn_dv = -law.c * ramp * n;
    if fn_ <= 0.0 {
        // The damping would pull: no force (the contact is opening).
        fn_ = 0.0;
        dfn_dp = Vec3::zeros();
        dfn_dv = Vec3::zeros();
    }
    // f_N = fn n: ∂(fn n)/∂p = n ∂fnᵀ + fn H.
    let mut f = n * fn_;
    let mut dp = n * dfn_dp.transpose() + dist.hessian * fn_;
    let mut dv = n * dfn_dv.transpose();
    let mut sticking = false;
    let mut de = Mat3::zeros();
    if let (Some(e), true) = (stretch, law.mu > 0.0 && fn_ > 0.0) {
        // Tangential projection P = I − nnᵀ and its derivative along p
        // (n moves with p by H): ∂(P x)/∂p = −(n xᵀ H + (n·x) H).
        let proj = Mat3::identity() - n * n.transpose();
        let dproj = |x: &Vec3| -(n * (dist.hessian * x).transpose() + dist.hessian * n.dot(x));
        let et = proj * e;
        let vt = proj * v;
        let (kt, ct) = (law.k, law.c);
        let trial = -kt * et - ct * vt;
        // ∂trial/∂p: the stretch moves with p (∂e/∂p = I).
        let dtrial_dp = -kt * (proj + dproj(&e)) - ct * dproj(v);
        let dtrial_dv = -ct * proj;
        let bound = law.mu * fn_;
        let t = trial.norm();
        if t <= bound {
            sticking = true;
            f += trial;
            dp += dtrial_dp;
            dv += dtrial_dv;
            de = -kt * proj;
        } else {
            // Slip: μ fn along the trial force.
            let u = trial / t;
            let du = (Mat3::identity() - u * u.transpose()) / t;
            f += u * bound;
            dp += u * (law.mu * dfn_dp).transpose() + du * dtrial_dp * bound;
            dv += u * (law.mu * dfn_dv).transpose() + du * dtrial_dv * bound;
            de = du * (-kt * proj) * bound;
        }
    }
    ContactForce {
        f,
        dp,
        dv,
        de,
        sticking,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use softrod_lie::Vec6;

    fn shapes() -> Vec<Shape> {
        let axis = Vec3::new(1.0, 2.0, 2.0) / 3.0;
        vec![
            Shape::Plane {
                point: Vec3::new(0.1, 0.0, -0.2),
                normal: Vec3::new(0.0, 0.6, 0.8),
            },
            Shape::Sphere {
                center: Vec3::new(0.1, 0.2, 0.0),
                radius: 0.3,
            },
            Shape::Cylinder {
                point: Vec3::new(0.0, 0.1, 0.0),
                axis,
                radius: 0.2,
            },
            Shape::Capsule {
                center: Vec3::zeros(),
                axis,
                length: 0.2,
                radius: 0.2,
            },
            Shape::Box {
                center: Vec3::new(0.0, 0.0, 0.1),
                rotation: softrod_lie::exp_twist(1.0, &Vec6::new(0.3, -0.2, 0.5, 0.0, 0.0, 0.0))
                    .rotation,
                half_extents: Vec3::new(0.1, 0.2, 0.3),
            },
        ]
    }

    /// The gradient and Hessian against central differences of the
    /// distance, inside and outside every shape.
    #[test]
    fn distance_derivatives_match_central_differences() {
        let frame = softrod_lie::exp_twist(1.0, &Vec6::new(0.1, 0.2, -0.3, 0.05, 0.0, 0.1));
        let points = [
            Vec3::new(0.4, 0.35, 0.3),
            Vec3::new(-0.05, 0.1, 0.12),
            Vec3::new(0.3, -0.4, 0.7),
        ];
        let h = 1e-6;
        for shape in shapes() {
            for p in &points {
                let d0 = distance(&shape, &frame, p);
                for i in 0..3 {
                    let mut dp = Vec3::zeros();
                    dp[i] = h;
                    let (a, b) = (
                        distance(&shape, &frame, &(p + dp)),
                        distance(&shape, &frame, &(p - dp)),
                    );
                    let g = (a.d - b.d) / (2.0 * h);
                    assert!((g - d0.normal[i]).abs() < 1e-7, "{shape:?} {p} grad");
                    let col = (a.normal - b.normal) / (2.0 * h);
                    let err = (col - d0.hessian.column(i)).norm();
                    assert!(err < 1e-5, "{shape:?} {p} hessian {err}");
                }
            }
        }
    }

    /// Closest points of segments against a dense sampling of both.
    #[test]
    fn closest_points_of_segments_match_brute_force() {
        let cases = [
            // crossing at an angle, skew by 0.1
            (
                [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)],
                [Vec3::new(0.3, -0.5, 0.1), Vec3::new(0.5, 0.5, 0.1)],
            ),
            // closest at an end of one
            (
                [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)],
                [Vec3::new(1.2, 0.3, 0.0), Vec3::new(2.0, 1.0, 0.5)],
            ),
            // parallel, overlapping
            (
                [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)],
                [Vec3::new(0.5, 0.1, 0.0), Vec3::new(1.5, 0.1, 0.0)],
            ),
            // parallel, apart along the axis
            (
                [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)],
                [Vec3::new(2.0, 0.1, 0.0), Vec3::new(3.0, 0.1, 0.0)],
            ),
        ];
        for ([p0, p1], [q0, q1]) in cases {
            let (t, u) = closest_on_segments(&p0, &p1, &q0, &q1);
            let d = (p0 + (p1 - p0) * t - q0 - (q1 - q0) * u).norm();
            let mut best = f64::INFINITY;
            let n = 400;
            for i in 0..=n {
                for j in 0..=n {
                    let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
                    best = best.min((p0 + (p1 - p0) * a - q0 - (q1 - q0) * b).norm());
                }
            }
            assert!(d <= best + 1e-12 && d >= best - 5e-3, "{d} vs {best}");
        }
    }

    /// Every branch of the force law against central differences in p, v.
    #[test]
    fn force_derivatives_match_central_differences() {
        let shape = Shape::Sphere {
            center: Vec3::zeros(),
            radius: 0.3,
        };
        let frame = Pose::identity();
        let law = Law::new(0.01, 0.01, 9.81, 0.5, 0.4);
        let cases = [
            // deep, sliding fast: slip
            (
                0.305,
                Vec3::new(0.3, -0.2, 0.01),
                Some(Vec3::new(0.0, 0.0, 0.0)),
            ),
            // deep, small stretch: stick
            (
                0.305,
                Vec3::new(0.001, 0.0, 0.0),
                Some(Vec3::new(0.0, 1e-6, 2e-6)),
            ),
            // in the quadratic start
            (0.30995, Vec3::new(0.0, 0.0, 0.0), None),
        ];
        let dir = Vec3::new(0.6, 0.0, 0.8);
        for (dist_c, v, stretch) in cases {
            let p = dir * dist_c;
            let eval = |p: &Vec3, v: &Vec3| {
                let d = distance(&shape, &frame, p);
                force(&law, &d, 0.01, v, stretch.map(|s| s + p - dir * dist_c))
            };
            let f0 = eval(&p, &v);
            let h = 1e-8;
            for i in 0..3 {
                let mut e = Vec3::zeros();
                e[i] = h;
                let cp = (eval(&(p + e), &v).f - eval(&(p - e), &v).f) / (2.0 * h);
                let cv = (eval(&p, &(v + e)).f - eval(&p, &(v - e)).f) / (2.0 * h);
                let scale = f0.dp.abs().max() + 1.0;
                assert!((cp - f0.dp.column(i)).norm() < 1e-6 * scale, "dp {i}");
                let scale = f0.dv.abs().max() + 1.0;
                assert!((cv - f0.dv.column(i)).norm() < 1e-6 * scale, "dv {i}");
            }
        }
    }
}
