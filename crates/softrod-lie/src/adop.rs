//! The block structure shared by every function of `ad_ξ`.

use crate::pose::Pose;
use crate::types::{Mat3, Mat6, Vec3, Vec6, angular, join, linear};
use std::ops::{Add, Mul, Sub};

/// A 6×6 matrix of the form `[[A, 0], [B, A]]` (3×3 blocks).
///
/// `ad_ξ`, every power of it, and so every analytic function of `x·ad_ξ`
/// (`exp(x·ad_ξ)`, `T(x)`, `T₋(x)`, their strain derivatives) and every
/// adjoint `Ad_g = [[R, 0], [p̃R, R]]` have this form, and the form is closed
/// under products: `(A,B)(C,D) = (AC, BC + AD)`. Keeping the two blocks
/// instead of a dense `Mat6` halves the storage and costs 3 instead of 8
/// 3×3 products per composition, 27 instead of 36 multiplications per
/// matrix–vector product.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdOp {
    /// Diagonal block `A` (acts angular→angular and linear→linear).
    pub a: Mat3,
    /// Lower-left block `B` (acts angular→linear).
    pub b: Mat3,
}

impl AdOp {
    /// `[[Aᵀ, 0], [Bᵀ, Aᵀ]]`, the blockwise transpose (not the 6×6
    /// transpose). For the tangent operators of a constant strain it maps
    /// `T₋(x)` to `T₊(x) = Ad_{g(x)}T₋(x)`: the sign of `ξ` flips exactly
    /// the skew parts of both blocks.
    #[inline(always)]
    pub fn transpose_blocks(&self) -> AdOp {
        AdOp {
            a: self.a.transpose(),
            b: self.b.transpose(),
        }
    }

    /// The identity `I₆`.
    #[inline]
    pub fn identity() -> Self {
        Self {
            a: Mat3::identity(),
            b: Mat3::zeros(),
        }
    }

    /// The zero matrix.
    #[inline]
    pub fn zeros() -> Self {
        Self {
            a: Mat3::zeros(),
            b: Mat3::zeros(),
        }
    }

    /// `ad_ξ = [[k̃, 0], [q̃, k̃]]` in block form.
    #[inline]
    pub fn ad(xi: &Vec6) -> Self {
        Self {
            a: crate::skew(&angular(xi)),
            b: crate::skew(&linear(xi)),
        }
    }

    /// `self · v = (A v_ω, B v_ω + A v_v)`.
    #[inline(always)]
    pub fn mul_vec(&self, v: &Vec6) -> Vec6 {
        let w = angular(v);
        join(&(self.a * w), &(self.b * w + self.a * linear(v)))
    }

    /// `selfᵀ · f = (Aᵀ f_M + Bᵀ f_N, Aᵀ f_N)`, the transpose applied without
    /// transposing; this is how `Ad*` and `Sᵀ` act on wrenches.
    #[inline(always)]
    pub fn tr_mul_vec(&self, f: &Vec6) -> Vec6 {
        let m = angular(f);
        let n = linear(f);
        join(&(self.a.tr_mul(&m) + self.b.tr_mul(&n)), &self.a.tr_mul(&n))
    }

    /// Dense 6×6 matrix.
    pub fn to_mat6(&self) -> Mat6 {
        let mut m = Mat6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.a);
        m.fixed_view_mut::<3, 3>(3, 0).copy_from(&self.b);
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.a);
        m
    }

    /// Reads the blocks of a dense matrix assumed to have this form (the
    /// upper-right block and the difference of the diagonal blocks are
    /// ignored; use only where the form is known to hold).
    pub fn from_mat6(m: &Mat6) -> Self {
        Self {
            a: m.fixed_view::<3, 3>(0, 0).into_owned(),
            b: m.fixed_view::<3, 3>(3, 0).into_owned(),
        }
    }

    /// Inverse `[[A⁻¹, 0], [−A⁻¹BA⁻¹, A⁻¹]]`, `None` if `A` is singular.
    pub fn try_inverse(&self) -> Option<Self> {
        let ai = self.a.try_inverse()?;
        Some(Self {
            a: ai,
            b: -(ai * self.b * ai),
        })
    }

    /// `self · s` for a scalar.
    #[inline]
    pub fn scale(&self, s: f64) -> Self {
        Self {
            a: self.a * s,
            b: self.b * s,
        }
    }

    /// `self · Ad⁻¹_g` for a pose `g = (R, p)`, without forming `Ad⁻¹_g`:
    /// with `Ad⁻¹_g = [[Rᵀ, 0], [−Rᵀp̃, Rᵀ]]` the product is
    /// `(A Rᵀ, B Rᵀ − (A Rᵀ) p̃)`, and `M p̃` is a combination of the columns
    /// of `M` (column j is `M (p × e_j)`): 72 multiplications instead of 81.
    #[inline]
    pub fn mul_ad_inv(&self, g: &Pose) -> AdOp {
        let rt = g.rotation.transpose();
        let a = self.a * rt;
        let p = &g.translation;
        let (c0, c1, c2) = (a.column(0), a.column(1), a.column(2));
        let ap = Mat3::from_columns(&[
            c1 * p[2] - c2 * p[1],
            c2 * p[0] - c0 * p[2],
            c0 * p[1] - c1 * p[0],
        ]);
        AdOp {
            a,
            b: self.b * rt - ap,
        }
    }

    /// Applies `self` to the 3-vector pair `(w, v)` given separately.
    #[inline(always)]
    pub fn mul_parts(&self, w: &Vec3, v: &Vec3) -> (Vec3, Vec3) {
        (self.a * w, self.b * w + self.a * v)
    }
}

impl Mul for AdOp {
    type Output = AdOp;
    #[inline]
    fn mul(self, rhs: AdOp) -> AdOp {
        AdOp {
            a: self.a * rhs.a,
            b: self.b * rhs.a + self.a * rhs.b,
        }
    }
}

impl Mul<&AdOp> for &AdOp {
    type Output = AdOp;
    #[inline]
    fn mul(self, rhs: &AdOp) -> AdOp {
        *self * *rhs
    }
}

impl Mul<Vec6> for AdOp {
    type Output = Vec6;
    #[inline]
    fn mul(self, v: Vec6) -> Vec6 {
        self.mul_vec(&v)
    }
}

impl Add for AdOp {
    type Output = AdOp;
    #[inline]
    fn add(self, rhs: AdOp) -> AdOp {
        AdOp {
            a: self.a + rhs.a,
            b: self.b + rhs.b,
        }
    }
}

impl Sub for AdOp {
    type Output = AdOp;
    #[inline]
    fn sub(self, rhs: AdOp) -> AdOp {
        AdOp {
            a: self.a - rhs.a,
            b: self.b - rhs.b,
        }
    }
}

impl From<AdOp> for Mat6 {
    fn from(op: AdOp) -> Mat6 {
        op.to_mat6()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mul_ad_inv_equals_the_product_with_ad_inv() {
        let xis = [
            Vec6::new(0.3, -1.1, 0.7, 1.05, 0.2, -0.1),
            Vec6::new(1e-9, 0.0, 2e-9, 0.9, 0.01, 0.0),
            Vec6::new(12.0, -30.0, 5.0, 1.2, -0.3, 0.4),
        ];
        let c = AdOp {
            a: Mat3::new(0.3, -0.2, 0.9, 1.1, 0.5, -0.7, 0.2, 0.4, 0.8),
            b: Mat3::new(-1.3, 0.6, 0.1, 0.0, 2.5, -0.4, 0.9, -0.8, 0.3),
        };
        for xi in &xis {
            for x in [0.0, 0.4, 3.0] {
                let mut g = crate::exp_twist(x, xi);
                g.translation += Vec3::new(5.0, -2.0, 0.5);
                let dense = c * g.ad_inv();
                let fast = c.mul_ad_inv(&g);
                let scale = 1.0 + dense.a.amax() + dense.b.amax();
                assert!((fast.a - dense.a).amax() < 1e-15 * scale);
                assert!((fast.b - dense.b).amax() < 4e-15 * scale, "{xi:?} {x}");
            }
        }
    }
}
