//! Independent references for the softrod-lie tests: a dense matrix
//! exponential by scaling and squaring + Taylor, in `f64` and in double-double
//! arithmetic (~32 significant digits), Van Loan block constructions built on
//! it, composite Gauss–Legendre quadrature, and a seeded PRNG.
//!
//! Nothing here calls into `softrod_lie` except the trivial `ad`/`hat`
//! matrices, which are rebuilt by hand (`ad_ref`, `hat_ref`) so that a sign or
//! ordering error in the crate cannot cancel against the reference.
#![allow(dead_code)]

use nalgebra as na;
use std::ops::{Add, Mul, Neg, Sub};

pub type Mat6 = na::Matrix6<f64>;
pub type Mat4 = na::Matrix4<f64>;
pub type Vec6 = na::Vector6<f64>;
pub type Vec3 = na::Vector3<f64>;

// ---------------------------------------------------------------------------
// Double-double arithmetic (Dekker / Knuth error-free transformations).
// ---------------------------------------------------------------------------

/// An unevaluated sum `hi + lo`, `|lo| ≤ ulp(hi)/2`: ~106 bits of mantissa.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dd {
    pub hi: f64,
    pub lo: f64,
}

#[inline(always)]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

#[inline(always)]
fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

#[inline(always)]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl Dd {
    pub const ZERO: Dd = Dd { hi: 0.0, lo: 0.0 };
    pub const ONE: Dd = Dd { hi: 1.0, lo: 0.0 };

    pub fn new(x: f64) -> Self {
        Dd { hi: x, lo: 0.0 }
    }

    /// The exact product of two doubles.
    pub fn prod(a: f64, b: f64) -> Self {
        let (p, e) = two_prod(a, b);
        Dd { hi: p, lo: e }
    }

    /// Division by a double.
    pub fn div_f64(self, d: f64) -> Self {
        let q1 = self.hi / d;
        let r = self - Dd::prod(q1, d);
        let q2 = r.hi / d;
        let r = r - Dd::prod(q2, d);
        let q3 = r.hi / d;
        let (s, e) = quick_two_sum(q1, q2);
        Dd { hi: s, lo: e } + Dd::new(q3)
    }
}

impl Add for Dd {
    type Output = Dd;
    #[inline(always)]
    fn add(self, b: Dd) -> Dd {
        let (s1, s2) = two_sum(self.hi, b.hi);
        let (t1, t2) = two_sum(self.lo, b.lo);
        let (s1, s2) = quick_two_sum(s1, s2 + t1);
        let (hi, lo) = quick_two_sum(s1, s2 + t2);
        Dd { hi, lo }
    }
}

impl Neg for Dd {
    type Output = Dd;
    #[inline(always)]
    fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
}

impl Sub for Dd {
    type Output = Dd;
    #[inline(always)]
    fn sub(self, b: Dd) -> Dd {
        self + (-b)
    }
}

impl Mul for Dd {
    type Output = Dd;
    #[inline(always)]
    fn mul(self, b: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, b.hi);
        let e = e + (self.hi * b.lo + self.lo * b.hi);
        let (hi, lo) = quick_two_sum(p, e);
        Dd { hi, lo }
    }
}

/// What the generic matrix exponential needs of its scalar.
pub trait Scalar:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    fn zero() -> Self;
    fn one() -> Self;
    fn to_f64(self) -> f64;
    fn div_int(self, k: u32) -> Self;
    /// Multiplication by a power of two (exact).
    fn scale2(self, s: f64) -> Self;
}

impl Scalar for f64 {
    fn zero() -> Self {
        0.0
    }
    fn one() -> Self {
        1.0
    }
    fn to_f64(self) -> f64 {
        self
    }
    fn div_int(self, k: u32) -> Self {
        self / k as f64
    }
    fn scale2(self, s: f64) -> Self {
        self * s
    }
}

impl Scalar for Dd {
    fn zero() -> Self {
        Dd::ZERO
    }
    fn one() -> Self {
        Dd::ONE
    }
    fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
    fn div_int(self, k: u32) -> Self {
        self.div_f64(k as f64)
    }
    fn scale2(self, s: f64) -> Self {
        Dd {
            hi: self.hi * s,
            lo: self.lo * s,
        }
    }
}

// ---------------------------------------------------------------------------
// Dense square matrices and the reference exponential.
// ---------------------------------------------------------------------------

/// A dense `n×n` matrix, row-major.
#[derive(Clone, Debug)]
pub struct Mat<S> {
    pub n: usize,
    pub d: Vec<S>,
}

impl<S: Scalar> Mat<S> {
    pub fn zeros(n: usize) -> Self {
        Mat {
            n,
            d: vec![S::zero(); n * n],
        }
    }
    pub fn identity(n: usize) -> Self {
        let mut m = Self::zeros(n);
        for i in 0..n {
            m.d[i * n + i] = S::one();
        }
        m
    }
    #[inline(always)]
    pub fn at(&self, i: usize, j: usize) -> S {
        self.d[i * self.n + j]
    }
    #[inline(always)]
    pub fn set(&mut self, i: usize, j: usize, v: S) {
        self.d[i * self.n + j] = v;
    }
    pub fn mul(&self, b: &Self) -> Self {
        let n = self.n;
        let mut c = Self::zeros(n);
        for i in 0..n {
            for k in 0..n {
                let a = self.d[i * n + k];
                if a.to_f64() == 0.0 {
                    continue; // the block matrices are sparse; zero is exact
                }
                for j in 0..n {
                    c.d[i * n + j] = c.d[i * n + j] + a * b.d[k * n + j];
                }
            }
        }
        c
    }
    /// ∞-norm (max row sum), only used to choose the scaling.
    pub fn norm_inf(&self) -> f64 {
        (0..self.n)
            .map(|i| {
                (0..self.n)
                    .map(|j| self.at(i, j).to_f64().abs())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max)
    }
    /// The `r×c` block at `(i0, j0)`, rounded to `f64`.
    pub fn block_f64(&self, i0: usize, j0: usize, r: usize, c: usize) -> na::DMatrix<f64> {
        na::DMatrix::from_fn(r, c, |i, j| self.at(i0 + i, j0 + j).to_f64())
    }
    pub fn block6(&self, i0: usize, j0: usize) -> Mat6 {
        Mat6::from_fn(|i, j| self.at(i0 + i, j0 + j).to_f64())
    }
    /// Copies a 6×6 `f64` matrix multiplied by `x` into the block at `(i0, j0)`,
    /// the products `x·m_ij` formed exactly.
    pub fn put6(&mut self, i0: usize, j0: usize, x: f64, m: &Mat6, from: fn(f64, f64) -> S) {
        for i in 0..6 {
            for j in 0..6 {
                self.set(i0 + i, j0 + j, from(x, m[(i, j)]));
            }
        }
    }
}

/// Exact-product constructors for the two scalar types.
pub fn f64_prod(a: f64, b: f64) -> f64 {
    a * b
}
pub fn dd_prod(a: f64, b: f64) -> Dd {
    Dd::prod(a, b)
}

/// Number of Taylor terms of the reference exponential. With the scaled
/// matrix of norm ≤ 1/2 the truncation is ≤ 2·0.5²¹/21! ≈ 2e-26 relative.
pub const TAYLOR_TERMS: u32 = 20;

/// `expm(A)` by scaling and squaring: `A/2^s` with `‖A/2^s‖∞ ≤ 1/2`, Taylor
/// to [`TAYLOR_TERMS`] terms (Horner: `I + A/1 (I + A/2 (I + …))`), then `s`
/// squarings.
pub fn expm<S: Scalar>(a: &Mat<S>) -> Mat<S> {
    let n = a.n;
    let norm = a.norm_inf();
    let mut s = 0i32;
    while norm * 0.5f64.powi(s) > 0.5 {
        s += 1;
    }
    let f = 0.5f64.powi(s);
    let a = Mat {
        n,
        d: a.d.iter().map(|v| v.scale2(f)).collect(),
    };
    let id = Mat::<S>::identity(n);
    let mut p = id.clone();
    for k in (1..=TAYLOR_TERMS).rev() {
        let mut ap = a.mul(&p);
        for v in ap.d.iter_mut() {
            *v = v.div_int(k);
        }
        for i in 0..n {
            ap.d[i * n + i] = ap.d[i * n + i] + S::one();
        }
        p = ap;
    }
    for _ in 0..s {
        p = p.mul(&p);
    }
    p
}

// ---------------------------------------------------------------------------
// se(3) matrices, rebuilt by hand from the conventions of docs/theory.md §0.2.
// ---------------------------------------------------------------------------

pub fn skew_ref(v: &Vec3) -> na::Matrix3<f64> {
    na::Matrix3::new(0.0, -v[2], v[1], v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// `ad_ξ = [[k̃, 0], [q̃, k̃]]` (angular first).
pub fn ad_ref(xi: &Vec6) -> Mat6 {
    let k = skew_ref(&Vec3::new(xi[0], xi[1], xi[2]));
    let q = skew_ref(&Vec3::new(xi[3], xi[4], xi[5]));
    let mut m = Mat6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&q);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&k);
    m
}

/// `ξ̂ = [[k̃, q], [0, 0]]`.
pub fn hat_ref(xi: &Vec6) -> Mat4 {
    let k = skew_ref(&Vec3::new(xi[0], xi[1], xi[2]));
    let mut m = Mat4::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&k);
    m[(0, 3)] = xi[3];
    m[(1, 3)] = xi[4];
    m[(2, 3)] = xi[5];
    m
}

fn mat_from_small<S: Scalar, const R: usize>(
    x: f64,
    m: &na::SMatrix<f64, R, R>,
    from: fn(f64, f64) -> S,
) -> Mat<S> {
    let mut out = Mat::zeros(R);
    for i in 0..R {
        for j in 0..R {
            out.set(i, j, from(x, m[(i, j)]));
        }
    }
    out
}

/// `expm(x·ξ̂)` (4×4), double-double.
pub fn ref_exp_hat(x: f64, xi: &Vec6) -> Mat4 {
    let e = expm(&mat_from_small(x, &hat_ref(xi), dd_prod));
    Mat4::from_fn(|i, j| e.at(i, j).to_f64())
}

/// `expm(x·ad_ξ)` (6×6), double-double.
pub fn ref_exp_ad_dd(x: f64, xi: &Vec6) -> Mat<Dd> {
    expm(&mat_from_small(x, &ad_ref(xi), dd_prod))
}

pub fn ref_exp_ad(x: f64, xi: &Vec6) -> Mat6 {
    ref_exp_ad_dd(x, xi).block6(0, 0)
}

/// `expm(x·ad_ξ)` in plain `f64` (for the quadrature integrands).
pub fn ref_exp_ad_f64(x: f64, xi: &Vec6) -> Mat6 {
    expm(&mat_from_small(x, &ad_ref(xi), f64_prod)).block6(0, 0)
}

/// Van Loan: the upper-right block of `expm([[x·ad_ξ, x·I], [0, 0]])` is
/// `∫₀ˣ exp(l·ad_ξ) dl = T(x)`. `T₋(x, ξ) = T(x, −ξ)` since `ad_{−ξ} = −ad_ξ`.
pub fn ref_tangent_dd(x: f64, xi: &Vec6) -> Mat<Dd> {
    let mut m = Mat::<Dd>::zeros(12);
    m.put6(0, 0, x, &ad_ref(xi), dd_prod);
    m.put6(0, 6, x, &Mat6::identity(), dd_prod);
    let e = expm(&m);
    let mut t = Mat::zeros(6);
    for i in 0..6 {
        for j in 0..6 {
            t.set(i, j, e.at(i, 6 + j));
        }
    }
    t
}

pub fn ref_tangent(x: f64, xi: &Vec6) -> Mat6 {
    ref_tangent_dd(x, xi).block6(0, 0)
}

/// Same Van Loan construction in plain `f64`.
pub fn ref_tangent_f64(x: f64, xi: &Vec6) -> Mat6 {
    let mut m = Mat::<f64>::zeros(12);
    m.put6(0, 0, x, &ad_ref(xi), f64_prod);
    m.put6(0, 6, x, &Mat6::identity(), f64_prod);
    expm(&m).block6(0, 6)
}

/// `T₋(x)` as the double-double product `exp(−x·ad_ξ) · T(x)`.
pub fn ref_tangent_minus_product(x: f64, xi: &Vec6) -> Mat6 {
    ref_exp_ad_dd(-x, xi)
        .mul(&ref_tangent_dd(x, xi))
        .block6(0, 0)
}

/// Strain derivative `D_ξT[δ]` (sign = +1) or `D_ξT₋[δ]` (sign = −1) by the
/// three-block Van Loan construction: for
/// `Z = [[σA, σΔ, 0], [0, σA, I], [0, 0, 0]]` (`A = ad_ξ`, `Δ = ad_δ`, σ = sign),
/// the (1,3) block of `expm(x·Z)` is
/// `∫₀ˣ e^{σ(x−l)A} σΔ ∫₀ˡ e^{σuA} du dl`, i.e. `σ∫₀ˣ e^{σ(x−l)A} Δ T_σ(l) dl`,
/// which is the quadrature form of docs/theory.md (D6) (it solves
/// `∂_x D T_σ = σ(Δ T_σ + A D T_σ)`, from `∂_x T_σ = I + σ A T_σ`).
pub fn ref_d_tangent(x: f64, xi: &Vec6, delta: &Vec6, sign: f64) -> Mat6 {
    let a = ad_ref(xi) * sign;
    let d = ad_ref(delta) * sign;
    let mut m = Mat::<Dd>::zeros(18);
    m.put6(0, 0, x, &a, dd_prod);
    m.put6(0, 6, x, &d, dd_prod);
    m.put6(6, 6, x, &a, dd_prod);
    m.put6(6, 12, x, &Mat6::identity(), dd_prod);
    expm(&m).block6(0, 12)
}

/// Fréchet derivative of `exp(x·ad_ξ)` in direction `δ`: the upper-right
/// block of `expm([[x·A, x·Δ], [0, x·A]])`.
pub fn ref_d_exp_ad(x: f64, xi: &Vec6, delta: &Vec6) -> Mat6 {
    let mut m = Mat::<Dd>::zeros(12);
    m.put6(0, 0, x, &ad_ref(xi), dd_prod);
    m.put6(0, 6, x, &ad_ref(delta), dd_prod);
    m.put6(6, 6, x, &ad_ref(xi), dd_prod);
    expm(&m).block6(0, 6)
}

// ---------------------------------------------------------------------------
// Gauss–Legendre quadrature.
// ---------------------------------------------------------------------------

/// Nodes and weights of the `n`-point Gauss–Legendre rule on [−1, 1]
/// (Newton on the Legendre recurrence, converged to machine precision).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = n as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-17 {
                break;
            }
        }
        out.push((z, 2.0 / ((1.0 - z * z) * dp * dp)));
    }
    out
}

/// Composite `n`-point Gauss–Legendre of a matrix-valued `f` over `[0, x]`
/// on `panels` equal panels.
pub fn quad<F: FnMut(f64) -> Mat6>(x: f64, panels: usize, n: usize, mut f: F) -> Mat6 {
    let rule = gauss_legendre(n);
    let h = x / panels as f64;
    let mut acc = Mat6::zeros();
    for p in 0..panels {
        let a = p as f64 * h;
        let mut panel = Mat6::zeros();
        for &(z, w) in &rule {
            panel += f(a + 0.5 * h * (z + 1.0)) * w;
        }
        acc += panel * (0.5 * h);
    }
    acc
}

/// Panels so that each covers at most half a radian of rotation: with 10
/// points the rule is exact for the polynomial factor (degree ≤ 4) of the
/// integrand and its error on the oscillating factor is ~ (h θ/2)^20/20! ≲ 1e-25.
pub fn panels_for(x: f64, xi: &Vec6) -> usize {
    let theta = Vec3::new(xi[0], xi[1], xi[2]).norm();
    ((2.0 * x * theta).ceil() as usize).max(1)
}

pub const GL_POINTS: usize = 10;

/// `T(x)` (sign +1) or `T₋(x)` (sign −1) by composite quadrature of the
/// double-double `expm` (rounded to `f64` at each node).
pub fn quad_tangent(x: f64, xi: &Vec6, sign: f64) -> Mat6 {
    quad(x, panels_for(x, xi), GL_POINTS, |l| {
        ref_exp_ad(sign * l, xi)
    })
}

/// `D_ξT₋(x)[δ] = −∫₀ˣ exp(−(x−l) ad_ξ) ad_δ T₋(l) dl` (docs/theory.md §1),
/// with the double-double `expm` and Van Loan `T₋` inside.
pub fn quad_d_tangent_minus(x: f64, xi: &Vec6, delta: &Vec6) -> Mat6 {
    let d = ad_ref(delta);
    let mxi = -*xi;
    quad(x, panels_for(x, xi), GL_POINTS, |l| {
        -(ref_exp_ad(-(x - l), xi) * d * ref_tangent(l, &mxi))
    })
}

// ---------------------------------------------------------------------------
// Errors and random numbers.
// ---------------------------------------------------------------------------

/// `max|a − ref| / max(1, max|ref|)`.
pub fn rel_err<const R: usize, const C: usize>(
    a: &na::SMatrix<f64, R, C>,
    reference: &na::SMatrix<f64, R, C>,
) -> f64 {
    (a - reference).amax() / reference.amax().max(1.0)
}

/// SplitMix64: a tiny seeded generator, so the test inputs are reproducible
/// without a dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [−1, 1).
    pub fn sym(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    pub fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.sym(), self.sym(), self.sym())
    }
    pub fn unit3(&mut self) -> Vec3 {
        loop {
            let v = self.vec3();
            let n = v.norm();
            if n > 0.2 && n <= 1.0 {
                return v / n;
            }
        }
    }
    pub fn vec6(&mut self) -> Vec6 {
        Vec6::new(
            self.sym(),
            self.sym(),
            self.sym(),
            self.sym(),
            self.sym(),
            self.sym(),
        )
    }
}
