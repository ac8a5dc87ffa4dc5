//! 6×6 matrices kept as 3×3 blocks for the inward recursions.
//!
//! The operators the recursions apply to an inertia have structure: `T₋(ℓ)`
//! has the block form [`AdOp`] `[[a, 0], [b, a]]`, and `A_ℓ = Ad⁻¹_{g(ℓ)}` is
//! a rigid transform, applied from `g = (R, p)` as a rotation and a shift
//! (cross products) without forming it. Every inertia is symmetric, so
//! only its upper blocks are kept and symmetric products compute their
//! upper halves.

use softrod_lie::{AdOp, Mat3, Mat6, Pose, Vec3, Vec6};
use std::ops::{Add, AddAssign, Sub, SubAssign};

/// `a₁ᵀb₁ + a₂ᵀb₂` for a sum the caller knows to be symmetric: the six
/// upper entries as column dots, mirrored (a third fewer multiplications
/// than two full products).
#[inline(always)]
pub(crate) fn tr_mul_sym2(a1: &Mat3, b1: &Mat3, a2: &Mat3, b2: &Mat3) -> Mat3 {
    let e = |i: usize, j: usize| a1.column(i).dot(&b1.column(j)) + a2.column(i).dot(&b2.column(j));
    let (m00, m01, m02, m11, m12, m22) = (e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2));
    Mat3::new(m00, m01, m02, m01, m11, m12, m02, m12, m22)
}

/// `aᵀb` known to be symmetric: six dots, mirrored.
#[inline(always)]
pub(crate) fn tr_mul_sym(a: &Mat3, b: &Mat3) -> Mat3 {
    let e = |i: usize, j: usize| a.column(i).dot(&b.column(j));
    let (m00, m01, m02, m11, m12, m22) = (e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2));
    Mat3::new(m00, m01, m02, m01, m11, m12, m02, m12, m22)
}

/// `x yᵀ` known to be symmetric: six row dots, mirrored.
#[inline(always)]
pub(crate) fn mul_tr_sym(x: &Mat3, y: &Mat3) -> Mat3 {
    let e = |i: usize, j: usize| x.row(i).dot(&y.row(j));
    let (m00, m01, m02, m11, m12, m22) = (e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2));
    Mat3::new(m00, m01, m02, m01, m11, m12, m02, m12, m22)
}

/// The upper triangle of `m` mirrored into the lower one.
#[inline(always)]
fn upper_mirrored(m: &Mat3) -> Mat3 {
    Mat3::new(
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(0, 1)],
        m[(1, 1)],
        m[(1, 2)],
        m[(0, 2)],
        m[(1, 2)],
        m[(2, 2)],
    )
}

/// `p̃ X`, column by column as cross products (18 multiplications).
#[inline(always)]
pub(crate) fn cross_cols(p: &Vec3, x: &Mat3) -> Mat3 {
    Mat3::from_columns(&[
        p.cross(&x.column(0)),
        p.cross(&x.column(1)),
        p.cross(&x.column(2)),
    ])
}

/// `Ad⁻¹_g η = (Rᵀω, Rᵀ(v − p × ω))` for `g = (R, p)`, without building the
/// operator.
#[inline(always)]
pub(crate) fn ad_inv_vec(g: &Pose, eta: &Vec6) -> Vec6 {
    let w = softrod_lie::angular(eta);
    let v = softrod_lie::linear(eta);
    softrod_lie::join(
        &g.rotation.tr_mul(&w),
        &g.rotation.tr_mul(&(v - g.translation.cross(&w))),
    )
}

/// `(Ad⁻¹_g)ᵀ f = (R f_M + p × R f_N, R f_N)`: a wrench carried from the
/// frame `g` back to the frame it is expressed relative to.
#[inline(always)]
pub(crate) fn ad_inv_tr_vec(g: &Pose, f: &Vec6) -> Vec6 {
    let rn = g.rotation * softrod_lie::linear(f);
    softrod_lie::join(
        &(g.rotation * softrod_lie::angular(f) + g.translation.cross(&rn)),
        &rn,
    )
}

/// A symmetric 6×6 matrix `[[a, b], [bᵀ, c]]`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Sym6 {
    pub a: Mat3,
    pub b: Mat3,
    pub c: Mat3,
}

/// A general 6×6 matrix `[[m11, m12], [m21, m22]]`.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Blk6 {
    pub m11: Mat3,
    pub m12: Mat3,
    pub m21: Mat3,
    pub m22: Mat3,
}

impl Sym6 {
    /// Reads the upper blocks of a matrix known to be symmetric.
    #[inline(always)]
    pub fn from_mat6(m: &Mat6) -> Self {
        Self {
            a: m.fixed_view::<3, 3>(0, 0).into_owned(),
            b: m.fixed_view::<3, 3>(0, 3).into_owned(),
            c: m.fixed_view::<3, 3>(3, 3).into_owned(),
        }
    }

    /// Dense form.
    #[inline(always)]
    pub fn dense(&self) -> Mat6 {
        let mut m = Mat6::zeros();
        self.write_dense(&mut m);
        m
    }

    /// `m += self` (dense `m`).
    #[inline(always)]
    pub fn add_to(&self, m: &mut Mat6) {
        let mut v = m.fixed_view_mut::<3, 3>(0, 0);
        v += self.a;
        let mut v = m.fixed_view_mut::<3, 3>(0, 3);
        v += self.b;
        let mut v = m.fixed_view_mut::<3, 3>(3, 0);
        v += self.b.transpose();
        let mut v = m.fixed_view_mut::<3, 3>(3, 3);
        v += self.c;
    }

    /// `W Wᵀ` for a 6×6 `W` (rows split 3 + 3): exactly symmetric, the
    /// diagonal blocks by their upper halves.
    #[inline(always)]
    pub fn gram_rows(w: &Mat6) -> Sym6 {
        let w1 = w.fixed_rows::<3>(0);
        let w2 = w.fixed_rows::<3>(3);
        let sym = |x: &nalgebra::MatrixView<
            f64,
            nalgebra::U3,
            nalgebra::U6,
            nalgebra::U1,
            nalgebra::U6,
        >| {
            let e = |i: usize, j: usize| x.row(i).dot(&x.row(j));
            let (m00, m01, m02, m11, m12, m22) =
                (e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2));
            Mat3::new(m00, m01, m02, m01, m11, m12, m02, m12, m22)
        };
        Sym6 {
            a: sym(&w1),
            b: w1 * w2.transpose(),
            c: sym(&w2),
        }
    }

    /// Writes the dense form into `m`.
    #[inline(always)]
    pub fn write_dense(&self, m: &mut Mat6) {
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.a);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.b);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.b.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.c);
    }

    /// `self · x` for a block operator `x = [[xa, 0], [xb, xa]]`.
    #[inline(always)]
    pub fn mul_op(&self, x: &AdOp) -> Blk6 {
        let y12 = self.b * x.a;
        Blk6 {
            m11: self.a * x.a + self.b * x.b,
            m12: y12,
            m21: self.b.tr_mul(&x.a) + self.c * x.b,
            m22: self.c * x.a,
        }
    }

    /// `self · v`.
    #[inline(always)]
    pub fn mul_vec(&self, v: &Vec6) -> Vec6 {
        let w = softrod_lie::angular(v);
        let u = softrod_lie::linear(v);
        softrod_lie::join(
            &(self.a * w + self.b * u),
            &(self.b.tr_mul(&w) + self.c * u),
        )
    }

    /// The congruence `(Ad⁻¹_g)ᵀ · self · Ad⁻¹_g` for `g = (R, p)`, the
    /// rigid transform of an inertia: rotate the blocks (`R a Rᵀ`, `R b Rᵀ`,
    /// `R c Rᵀ`), then shift by `p`: with `[[I, p̃], [0, I]]` on the left and
    /// its transpose on the right, `b ← b + p̃c`, `a ← a + p̃bᵀ + b p̃ᵀ +
    /// p̃ c p̃ᵀ`. About 200 multiplications instead of the ~280 of the
    /// generic block congruence; exactly symmetric.
    #[inline(always)]
    pub fn congruence_ad_inv(&self, g: &Pose) -> Sym6 {
        let r = &g.rotation;
        let p = &g.translation;
        let a1 = mul_tr_sym(&(r * self.a), r);
        let b1 = (r * self.b) * r.transpose();
        let c1 = mul_tr_sym(&(r * self.c), r);
        let pc = cross_cols(p, &c1);
        let b2 = b1 + pc;
        let x = cross_cols(p, &b1.transpose());
        // p̃ c p̃ᵀ = p̃ (p̃ c)ᵀ for symmetric c.
        let z = cross_cols(p, &pc.transpose());
        Sym6 {
            a: upper_mirrored(&(a1 + x + x.transpose() + z)),
            b: b2,
            c: c1,
        }
    }
}

impl Blk6 {
    /// `m += self` (dense `m`).
    #[inline(always)]
    pub fn add_to(&self, m: &mut Mat6) {
        let mut v = m.fixed_view_mut::<3, 3>(0, 0);
        v += self.m11;
        let mut v = m.fixed_view_mut::<3, 3>(0, 3);
        v += self.m12;
        let mut v = m.fixed_view_mut::<3, 3>(3, 0);
        v += self.m21;
        let mut v = m.fixed_view_mut::<3, 3>(3, 3);
        v += self.m22;
    }

    /// Dense form.
    #[inline(always)]
    pub fn dense(&self) -> Mat6 {
        let mut m = Mat6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.m11);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.m12);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.m21);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.m22);
        m
    }

    /// `xᵀ · y` where the caller knows the product is symmetric (`y = M x`
    /// with `M` symmetric): the lower-left block is not computed.
    #[inline(always)]
    pub fn tr_premul_sym(x: &AdOp, y: &Blk6) -> Sym6 {
        Sym6 {
            a: tr_mul_sym2(&x.a, &y.m11, &x.b, &y.m21),
            b: x.a.tr_mul(&y.m12) + x.b.tr_mul(&y.m22),
            c: tr_mul_sym(&x.a, &y.m22),
        }
    }

    /// Entry `(i, j)`, `0 ≤ i, j < 6` (for the tests).
    #[cfg(test)]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        match (i < 3, j < 3) {
            (true, true) => self.m11[(i, j)],
            (true, false) => self.m12[(i, j - 3)],
            (false, true) => self.m21[(i - 3, j)],
            (false, false) => self.m22[(i - 3, j - 3)],
        }
    }
}

impl Sym6 {
    /// Entry `(i, j)`, `0 ≤ i, j < 6` (for the tests).
    #[cfg(test)]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        match (i < 3, j < 3) {
            (true, true) => self.a[(i, j)],
            (true, false) => self.b[(i, j - 3)],
            (false, true) => self.b[(j, i - 3)],
            (false, false) => self.c[(i - 3, j - 3)],
        }
    }
}

impl Add for Sym6 {
    type Output = Sym6;
    #[inline(always)]
    fn add(self, o: Sym6) -> Sym6 {
        Sym6 {
            a: self.a + o.a,
            b: self.b + o.b,
            c: self.c + o.c,
        }
    }
}

impl Sub for Sym6 {
    type Output = Sym6;
    #[inline(always)]
    fn sub(self, o: Sym6) -> Sym6 {
        Sym6 {
            a: self.a - o.a,
            b: self.b - o.b,
            c: self.c - o.c,
        }
    }
}

impl AddAssign for Sym6 {
    #[inline(always)]
    fn add_assign(&mut self, o: Sym6) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }
}

impl SubAssign for Sym6 {
    #[inline(always)]
    fn sub_assign(&mut self, o: Sym6) {
        self.a -= o.a;
        self.b -= o.b;
        self.c -= o.c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn op(seed: f64) -> AdOp {
        AdOp {
            a: Mat3::from_fn(|i, j| ((i * 3 + j) as f64 * 0.7 + seed).sin()),
            b: Mat3::from_fn(|i, j| ((i * 5 + j) as f64 * 1.3 + seed).cos()),
        }
    }

    fn sym(seed: f64) -> Mat6 {
        let g = Mat6::from_fn(|i, j| ((i * 6 + j) as f64 * 0.37 + seed).sin());
        g.transpose() * g
    }

    #[test]
    fn block_products_equal_dense_products() {
        let m = sym(0.3);
        let s = Sym6::from_mat6(&m);
        assert_relative_eq!(s.dense(), m, max_relative = 1e-15);
        let x = op(1.1);
        let y = op(-0.4);
        let xm = x.to_mat6();
        let ym = y.to_mat6();
        let my = s.mul_op(&y);
        let myd = m * ym;
        let c = Blk6::tr_premul_sym(&x, &s.mul_op(&x));
        let cd = xm.transpose() * m * xm;
        for i in 0..6 {
            for j in 0..6 {
                assert_relative_eq!(my.get(i, j), myd[(i, j)], epsilon = 1e-13);
                assert_relative_eq!(c.get(i, j), cd[(i, j)], epsilon = 1e-13);
            }
        }
        let v = Vec6::from_fn(|i, _| (i as f64).cos());
        assert_relative_eq!(s.mul_vec(&v), m * v, epsilon = 1e-13);
        let g = Sym6::gram_rows(&xm);
        assert_relative_eq!(g.dense(), xm * xm.transpose(), epsilon = 1e-13);
        let mut acc = xm;
        s.add_to(&mut acc);
        my.add_to(&mut acc);
        assert_relative_eq!(acc, xm + m + myd, epsilon = 1e-13);
        // Rigid forms against the dense Ad⁻¹_g, including a far-off p.
        for (axis, p) in [
            (Vec3::new(0.3, -1.2, 0.5), Vec3::new(0.1, 0.2, -0.3)),
            (Vec3::new(2.0, 0.1, -0.4), Vec3::new(-3.0, 40.0, 7.0)),
        ] {
            let g = Pose::new(*nalgebra::Rotation3::new(axis).matrix(), p);
            let ai = g.ad_inv().to_mat6();
            let cong = s.congruence_ad_inv(&g);
            let cd = ai.transpose() * m * ai;
            let scale = cd.amax();
            for i in 0..6 {
                for j in 0..6 {
                    assert_relative_eq!(cong.get(i, j), cd[(i, j)], epsilon = 1e-13 * scale);
                }
            }
            assert_eq!(cong.a, cong.a.transpose());
            assert_relative_eq!(ad_inv_vec(&g, &v), ai * v, epsilon = 1e-12);
            assert_relative_eq!(ad_inv_tr_vec(&g, &v), ai.transpose() * v, epsilon = 1e-12);
        }
    }
}
