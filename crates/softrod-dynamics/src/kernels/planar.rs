//! The planar (se(2)) arithmetic of the planar path (docs/theory.md §13,
//! D71–D75): poses of SE(2) as cosine, sine and a plane translation, the
//! planar blocks of `Ad`, `ad`, `ad*`, the exponential and tangent maps of
//! a piece with their `θ`-series (D72–D73), and the 3×3 Cholesky of a
//! piece's block. The sweeps that use them are in `crate::algorithms::planar`.

use nalgebra::Vector2;
use softrod_lie::{Mat3, Vec3};

pub(crate) type V2 = Vector2<f64>;

/// An element of SE(2): rotation by the angle with cosine `c`, sine `s`
/// about the bending axis, translation `p` in the plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pose2 {
    pub(crate) c: f64,
    pub(crate) s: f64,
    pub(crate) p: V2,
}

/// `J u`, the quarter turn: `e_a × u` for `u` in the plane.
#[inline(always)]
pub(crate) fn perp(u: &V2) -> V2 {
    V2::new(-u[1], u[0])
}

/// `(αI + βJ) u`.
#[inline(always)]
pub(crate) fn rot_like(alpha: f64, beta: f64, u: &V2) -> V2 {
    V2::new(alpha * u[0] - beta * u[1], beta * u[0] + alpha * u[1])
}

/// The scalar (out-of-plane) cross product `u × w · e_a`.
#[inline(always)]
pub(crate) fn cross2(u: &V2, w: &V2) -> f64 {
    u[0] * w[1] - u[1] * w[0]
}

#[inline(always)]
pub(crate) fn lin(v: &Vec3) -> V2 {
    V2::new(v[1], v[2])
}

#[inline(always)]
pub(crate) fn join(w: f64, v: V2) -> Vec3 {
    Vec3::new(w, v[0], v[1])
}

impl Pose2 {
    pub(crate) const IDENTITY: Self = Self {
        c: 1.0,
        s: 0.0,
        p: V2::new(0.0, 0.0),
    };

    #[inline(always)]
    pub(crate) fn rot(&self, u: &V2) -> V2 {
        rot_like(self.c, self.s, u)
    }

    #[inline(always)]
    pub(crate) fn rot_tr(&self, u: &V2) -> V2 {
        rot_like(self.c, -self.s, u)
    }

    #[inline(always)]
    pub(crate) fn compose(&self, o: &Self) -> Self {
        Self {
            c: self.c * o.c - self.s * o.s,
            s: self.s * o.c + self.c * o.s,
            p: self.p + self.rot(&o.p),
        }
    }

    /// `Ad⁻¹_g η = (ω, Rᵀ(v + ω J p))`, the planar block of (D4).
    #[inline(always)]
    pub(crate) fn ad_inv_vec(&self, eta: &Vec3) -> Vec3 {
        let w = eta[0];
        join(w, self.rot_tr(&(lin(eta) + perp(&self.p) * w)))
    }

    /// `Ad⁻ᵀ_g 𝓕 = (M + p × RF, RF)`: a wrench carried from the frame `g`
    /// to its reference.
    #[inline(always)]
    pub(crate) fn ad_inv_tr_vec(&self, f: &Vec3) -> Vec3 {
        let rf = self.rot(&lin(f));
        join(f[0] + cross2(&self.p, &rf), rf)
    }

    /// `Ad⁻¹_g` as a matrix: `[[1, 0], [RᵀJp, Rᵀ]]`.
    #[inline(always)]
    pub(crate) fn ad_inv(&self) -> Mat3 {
        let h = self.rot_tr(&perp(&self.p));
        Mat3::new(1.0, 0.0, 0.0, h[0], self.c, self.s, h[1], -self.s, self.c)
    }
}

/// `ad_a b` in `P`: `(0, ω_a J v_b − ω_b J v_a)`.
#[inline(always)]
pub(crate) fn ad2(a: &Vec3, b: &Vec3) -> Vec3 {
    join(0.0, perp(&lin(b)) * a[0] - perp(&lin(a)) * b[0])
}

/// `ad*_η 𝓕 = (v × F, ω J F)` in `P` (the moment of the planar force and
/// its rotation with the section).
#[inline(always)]
pub(crate) fn coad2(eta: &Vec3, f: &Vec3) -> Vec3 {
    let fl = lin(f);
    join(cross2(&lin(eta), &fl), perp(&fl) * eta[0])
}

/// Horner in `u`.
#[inline(always)]
pub(crate) fn horner(c: &[f64], u: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * u + k)
}

// Taylor coefficients in u = θ² (D73): a = sinθ/θ, c = (1 − cosθ)/θ²,
// d/θ = (θ − sinθ)/θ³, a'/θ, c'/θ, d'. Ten terms leave < 1e-17 at |θ| = 1.
const SA: [f64; 10] = [
    1.0,
    -0.16666666666666666,
    0.008333333333333333,
    -0.0001984126984126984,
    2.7557319223985893e-06,
    -2.505210838544172e-08,
    1.6059043836821613e-10,
    -7.647163731819816e-13,
    2.8114572543455206e-15,
    -8.22063524662433e-18,
];
const SC: [f64; 10] = [
    0.5,
    -0.041666666666666664,
    0.001388888888888889,
    -2.48015873015873e-05,
    2.755731922398589e-07,
    -2.08767569878681e-09,
    1.1470745597729725e-11,
    -4.779477332387385e-14,
    1.5619206968586225e-16,
    -4.110317623312165e-19,
];
const SD: [f64; 10] = [
    0.16666666666666666,
    -0.008333333333333333,
    0.0001984126984126984,
    -2.7557319223985893e-06,
    2.505210838544172e-08,
    -1.6059043836821613e-10,
    7.647163731819816e-13,
    -2.8114572543455206e-15,
    8.22063524662433e-18,
    -1.9572941063391263e-20,
];
const SA1: [f64; 9] = [
    -0.3333333333333333,
    0.03333333333333333,
    -0.0011904761904761906,
    2.2045855379188714e-05,
    -2.505210838544172e-07,
    1.9270852604185937e-09,
    -1.0706029224547743e-11,
    4.498331606952833e-14,
    -1.4797143443923793e-16,
];
const SC1: [f64; 9] = [
    -0.08333333333333333,
    0.005555555555555556,
    -0.00014880952380952382,
    2.204585537918871e-06,
    -2.08767569878681e-08,
    1.376489471727567e-10,
    -6.691268265342339e-13,
    2.499073114973796e-15,
    -7.398571721961897e-18,
];
const SD1: [f64; 10] = [
    0.16666666666666666,
    -0.025,
    0.000992063492063492,
    -1.9290123456790123e-05,
    2.2546897546897547e-07,
    -1.7664948220503776e-09,
    9.941312851365761e-12,
    -4.217185881518281e-14,
    1.3975079919261362e-16,
    -3.7188588020443397e-19,
];

/// The functions of `θ` in the planar exponential, tangent and its
/// derivative (D72–D73), with their `θ`-derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coeffs {
    pub cos: f64,
    pub sin: f64,
    pub a: f64,
    pub b: f64,
    pub c: f64,
    pub d: f64,
    pub da: f64,
    pub db: f64,
    pub dc: f64,
    pub dd: f64,
}

impl Coeffs {
    /// Series for `|θ| < 1` (the closed forms lose up to `1e-16/θ⁴` to
    /// cancellation in `c'`), closed forms beyond. Below `|θ| = 1/4` the
    /// first six terms suffice: the first one left out is below `1e-17` of
    /// the leading term in every series (`|SA₆| u⁶ ≤ 1.6e-10 · 16⁻⁶ = 9.6e-18`,
    /// the others smaller), under the rounding of the sum.
    #[inline(always)]
    pub(crate) fn new(theta: f64) -> Self {
        let u = theta * theta;
        if u < 0.0625 {
            Self::series::<6>(theta, u)
        } else if u < 1.0 {
            Self::series::<10>(theta, u)
        } else {
            let (s, co) = theta.sin_cos();
            let (t2, t3) = (u, u * theta);
            let c = (1.0 - co) / t2;
            let dc = (theta * s - 2.0 * (1.0 - co)) / t3;
            Self {
                cos: co,
                sin: s,
                a: s / theta,
                b: theta * c,
                c,
                d: (theta - s) / t2,
                da: (theta * co - s) / t2,
                db: c + theta * dc,
                dc,
                dd: (2.0 * s - theta - theta * co) / t3,
            }
        }
    }

    /// The series branch on the first `N ≤ 9` (or all ten) terms.
    #[inline(always)]
    fn series<const N: usize>(theta: f64, u: f64) -> Self {
        let n1 = N.min(SA1.len());
        let a = horner(&SA[..N], u);
        let c = horner(&SC[..N], u);
        let dc = theta * horner(&SC1[..n1], u);
        Self {
            cos: 1.0 - u * c,
            sin: theta * a,
            a,
            b: theta * c,
            c,
            d: theta * horner(&SD[..N], u),
            da: theta * horner(&SA1[..n1], u),
            db: c + theta * dc,
            dc,
            dd: horner(&SD1[..N], u),
        }
    }
}

/// The planar piece maps at `x` for the strain `ξ = (ω, v)` and its rate
/// `ξ̇ = (ω̇, v̇)` (D72–D74): `g(x) = exp(xξ)`, `T₋(x)` and
/// `∂_ξ(T₋ξ̇)[ξ̇]`, the strain-rate part of the velocity bias.
#[inline(always)]
pub(crate) fn maps(xi: &Vec3, dxi: &Vec3, x: f64, with_bias: bool) -> (Pose2, Mat3, Vec3) {
    let w = xi[0];
    let v = lin(xi);
    let k = Coeffs::new(w * x);
    let g = Pose2 {
        c: k.cos,
        s: k.sin,
        p: rot_like(k.a, k.b, &v) * x,
    };
    let x2 = x * x;
    let col = rot_like(k.d, k.c, &v) * x2;
    let (xa, xb) = (x * k.a, x * k.b);
    let t = Mat3::new(x, 0.0, 0.0, col[0], xa, xb, col[1], -xb, xa);
    let bias = if with_bias {
        let wd = dxi[0];
        let vd = lin(dxi);
        join(
            0.0,
            rot_like(k.dd, k.dc, &v) * (x2 * x * wd * wd)
                + rot_like(k.d + k.da, k.c - k.db, &vd) * (x2 * wd),
        )
    } else {
        Vec3::zeros()
    };
    (g, t, bias)
}

/// `diag(d) M`.
#[inline(always)]
pub(crate) fn scale_rows(d: &Vec3, m: &Mat3) -> Mat3 {
    Mat3::from_fn(|i, j| d[i] * m[(i, j)])
}

/// Running sums of one piece's planar inertia integrals (D20 in `P`):
/// `𝓤ᶠ = Σ wAᵀMT₋`, `𝓓ᶠ = Σ wT₋ᵀMT₋`, `𝓜ᵗ = Σ wAᵀMA` for `A = Ad⁻¹_g` and
/// `T₋` as [`maps`] returns them, `M = diag(J_a, m_b, m_c)`.
///
/// Both operators have the form `[[α, 0], [u, Q]]` with a rotation-like
/// 2×2 `Q`: `A = [[1, 0], [h, Rᵀ]]` (`h = RᵀJp`) and `T₋ = [[x, 0], [t, L]]`
/// (`L = x(aI − bJ)`). With the isotropic linear inertia `m_b = m_c = m`
/// of every Cosserat section the products are
/// `AᵀMT₋ = [[J x + m h·t, m hᵀL], [m Rt, m RL]]`,
/// `T₋ᵀMT₋ = [[J x² + m|t|², m tᵀL], [m Lᵀt, m|L|² I]]` (`LᵀL` is a multiple
/// of `I`) and `AᵀMA = [[J + m|h|², m (Rh)ᵀ], [m Rh, m I]]` (`RRᵀ = I`):
/// fifteen distinct scalars and about 40 multiplications per point where
/// the three dense products take ~110 and 27 sums. Equal to them to
/// round-off; other inertias take the dense products.
#[derive(Default)]
pub(crate) struct PlanarSums {
    /// `𝓤ᶠ`: `(0,0)`, `(0,1..3)`, `(1..3,0)`, and `RL = [[p, r], [−r, p]]`.
    u00: f64,
    u0: V2,
    u1: V2,
    up: f64,
    ur: f64,
    /// `𝓓ᶠ`: `(0,0)`, `(0,1..3)` (= `(1..3,0)`), the diagonal `m|L|²`.
    d00: f64,
    d0: V2,
    dl: f64,
    /// `𝓜ᵗ`: `(0,0)`, `(0,1..3)` (= `(1..3,0)`), `Σ m`.
    m00: f64,
    m0: V2,
    mass: f64,
    /// The dense sums of points with `m_b ≠ m_c`.
    dense: Option<(Mat3, Mat3, Mat3)>,
}

impl PlanarSums {
    /// Adds one point, the weight already in `mw = w·(J_a, m_b, m_c)`.
    #[inline(always)]
    pub(crate) fn add(&mut self, g: &Pose2, t: &Mat3, mw: &Vec3) {
        let (mj, m) = (mw[0], mw[1]);
        if m != mw[2] {
            self.add_dense(g, t, mw);
            return;
        }
        let h = g.rot_tr(&perp(&g.p));
        let x = t[(0, 0)];
        let tc = V2::new(t[(1, 0)], t[(2, 0)]);
        let (al, be) = (t[(1, 1)], t[(1, 2)]);
        let mh = h * m;
        let mtc = tc * m;
        // vᵀL = (α v₀ − β v₁, β v₀ + α v₁).
        let tr_l = |v: &V2| V2::new(al * v[0] - be * v[1], be * v[0] + al * v[1]);
        // R L = [[p, r], [−r, p]] for R = [[c, −s], [s, c]].
        let (c, s) = (g.c, g.s);
        self.u00 += mj * x + mh.dot(&tc);
        self.u0 += tr_l(&mh);
        self.u1 += g.rot(&mtc);
        self.up += (c * al + s * be) * m;
        self.ur += (c * be - s * al) * m;
        self.d00 += mj * x * x + mtc.dot(&tc);
        self.d0 += tr_l(&mtc);
        self.dl += m * (al * al + be * be);
        self.m00 += mj + mh.dot(&h);
        self.m0 += g.rot(&mh);
        self.mass += m;
    }

    /// The dense products, for a point whose linear inertia is not
    /// isotropic in the plane.
    #[inline(never)]
    fn add_dense(&mut self, g: &Pose2, t: &Mat3, mw: &Vec3) {
        let a = g.ad_inv();
        let (uf, df, mt) = self.dense.get_or_insert_with(Default::default);
        *uf += a.tr_mul(&scale_rows(mw, t));
        *df += t.tr_mul(&scale_rows(mw, t));
        *mt += a.tr_mul(&scale_rows(mw, &a));
    }

    /// `(𝓤ᶠ, 𝓓ᶠ, 𝓜ᵗ)` as dense 3×3 matrices.
    #[inline(always)]
    pub(crate) fn finish(&self) -> (Mat3, Mat3, Mat3) {
        let uf = Mat3::new(
            self.u00, self.u0[0], self.u0[1], self.u1[0], self.up, self.ur, self.u1[1], -self.ur,
            self.up,
        );
        let df = Mat3::new(
            self.d00, self.d0[0], self.d0[1], self.d0[0], self.dl, 0.0, self.d0[1], 0.0, self.dl,
        );
        let mt = Mat3::new(
            self.m00, self.m0[0], self.m0[1], self.m0[0], self.mass, 0.0, self.m0[1], 0.0,
            self.mass,
        );
        match &self.dense {
            Some((u, d, m)) => (uf + u, df + d, mt + m),
            None => (uf, df, mt),
        }
    }
}

/// In-place Cholesky of the leading `k×k` block; `false` if not positive
/// definite.
pub(crate) fn cholesky(m: &mut Mat3, k: usize) -> bool {
    for j in 0..k {
        let mut d = m[(j, j)];
        for p in 0..j {
            d -= m[(j, p)] * m[(j, p)];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        m[(j, j)] = d;
        for i in (j + 1)..k {
            let mut s = m[(i, j)];
            for p in 0..j {
                s -= m[(i, p)] * m[(j, p)];
            }
            m[(i, j)] = s / d;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// The coefficients against their definitions, on both sides of the
    /// switch and where the closed forms are well conditioned.
    #[test]
    fn coefficients_match_definitions() {
        for &t in &[1e-9, 0.3, 0.999_999, 1.000_001, 2.5, -4.0, 40.0] {
            let k = Coeffs::new(t);
            let (s, c) = (t.sin(), t.cos());
            let tol = 1e-14;
            assert_relative_eq!(k.cos, c, epsilon = tol);
            assert_relative_eq!(k.sin, s, epsilon = tol);
            assert_relative_eq!(k.a, s / t, epsilon = tol);
            if t.abs() > 0.1 {
                assert_relative_eq!(k.c, (1.0 - c) / (t * t), epsilon = 1e-12);
                assert_relative_eq!(k.d, (t - s) / (t * t), epsilon = 1e-12);
            }
            // Derivatives against central differences of the values.
            let h = 1e-5;
            let (kp, km) = (Coeffs::new(t + h), Coeffs::new(t - h));
            for (d, p, m) in [
                (k.da, kp.a, km.a),
                (k.db, kp.b, km.b),
                (k.dc, kp.c, km.c),
                (k.dd, kp.d, km.d),
            ] {
                assert_relative_eq!(d, (p - m) / (2.0 * h), epsilon = 1e-9);
            }
        }
    }

    /// The six-term series below |θ| = 1/4 against all ten terms: equal to
    /// the rounding of the sums (relative 2.3e-16 of each value's scale).
    #[test]
    fn short_series_equals_the_full_one() {
        for i in 0..=400 {
            let t = -0.25 + 0.5 * f64::from(i) / 400.0;
            if t * t >= 0.0625 {
                continue;
            }
            let (short, full) = (
                Coeffs::series::<6>(t, t * t),
                Coeffs::series::<10>(t, t * t),
            );
            assert_eq!(Coeffs::new(t), short);
            let pairs = [
                (short.cos, full.cos, 1.0),
                (short.sin, full.sin, t.abs()),
                (short.a, full.a, 1.0),
                (short.b, full.b, 0.5 * t.abs()),
                (short.c, full.c, 0.5),
                (short.d, full.d, t.abs() / 6.0),
                (short.da, full.da, t.abs() / 3.0),
                (short.db, full.db, 1.5),
                (short.dc, full.dc, t.abs() / 12.0),
                (short.dd, full.dd, 1.0 / 6.0),
            ];
            for (s, f, scale) in pairs {
                assert!((s - f).abs() <= 2.3e-16 * scale, "θ = {t}: {s} vs {f}");
            }
        }
    }

    /// [`PlanarSums`] against the dense products `AᵀMT₋`, `T₋ᵀMT₋`,
    /// `AᵀMA` they replace, for isotropic and anisotropic linear inertias
    /// and a mix of both along a piece.
    #[test]
    fn planar_sums_equal_the_dense_products() {
        let xi = Vec3::new(1.7, 1.05, -0.2);
        let dxi = Vec3::new(0.3, -0.1, 0.4);
        let inertias = [
            Vec3::new(0.3, 2.0, 2.0),
            Vec3::new(0.3, 2.0, 2.5),
            Vec3::new(1e-3, 0.7, 0.7),
        ];
        for mix in [&inertias[..1], &inertias[1..2], &inertias[..]] {
            let mut sums = PlanarSums::default();
            let (mut uf, mut df, mut mt) = (Mat3::zeros(), Mat3::zeros(), Mat3::zeros());
            for (i, x) in [0.05, 0.21, 0.33, 0.48].into_iter().enumerate() {
                let (g, t, _) = maps(&xi, &dxi, x, false);
                let mw = mix[i % mix.len()] * (0.1 + 0.2 * x);
                sums.add(&g, &t, &mw);
                let a = g.ad_inv();
                uf += a.transpose() * Mat3::from_diagonal(&mw) * t;
                df += t.transpose() * Mat3::from_diagonal(&mw) * t;
                mt += a.transpose() * Mat3::from_diagonal(&mw) * a;
            }
            let (u, d, m) = sums.finish();
            assert_relative_eq!(u, uf, epsilon = 1e-15);
            assert_relative_eq!(d, df, epsilon = 1e-15);
            assert_relative_eq!(m, mt, epsilon = 1e-15);
        }
    }
}
