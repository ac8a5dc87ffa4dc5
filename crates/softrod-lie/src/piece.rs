//! The maps of one PCS piece, with everything that does not depend on the
//! abscissa computed once.

use crate::adop::AdOp;
use crate::ops::{ad_vec, skew};
use crate::pose::Pose;
use crate::series;
use crate::types::{Mat3, Vec3, Vec6, angular, join, linear};

/// Precomputed parts of `exp(x·ξ̂)`, `T₋(x)` and `D_ξT₋(x)[δ]δ` for a piece of
/// constant strain `ξ = (k, q)` and strain rate `δ = ξ̇`.
///
/// Along a piece only the scalar coefficients `a, b, c, τ_i, ρ_i` depend on
/// the abscissa `x`; the matrices and vectors they multiply — `k̃`,
/// `k̃² = kkᵀ − θ²I`, `q̃`, `P₂ = kqᵀ + qkᵀ − 2σI` (see [`crate::tangent`]),
/// `k × q`, `k × (k × q)`, and for the bias the vectors `v_i = ad_ξ^i δ`,
/// `e_i` of (D6) — depend only on `ξ` and `δ`. A sweep that evaluates a
/// piece at its Gauss points and tip builds one `PieceMaps` per piece and
/// then pays only for the scalar series and a few scaled additions per
/// point. Results equal [`crate::exp_and_tangent_minus`] and
/// [`crate::d_tangent_minus_self`] to round-off.
#[derive(Clone, Debug)]
pub struct PieceMaps {
    theta: f64,
    theta2: f64,
    sigma: f64,
    q: Vec3,
    kmat: Mat3,
    k2: Mat3,
    qmat: Mat3,
    p2: Mat3,
    kq: Vec3,
    kkq: Vec3,
    /// `k·δ_k`, `v₁…v₄ = ad^i δ`, `e₂…e₄` (D6); zero without a rate.
    kd: f64,
    v: [Vec6; 4],
    e: [Vec6; 3],
    has_rate: bool,
}

impl PieceMaps {
    /// Precomputes for strain `ξ` and, when the bias is wanted, rate `δ`.
    #[inline(always)]
    pub fn new(xi: &Vec6, delta: Option<&Vec6>) -> Self {
        let k = angular(xi);
        let q = linear(xi);
        let th2 = k.norm_squared();
        let sigma = k.dot(&q);
        let kq_outer = k * q.transpose();
        let kq = k.cross(&q);
        let mut out = Self {
            theta: th2.sqrt(),
            theta2: th2,
            sigma,
            q,
            kmat: skew(&k),
            k2: k * k.transpose() - Mat3::from_diagonal_element(th2),
            qmat: skew(&q),
            p2: kq_outer + kq_outer.transpose() - Mat3::from_diagonal_element(2.0 * sigma),
            kq,
            kkq: k.cross(&kq),
            kd: 0.0,
            v: [Vec6::zeros(); 4],
            e: [Vec6::zeros(); 3],
            has_rate: false,
        };
        if let Some(d) = delta {
            // ad³δ = −θ²v₁ − 2σ(0, k×δ_k), ad⁴δ = −θ²v₂ − 2σ(0, k̃²δ_k)
            // (from P₃, P₄ of `tangent`): two brackets instead of four.
            let dk = angular(d);
            let v1 = ad_vec(xi, d);
            let v2 = ad_vec(xi, &v1);
            let kdk = k.cross(&dk);
            let v3 = v1 * (-th2) - join(&Vec3::zeros(), &kdk) * (2.0 * sigma);
            let v4 = v2 * (-th2) - join(&Vec3::zeros(), &(out.k2 * dk)) * (2.0 * sigma);
            let e2 = ad_vec(d, &v1);
            let e3 = ad_vec(d, &v2) + ad_vec(xi, &e2);
            let e4 = ad_vec(d, &v3) + ad_vec(xi, &e3);
            out.kd = k.dot(&dk);
            out.v = [v1, v2, v3, v4];
            out.e = [e2, e3, e4];
            out.has_rate = true;
        }
        out
    }

    /// `R = I + xa k̃ + x²b k̃²` and `p` (D4). The matrix sums are written on
    /// the structure of their terms — `k̃` skew, `k̃²` symmetric — each
    /// off-diagonal pair from one product of each (the same operations in
    /// the same order as the dense sums, so the same bits, in half the
    /// multiplications).
    #[inline(always)]
    fn pose(&self, x: f64, a: f64, b: f64, c: f64) -> Pose {
        let x2 = x * x;
        Pose {
            rotation: skew_plus_sym(1.0, &self.kmat, x * a, &self.k2, x2 * b),
            translation: self.q * x + self.kq * (x2 * b) + self.kkq * (x2 * x * c),
        }
    }

    /// `T₋(x)` (D3′) in block form, on the structure of its terms as
    /// [`Self::pose`]: `q̃`, `k̃` skew, `P₂`, `k̃²` symmetric.
    #[inline(always)]
    fn tangent_minus(&self, x: f64, b: f64, c: f64, t3: f64, t4: f64) -> AdOp {
        let x2 = x * x;
        let x3 = x2 * x;
        let cb = -x2 * b;
        let cc = x3 * c;
        let s = 2.0 * self.sigma * x2 * x2;
        let (st3, st4) = (s * t3, s * x * t4);
        let (qm, p2, km, k2) = (&self.qmat, &self.p2, &self.kmat, &self.k2);
        // ((q̃ cb + P₂ cc) + k̃ st3) − k̃² st4 entry by entry; the skew terms
        // change sign across the diagonal and vanish on it.
        let e = |i: usize, j: usize| {
            let (qa, pc) = (qm[(i, j)] * cb, p2[(i, j)] * cc);
            let (ka, ks) = (km[(i, j)] * st3, k2[(i, j)] * st4);
            (((qa + pc) + ka) - ks, ((pc - qa) - ka) - ks)
        };
        let d = |i: usize| p2[(i, i)] * cc - k2[(i, i)] * st4;
        let (b01, b10) = e(0, 1);
        let (b02, b20) = e(0, 2);
        let (b12, b21) = e(1, 2);
        AdOp {
            a: skew_plus_sym(x, km, cb, k2, cc),
            b: Mat3::new(d(0), b01, b02, b10, d(1), b12, b20, b21, d(2)),
        }
    }

    /// `exp(x·ξ̂)` (D4) alone: three series and two scaled additions.
    #[inline]
    pub fn exp(&self, x: f64) -> Pose {
        let [a, b, c] = series::abc(x * self.theta);
        self.pose(x, a, b, c)
    }

    /// `exp(x·ξ̂)` (D4) and `T₋(x)` (D3′).
    #[inline(always)]
    pub fn exp_and_tangent_minus(&self, x: f64) -> (Pose, AdOp) {
        let ([a, b, c], [t3, t4]) = series::abc_tau34(x * self.theta);
        (self.pose(x, a, b, c), self.tangent_minus(x, b, c, t3, t4))
    }

    /// `exp(x·ξ̂)`, `T₋(x)` and the bias `D_ξT₋(x)[δ]δ = Ṡ_n(x) q̇_n` (D6, D9),
    /// which is zero when no rate was given.
    #[inline(always)]
    pub fn eval(&self, x: f64) -> (Pose, AdOp, Vec6) {
        let (g, t, bias, _) = self.eval_with_ta(x);
        (g, t, bias)
    }

    /// [`Self::eval`] and the scalar coefficients `[x, c_b, c_c]` of the
    /// diagonal block of `T₋(x)`: `T_a(x) = x I + c_b k̃ + c_c k̃²` (D3′), a
    /// polynomial in `k̃` ([`Self::k_skew`], [`Self::k_skew_squared`]), so
    /// sums over a piece's points of products of `T_a` can be carried as
    /// scalar sums.
    #[inline(always)]
    pub fn eval_with_ta(&self, x: f64) -> (Pose, AdOp, Vec6, [f64; 3]) {
        if !self.has_rate {
            let ([a, b, c], [t3, t4]) = series::abc_tau34(x * self.theta);
            let x2 = x * x;
            let ta = [x, -x2 * b, x2 * x * c];
            return (
                self.pose(x, a, b, c),
                self.tangent_minus(x, b, c, t3, t4),
                Vec6::zeros(),
                ta,
            );
        }
        let psi = x * self.theta;
        let ([a, b, c], [t2, t3, t4], r) = series::abc_tau234_rho(psi);
        let x2 = x * x;
        let x3 = x2 * x;
        let x4 = x2 * x2;
        let x5 = x4 * x;
        let kd = self.kd;
        let [v1, v2, v3, v4] = &self.v;
        let [e2, e3, e4] = &self.e;
        let bias = v1 * (-x4 * r[0] * kd) + (v2 * (x5 * r[1] * kd) + e2 * (x3 * t2))
            - (v3 * (x5 * x * r[2] * kd) + e3 * (x4 * t3))
            + (v4 * (x5 * x2 * r[3] * kd) + e4 * (x5 * t4));
        (
            self.pose(x, a, b, c),
            self.tangent_minus(x, b, c, t3, t4),
            bias,
            [x, -x2 * b, x3 * c],
        )
    }

    /// The piece's curvature `k` (read off `k̃`).
    #[inline(always)]
    pub fn k(&self) -> Vec3 {
        let m = &self.kmat;
        Vec3::new(m[(2, 1)], m[(0, 2)], m[(1, 0)])
    }

    /// `k̃` of the piece's curvature `k`.
    #[inline(always)]
    pub fn k_skew(&self) -> &Mat3 {
        &self.kmat
    }

    /// `k̃² = kkᵀ − θ²I`.
    #[inline(always)]
    pub fn k_skew_squared(&self) -> &Mat3 {
        &self.k2
    }

    /// `θ² = |k|²` (`k̃³ = −θ²k̃`).
    #[inline(always)]
    pub fn theta_squared(&self) -> f64 {
        self.theta2
    }
}

/// `δI + α K + β S` for a skew `K` and a symmetric `S`, entry by entry as
/// `(δI + αK) + βS` sums them (bit-identical, but each off-diagonal pair
/// from one product of each).
#[inline(always)]
fn skew_plus_sym(delta: f64, k: &Mat3, alpha: f64, s: &Mat3, beta: f64) -> Mat3 {
    let e = |i: usize, j: usize| {
        let (ka, sb) = (k[(i, j)] * alpha, s[(i, j)] * beta);
        (ka + sb, sb - ka)
    };
    let d = |i: usize| delta + s[(i, i)] * beta;
    let (m01, m10) = e(0, 1);
    let (m02, m20) = e(0, 2);
    let (m12, m21) = e(1, 2);
    Mat3::new(d(0), m01, m02, m10, d(1), m12, m20, m21, d(2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{d_tangent_minus_self, exp_and_tangent_minus};

    /// `T_a = xI + c_b k̃ + c_c k̃²` from [`PieceMaps::eval_with_ta`], and the
    /// scalar form `T_aᵀT_a = −2c_b I + (2x c_c − c_b² − θ²c_c²) kkᵀ` the
    /// inertia sums use (D91), against the dense block and its dense product.
    #[test]
    fn ta_coefficients_give_the_block_and_its_gram() {
        let xis = [
            Vec6::new(0.3, -1.1, 0.7, 1.05, 0.2, -0.1),
            Vec6::new(1e-9, 0.0, 2e-9, 0.9, 0.01, 0.0),
            Vec6::new(12.0, -30.0, 5.0, 1.2, -0.3, 0.4),
        ];
        let d = Vec6::new(0.2, 0.1, -0.4, 0.3, -0.5, 0.9);
        for xi in &xis {
            for rate in [None, Some(&d)] {
                let pm = PieceMaps::new(xi, rate);
                let (km, k2, th2) = (pm.k_skew(), pm.k_skew_squared(), pm.theta_squared());
                let k = pm.k();
                assert_eq!(k, angular(xi));
                for x in [0.0, 0.01, 0.3, 1.0, 2.0] {
                    let (g, t, bias, [x0, cb, cc]) = pm.eval_with_ta(x);
                    assert_eq!(pm.eval(x), (g, t, bias));
                    assert_eq!(x0, x);
                    let ta = Mat3::identity() * x + km * cb + k2 * cc;
                    let scale = 1.0 + t.a.amax();
                    assert!((ta - t.a).amax() < 1e-15 * scale, "{xi:?} {x}");
                    let gram = Mat3::identity() * (-2.0 * cb)
                        + k * k.transpose() * ((2.0 * x * cc - cb * cb) - th2 * (cc * cc));
                    let dense = t.a.transpose() * t.a;
                    assert!(
                        (gram - dense).amax() < 1e-14 * scale * scale,
                        "{xi:?} {x}: {gram:?} vs {dense:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn equals_the_standalone_maps() {
        let xis = [
            Vec6::new(0.3, -1.1, 0.7, 1.05, 0.2, -0.1),
            Vec6::new(0.0, 0.0, 0.0, 1.0, 0.0, 0.0),
            Vec6::new(1e-9, 0.0, 2e-9, 0.9, 0.01, 0.0),
            Vec6::new(12.0, -30.0, 5.0, 1.2, -0.3, 0.4),
        ];
        let d = Vec6::new(0.2, 0.1, -0.4, 0.3, -0.5, 0.9);
        for xi in &xis {
            let pm = PieceMaps::new(xi, Some(&d));
            for x in [0.0, 0.01, 0.3, 1.0, 2.0] {
                let (g, t, bias) = pm.eval(x);
                assert_eq!(pm.exp(x), g);
                let (g0, t0) = exp_and_tangent_minus(x, xi);
                let b0 = d_tangent_minus_self(x, xi, &d);
                let scale = 1.0 + t0.a.amax() + t0.b.amax();
                assert!((g.rotation - g0.rotation).amax() < 1e-15);
                assert!((g.translation - g0.translation).amax() < 1e-15 * (1.0 + x));
                assert!((t.a - t0.a).amax() < 2e-15 * scale, "{xi:?} {x}");
                assert!((t.b - t0.b).amax() < 2e-15 * scale, "{xi:?} {x}");
                assert!(
                    (bias - b0).amax() < 1e-14 * (1.0 + b0.amax()),
                    "{xi:?} {x}: {bias:?} vs {b0:?}"
                );
            }
        }
    }
}
