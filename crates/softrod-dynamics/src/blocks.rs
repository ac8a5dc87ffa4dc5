//! 6×6 matrices kept as 3×3 blocks for the inward recursions.
//!
//! Every operator the recursions apply to an inertia — `A_ℓ = Ad⁻¹_{g(ℓ)}`,
//! `T₋(ℓ)` — has the block form [`AdOp`] `[[a, 0], [b, a]]`, and every
//! inertia is symmetric. Working on the blocks skips the structural zeros
//! and the duplicated diagonal block: `M·X` is six 3×3 products instead of
//! the eight of a dense 6×6 product, `Xᵀ(MX)` five when the result is
//! symmetric.

use softrod_lie::{AdOp, Mat3, Mat6, Vec6};
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
    #[inline]
    pub fn from_mat6(m: &Mat6) -> Self {
        Self {
            a: m.fixed_view::<3, 3>(0, 0).into_owned(),
            b: m.fixed_view::<3, 3>(0, 3).into_owned(),
            c: m.fixed_view::<3, 3>(3, 3).into_owned(),
        }
    }

    /// Dense form.
    #[inline]
    pub fn dense(&self) -> Mat6 {
        let mut m = Mat6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.a);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.b);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.b.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.c);
        m
    }

    /// `self · x` for a block operator `x = [[xa, 0], [xb, xa]]`.
    #[inline]
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
    #[inline]
    pub fn mul_vec(&self, v: &Vec6) -> Vec6 {
        let w = softrod_lie::angular(v);
        let u = softrod_lie::linear(v);
        softrod_lie::join(
            &(self.a * w + self.b * u),
            &(self.b.tr_mul(&w) + self.c * u),
        )
    }

    /// The congruence `xᵀ · self · x` (symmetric): eleven 3×3 products.
    #[inline]
    pub fn congruence(&self, x: &AdOp) -> Sym6 {
        Blk6::tr_premul_sym(x, &self.mul_op(x))
    }
}

impl Blk6 {
    /// Dense form.
    #[inline]
    pub fn dense(&self) -> Mat6 {
        let mut m = Mat6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.m11);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.m12);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.m21);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.m22);
        m
    }

    /// `xᵀ · y` for a block operator `x = [[xa, 0], [xb, xa]]`.
    #[inline]
    pub fn tr_premul(x: &AdOp, y: &Blk6) -> Blk6 {
        Blk6 {
            m11: x.a.tr_mul(&y.m11) + x.b.tr_mul(&y.m21),
            m12: x.a.tr_mul(&y.m12) + x.b.tr_mul(&y.m22),
            m21: x.a.tr_mul(&y.m21),
            m22: x.a.tr_mul(&y.m22),
        }
    }

    /// `xᵀ · y` where the caller knows the product is symmetric (`y = M x`
    /// with `M` symmetric): the lower-left block is not computed.
    #[inline]
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
    #[inline]
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
    #[inline]
    fn sub(self, o: Sym6) -> Sym6 {
        Sym6 {
            a: self.a - o.a,
            b: self.b - o.b,
            c: self.c - o.c,
        }
    }
}

impl AddAssign for Sym6 {
    #[inline]
    fn add_assign(&mut self, o: Sym6) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }
}

impl SubAssign for Sym6 {
    #[inline]
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
        let tp = Blk6::tr_premul(&x, &my);
        let tpd = xm.transpose() * myd;
        let c = s.congruence(&x);
        let cd = xm.transpose() * m * xm;
        for i in 0..6 {
            for j in 0..6 {
                assert_relative_eq!(my.get(i, j), myd[(i, j)], epsilon = 1e-13);
                assert_relative_eq!(tp.get(i, j), tpd[(i, j)], epsilon = 1e-13);
                assert_relative_eq!(c.get(i, j), cd[(i, j)], epsilon = 1e-13);
            }
        }
        let v = Vec6::from_fn(|i, _| (i as f64).cos());
        assert_relative_eq!(s.mul_vec(&v), m * v, epsilon = 1e-13);
    }
}
