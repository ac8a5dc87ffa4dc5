//! Dense 6×6 products inlined where they are used.
//!
//! nalgebra's generic `Mat6 * Mat6` and `tr_mul` are out-of-line calls:
//! inside the AVX2 copies of [`super::simd`] they run as the baseline
//! build's code behind a call and a copy of the result. These are the same
//! products, `#[inline(always)]`, in the same order of operations as
//! nalgebra's (`C[:, j] = Σ_k A[:, k] B[k, j]`, `k` ascending; a product
//! by `Aᵀ` sums the same terms in the same order as its dot products):
//! the results are nalgebra's, bit for bit (tested below; a product that
//! is exactly zero may differ in the sign of the zero).

use softrod_lie::Mat6;

/// `A B`.
#[inline(always)]
pub(crate) fn mm(a: &Mat6, b: &Mat6) -> Mat6 {
    let (a, b) = (a.as_slice(), b.as_slice());
    let mut c = [0.0f64; 36];
    for j in 0..6 {
        let mut col = [0.0f64; 6];
        let s = b[6 * j];
        for i in 0..6 {
            col[i] = a[i] * s;
        }
        for k in 1..6 {
            let s = b[6 * j + k];
            for i in 0..6 {
                col[i] += a[6 * k + i] * s;
            }
        }
        c[6 * j..6 * j + 6].copy_from_slice(&col);
    }
    Mat6::from_column_slice(&c)
}

/// `Aᵀ B`.
#[inline(always)]
pub(crate) fn tm(a: &Mat6, b: &Mat6) -> Mat6 {
    mm(&a.transpose(), b)
}

/// `A B C`, left to right (as `a * b * c`).
#[inline(always)]
pub(crate) fn mm3(a: &Mat6, b: &Mat6, c: &Mat6) -> Mat6 {
    mm(&mm(a, b), c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seeded(seed: f64) -> Mat6 {
        Mat6::from_fn(|i, j| {
            ((seed + 1.7 * i as f64 + 0.37 * (j * j) as f64).sin())
                * 1e3f64.powf((i as f64 - j as f64) / 6.0)
        })
    }

    /// The same IEEE operations as nalgebra's products: equal bit for bit.
    #[test]
    fn products_equal_nalgebra_bitwise() {
        for s in 0..20 {
            let (a, b, c) = (
                seeded(s as f64),
                seeded(0.3 + s as f64),
                seeded(1.1 * s as f64),
            );
            assert_eq!(mm(&a, &b), a * b);
            assert_eq!(tm(&a, &b), a.tr_mul(&b));
            assert_eq!(tm(&a, &b), a.transpose() * b);
            assert_eq!(mm3(&a, &b, &c), a * b * c);
        }
    }
}
