//! Exponentials, the tangent operator and its strain derivative, in closed
//! form with small-angle series (docs/theory.md §1).
//!
//! All functions take the arc length `x ≥ 0` [m] along a piece and the
//! constant strain `ξ = (k, q)` of the piece; `θ = |k|`, `ψ = x·θ`.

use crate::adop::AdOp;
use crate::ops::{ad_vec, skew};
use crate::pose::Pose;
use crate::series;
use crate::types::{Mat3, Vec3, Vec6, angular, linear};

/// Powers `ad_ξ^i = [[K^i, 0], [P_i, K^i]]`, `i = 1…4`, with `K = k̃`, `Q = q̃`,
/// `P₁ = Q`, `P_{i+1} = Q K^i + K P_i`, and `K³ = −θ²K`, `K⁴ = −θ²K²`.
struct AdPowers {
    k: [Mat3; 4],
    p: [Mat3; 4],
}

impl AdPowers {
    #[inline(always)]
    fn new(xi: &Vec6) -> Self {
        let kv = angular(xi);
        let th2 = kv.norm_squared();
        let k1 = skew(&kv);
        let q = skew(&linear(xi));
        let k2 = k1 * k1;
        let k3 = k1 * (-th2);
        let k4 = k2 * (-th2);
        let p1 = q;
        let p2 = q * k1 + k1 * p1;
        let p3 = q * k2 + k1 * p2;
        let p4 = q * k3 + k1 * p3;
        Self {
            k: [k1, k2, k3, k4],
            p: [p1, p2, p3, p4],
        }
    }
}

/// Group exponential `exp(x·ξ̂)` (D4), the pose of the section at `x`
/// relative to the piece base (D7)):
/// `R = I + x a(ψ) k̃ + x² b(ψ) k̃²`, `p = (x I + x² b(ψ) k̃ + x³ c(ψ) k̃²) q`,
/// `a = sinψ/ψ`, `b = (1−cosψ)/ψ²`, `c = (ψ−sinψ)/ψ³` (series below ψ* = 2.5).
///
/// Accuracy: ≤ 4e-16 relative in the coefficients; the pose to a few ulps.
#[inline]
pub fn exp_twist(x: f64, xi: &Vec6) -> Pose {
    let kv = angular(xi);
    let th = kv.norm();
    let psi = x * th;
    if psi.abs() < series::PSI_SWITCH {
        let [a, b, c] = series::abc_below_switch(psi);
        exp_twist_with(x, xi, a, b, c)
    } else {
        exp_twist_closed(x, xi, th, psi)
    }
}

/// The closed branch of [`exp_twist`] without a division after the sine:
/// with `θ = |k| > 0`, `x·a = sinψ/θ`, `x²b = (1 − cosψ)/θ²`,
/// `x³c = (ψ − sinψ)/θ³` (`ψ = xθ`, either sign), and `1/θ` is ready long
/// before `sin_cos` is; the diagonal `1 − x²bθ²` of `R` is `cosψ` itself.
/// (Dividing by `ψ` after the sine measured 20 % slower: the division sits
/// on the dependency chain.) Out of line: inlined, its register needs
/// slowed the series branch by ~8 %.
#[inline(never)]
fn exp_twist_closed(x: f64, xi: &Vec6, th: f64, psi: f64) -> Pose {
    let inv = 1.0 / th;
    let inv2 = inv * inv;
    let (s, c) = series::sin_cos(psi);
    pose_from(
        x,
        xi,
        &PoseCoefficients {
            diag: c,
            xa: s * inv,
            x2b: (1.0 - c) * inv2,
            x3c: (psi - s) * (inv2 * inv),
        },
    )
}

/// The scalars of (D4) as they enter the pose: `R = d I + (xa) k̃ + (x²b) kkᵀ`
/// (`d = 1 − x²bθ²`, from `k̃² = kkᵀ − θ²I`) and
/// `p = x q + (x²b) k×q + (x³c) k×(k×q)`.
struct PoseCoefficients {
    diag: f64,
    xa: f64,
    x2b: f64,
    x3c: f64,
}

impl PoseCoefficients {
    #[inline(always)]
    fn from_abc(x: f64, th2: f64, a: f64, b: f64, c: f64) -> Self {
        let x2b = x * x * b;
        Self {
            diag: 1.0 - x2b * th2,
            xa: x * a,
            x2b,
            x3c: x * x * x * c,
        }
    }
}

#[inline(always)]
fn pose_from(x: f64, xi: &Vec6, k: &PoseCoefficients) -> Pose {
    let kv = angular(xi);
    let q = linear(xi);
    // No 3×3 product needed. Kept as whole-matrix operations on purpose: the
    // entrywise symmetric + skew form (as in `tangent_blocks`) runs 25 fewer
    // instructions but measured 14–33 % slower under criterion (not
    // investigated further).
    let rotation =
        Mat3::from_diagonal_element(k.diag) + skew(&kv) * k.xa + (kv * kv.transpose()) * k.x2b;
    let kq = kv.cross(&q);
    let translation = q * x + kq * k.x2b + kv.cross(&kq) * k.x3c;
    Pose {
        rotation,
        translation,
    }
}

#[inline(always)]
fn exp_twist_with(x: f64, xi: &Vec6, a: f64, b: f64, c: f64) -> Pose {
    pose_from(
        x,
        xi,
        &PoseCoefficients::from_abc(x, angular(xi).norm_squared(), a, b, c),
    )
}

/// The 3×3 matrix `S + w̃` from the diagonal `d` and the upper off-diagonal
/// entries `o = (S₀₁, S₀₂, S₁₂)` of a symmetric `S` and the axial vector `w`.
#[inline(always)]
fn sym_plus_skew(d: [f64; 3], o: [f64; 3], w: &Vec3) -> Mat3 {
    Mat3::new(
        d[0],
        o[0] - w[2],
        o[1] + w[1],
        o[0] + w[2],
        d[1],
        o[2] - w[0],
        o[1] - w[1],
        o[2] + w[0],
        d[2],
    )
}

/// `T(x)` (`sign = +1`) or `T₋(x)` (`sign = −1`) in block form from the
/// coefficients, without any 3×3 product.
///
/// With `K = k̃`, `Q = q̃`, `σ = k·q`, the powers of `ad_ξ` have the blocks
/// `K² = kkᵀ − θ²I`, `K³ = −θ²K`, `K⁴ = −θ²K²` and `P₁ = Q`,
/// `P₂ = QK + KQ = kqᵀ + qkᵀ − 2σI`, `P₃ = −θ²Q − 2σK`, `P₄ = −θ²P₂ − 2σK²`
/// (the skew-product identity `ãb̃ = baᵀ − (a·b)I`). Collecting (D3) and using
/// the exact identities `τ₁ − ψ²τ₃ = b(ψ)`, `τ₂ − ψ²τ₄ = c(ψ)` (which avoid
/// a cancellation at large ψ):
/// `A = xI ± x²b K + x³c K²`,
/// `B = ±x²b Q + x³c P₂ − 2σx⁴(±τ₃ K + xτ₄ K²)`.
#[inline(always)]
fn tangent_blocks(x: f64, xi: &Vec6, b: f64, c: f64, t3: f64, t4: f64, sign: f64) -> AdOp {
    let kv = angular(xi);
    let q = linear(xi);
    let th2 = kv.norm_squared();
    let sigma = kv.dot(&q);
    let x2 = x * x;
    let x3 = x2 * x;
    let x4 = x2 * x2;
    let cb = sign * x2 * b;
    let cc = x3 * c;
    let s = 2.0 * sigma * x4;
    let s3 = s * (sign * t3);
    let s4 = s * (x * t4);
    // Split into symmetric parts (from K² = kkᵀ − θ²I and P₂) and skew parts
    // (from K and Q): A = xI + cc K² + (cb k)~,
    // B = cc P₂ − s₄ K² + (cb q − s₃ k)~, each mirrored pair sharing products.
    let (k0, k1, k2) = (kv[0], kv[1], kv[2]);
    let (q0, q1, q2) = (q[0], q[1], q[2]);
    let kk = [k0 * k1, k0 * k2, k1 * k2];
    let kkd = [k0 * k0 - th2, k1 * k1 - th2, k2 * k2 - th2];
    let p2 = [k0 * q1 + q0 * k1, k0 * q2 + q0 * k2, k1 * q2 + q1 * k2];
    let two_sigma = 2.0 * sigma;
    let p2d = [
        2.0 * (k0 * q0) - two_sigma,
        2.0 * (k1 * q1) - two_sigma,
        2.0 * (k2 * q2) - two_sigma,
    ];
    AdOp {
        a: sym_plus_skew(
            [x + kkd[0] * cc, x + kkd[1] * cc, x + kkd[2] * cc],
            [kk[0] * cc, kk[1] * cc, kk[2] * cc],
            &(kv * cb),
        ),
        b: sym_plus_skew(
            [
                p2d[0] * cc - kkd[0] * s4,
                p2d[1] * cc - kkd[1] * s4,
                p2d[2] * cc - kkd[2] * s4,
            ],
            [
                p2[0] * cc - kk[0] * s4,
                p2[1] * cc - kk[1] * s4,
                p2[2] * cc - kk[2] * s4,
            ],
            &(q * cb - kv * s3),
        ),
    }
}

/// `exp(x·ad_ξ) = Ad_{exp(x ξ̂)}` (D2), built from (D4) as
/// `[[R, 0], [p̃R, R]]`, which is cheaper than the quartic in `ad_ξ` and as
/// accurate. `Ad⁻¹_{g_n(x)} = exp(−x·ad_ξ)` is `exp_twist(x, ξ).ad_inv()`.
#[inline]
pub fn exp_ad(x: f64, xi: &Vec6) -> AdOp {
    exp_twist(x, xi).ad()
}

/// Tangent operator `T(x) = ∫₀ˣ exp(l·ad_ξ) dl = Σ_{i=0}^{4} x^{i+1} τ_i(ψ) ad_ξ^i`
/// (D3), `τ₀ = 1`.
///
/// Accuracy: coefficients ≤ 6e-16 relative on both sides of the switch.
#[inline]
pub fn tangent(x: f64, xi: &Vec6) -> AdOp {
    let ([_, b, c], [t3, t4]) = series::abc_tau34(x * angular(xi).norm());
    tangent_blocks(x, xi, b, c, t3, t4, 1.0)
}

/// `T₋(x) = Ad⁻¹_{g_n(x)} T(x) = ∫₀ˣ exp(−u·ad_ξ) du
/// = Σ (−1)^i x^{i+1} τ_i(ψ) ad_ξ^i` (D3′): the local Jacobian operator,
/// `S_n(x) = T₋(x) B_n` (D8).
#[inline]
pub fn tangent_minus(x: f64, xi: &Vec6) -> AdOp {
    let ([_, b, c], [t3, t4]) = series::abc_tau34(x * angular(xi).norm());
    tangent_blocks(x, xi, b, c, t3, t4, -1.0)
}

/// `exp(x·ξ̂)` and `T₋(x)` together, sharing the trigonometry: the two maps
/// a PCS kinematics sweep needs at every evaluation point.
#[inline(always)]
pub fn exp_and_tangent_minus(x: f64, xi: &Vec6) -> (Pose, AdOp) {
    let ([a, b, c], [t3, t4]) = series::abc_tau34(x * angular(xi).norm());
    (
        exp_twist_with(x, xi, a, b, c),
        tangent_blocks(x, xi, b, c, t3, t4, -1.0),
    )
}

/// Directional derivative of `T(x)` with respect to the strain (D6):
/// `D_ξ T(x)\[δ\] = Σ_{i=1}^{4} ( x^{i+3} ρ_i(ψ) (k·δ_k) ad_ξ^i
///   + x^{i+1} τ_i(ψ) Σ_{j=0}^{i−1} ad_ξ^j ad_δ ad_ξ^{i−1−j} )`.
///
/// Accuracy: ~1e-15 relative (ρ_i ≤ 4e-15).
pub fn d_tangent(x: f64, xi: &Vec6, delta: &Vec6) -> AdOp {
    d_tangent_signed(x, xi, delta, 1.0)
}

/// Directional derivative of `T₋(x)` (D6 with the i-th term times `(−1)^i`).
/// With `δ = B_n q̇_n` this is the factor of the true `Ṡ_n(x) = D_ξT₋(x)[B_n q̇_n] B_n` (D9).
pub fn d_tangent_minus(x: f64, xi: &Vec6, delta: &Vec6) -> AdOp {
    d_tangent_signed(x, xi, delta, -1.0)
}

fn d_tangent_signed(x: f64, xi: &Vec6, delta: &Vec6, sign: f64) -> AdOp {
    let kv = angular(xi);
    let (t, r) = series::tau_rho(x * kv.norm());
    let kd = kv.dot(&angular(delta));
    let pw = AdPowers::new(xi);
    let d = AdOp::ad(delta);
    // E_1 = ad_δ, E_{i+1} = ad_ξ E_i + ad_δ ad_ξ^i (block-wise).
    let mut e = d;
    let mut out = AdOp::zeros();
    let mut xp = x * x; // x^{i+1}
    let mut sgn = sign;
    for i in 0..4 {
        let cr = sgn * xp * x * x * r[i] * kd;
        let ct = sgn * xp * t[i];
        out.a += pw.k[i] * cr + e.a * ct;
        out.b += pw.p[i] * cr + e.b * ct;
        if i < 3 {
            let ad_i = AdOp {
                a: pw.k[i],
                b: pw.p[i],
            };
            let ad1 = AdOp {
                a: pw.k[0],
                b: pw.p[0],
            };
            e = ad1 * e + d * ad_i;
        }
        xp *= x;
        sgn *= sign;
    }
    out
}

/// The vector `D_ξT₋(x)[δ] δ`, which is all the dynamics needs: with
/// `δ = B_n q̇_n` it is `Ṡ_n(x) q̇_n` (D9, D10). Uses only cross products:
/// `v_i = ad^i δ`, `w_m = ad_δ v_m`, `e₂ = w₁`, `e_{i+1} = w_i + ad e_i`
/// (the `j = i−1` term of (D6) vanishes because `ad_δ δ = 0`).
pub fn d_tangent_minus_self(x: f64, xi: &Vec6, delta: &Vec6) -> Vec6 {
    let kv = angular(xi);
    let (t, r) = series::tau_rho(x * kv.norm());
    let kd = kv.dot(&angular(delta));
    let v1 = ad_vec(xi, delta);
    let v2 = ad_vec(xi, &v1);
    let v3 = ad_vec(xi, &v2);
    let v4 = ad_vec(xi, &v3);
    let e2 = ad_vec(delta, &v1);
    let e3 = ad_vec(delta, &v2) + ad_vec(xi, &e2);
    let e4 = ad_vec(delta, &v3) + ad_vec(xi, &e3);
    let x2 = x * x;
    let x3 = x2 * x;
    let x4 = x2 * x2;
    let x5 = x4 * x;
    let x6 = x3 * x3;
    let x7 = x6 * x;
    // (−1)^i signs for T₋.
    v1 * (-x4 * r[0] * kd) + (v2 * (x5 * r[1] * kd) + e2 * (x3 * t[1]))
        - (v3 * (x6 * r[2] * kd) + e3 * (x4 * t[2]))
        + (v4 * (x7 * r[3] * kd) + e4 * (x5 * t[3]))
}

/// Directional derivative of `exp(x·ad_ξ)` with respect to the strain:
/// from `exp(x·ad_ξ) = I + ad_ξ T(x)`,
/// `D_ξ exp(x·ad_ξ)[δ] = ad_δ T(x) + ad_ξ D_ξT(x)[δ]`.
pub fn d_exp_ad(x: f64, xi: &Vec6, delta: &Vec6) -> AdOp {
    AdOp::ad(delta) * tangent(x, xi) + AdOp::ad(xi) * d_tangent(x, xi, delta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::ad;
    use crate::types::Mat6;

    fn xi() -> Vec6 {
        Vec6::new(0.3, -1.1, 0.7, 1.05, 0.2, -0.1)
    }

    #[test]
    fn exp_ad_is_identity_plus_ad_tangent() {
        for x in [0.0, 0.1, 1.0, 4.0] {
            let lhs = exp_ad(x, &xi()).to_mat6();
            let rhs = Mat6::identity() + ad(&xi()) * tangent(x, &xi()).to_mat6();
            assert!((lhs - rhs).amax() < 1e-13, "x = {x}");
        }
    }

    #[test]
    fn self_derivative_matches_matrix_form() {
        let d = Vec6::new(0.2, 0.1, -0.4, 0.3, -0.5, 0.9);
        for x in [0.0, 0.3, 2.0, 7.0] {
            let m = d_tangent_minus(x, &xi(), &d).mul_vec(&d);
            let v = d_tangent_minus_self(x, &xi(), &d);
            assert!((m - v).amax() < 1e-13 * (1.0 + m.amax()), "x = {x}");
        }
    }
}
