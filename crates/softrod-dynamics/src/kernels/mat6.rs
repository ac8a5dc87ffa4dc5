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
    mm_part(a, b, 6, 6)
}

/// The leading `rows × cols` block of `A B` (the rest zero): `A B` itself
/// when the rows of `A` from `rows` on and the columns of `B` from `cols`
/// on are zero, each computed entry with nalgebra's operations.
#[inline(always)]
pub(crate) fn mm_part(a: &Mat6, b: &Mat6, rows: usize, cols: usize) -> Mat6 {
    let (a, b) = (a.as_slice(), b.as_slice());
    let mut c = [0.0f64; 36];
    for j in 0..cols {
        let mut col = [0.0f64; 6];
        let s = b[6 * j];
        for i in 0..rows {
            col[i] = a[i] * s;
        }
        for k in 1..6 {
            let s = b[6 * j + k];
            for i in 0..rows {
                col[i] += a[6 * k + i] * s;
            }
        }
        c[6 * j..6 * j + 6].copy_from_slice(&col);
    }
    Mat6::from_column_slice(&c)
}

/// [`mm_part`] with the block's size known at compile time (the loops
/// unrolled): the leading `R × C` block of `A B`, the rest zero.
#[inline(always)]
pub(crate) fn mmk<const R: usize, const C: usize>(a: &Mat6, b: &Mat6) -> Mat6 {
    let (a, b) = (a.as_slice(), b.as_slice());
    let mut c = Mat6::zeros();
    let cs = c.as_mut_slice();
    for j in 0..C {
        let mut col = [0.0f64; R];
        let s = b[6 * j];
        for i in 0..R {
            col[i] = a[i] * s;
        }
        for k in 1..6 {
            let s = b[6 * j + k];
            for i in 0..R {
                col[i] += a[6 * k + i] * s;
            }
        }
        cs[6 * j..6 * j + R].copy_from_slice(&col);
    }
    c
}

/// `A B` for `A`, `B` of the form `[[X, 0], [Y, X]]` (3×3 blocks; `ad_v`
/// and the sums and products of such, the algebra of (D32)–(D35)), whose
/// product is `[[X₁X₂, 0], [Y₁X₂ + X₁Y₂, X₁X₂]]`: 3 instead of 8 3×3 block
/// products, each entry summed in [`mm`]'s order without its zero terms
/// (the same numbers up to the sign of a zero).
#[inline(always)]
pub(crate) fn mm_lower(a: &Mat6, b: &Mat6) -> Mat6 {
    let (a, b) = (a.as_slice(), b.as_slice());
    let mut c = [0.0f64; 36];
    for j in 0..3 {
        // Column j of the top-left (= bottom-right) block: Σ_k A[:3, k] B[k, j].
        let mut x = [0.0f64; 3];
        // Column j of the bottom-left: Σ_{k<3} Y₁[:, k] X₂[k, j] + Σ_k X₁[:, k] Y₂[k, j].
        let mut y = [0.0f64; 3];
        let s = b[6 * j];
        for i in 0..3 {
            x[i] = a[i] * s;
            y[i] = a[3 + i] * s;
        }
        for k in 1..3 {
            let s = b[6 * j + k];
            for i in 0..3 {
                x[i] += a[6 * k + i] * s;
                y[i] += a[6 * k + 3 + i] * s;
            }
        }
        for k in 0..3 {
            let s = b[6 * j + 3 + k];
            for i in 0..3 {
                y[i] += a[6 * (3 + k) + 3 + i] * s;
            }
        }
        c[6 * j..6 * j + 3].copy_from_slice(&x);
        c[6 * j + 3..6 * j + 6].copy_from_slice(&y);
        c[6 * (j + 3) + 3..6 * (j + 3) + 6].copy_from_slice(&x);
    }
    Mat6::from_column_slice(&c)
}

/// The leading `R × C` block of `Aᵀ B` (the rest zero): [`mmk`] of the
/// transpose, read from `A`'s columns (the same operations, no copy).
#[inline(always)]
pub(crate) fn tmk<const R: usize, const C: usize>(a: &Mat6, b: &Mat6) -> Mat6 {
    let (a, b) = (a.as_slice(), b.as_slice());
    let mut c = Mat6::zeros();
    let cs = c.as_mut_slice();
    for j in 0..C {
        let mut col = [0.0f64; R];
        let s = b[6 * j];
        for i in 0..R {
            col[i] = a[6 * i] * s;
        }
        for k in 1..6 {
            let s = b[6 * j + k];
            for i in 0..R {
                col[i] += a[6 * i + k] * s;
            }
        }
        cs[6 * j..6 * j + R].copy_from_slice(&col);
    }
    c
}

/// The leading `rows × cols` block of `Aᵀ B` (the rest zero), as
/// [`mm_part`] of the transpose.
#[inline(always)]
pub(crate) fn tm_part(a: &Mat6, b: &Mat6, rows: usize, cols: usize) -> Mat6 {
    mm_part(&a.transpose(), b, rows, cols)
}

/// A piece's (or joint's) basis `B` zero-padded to 6×6 (`k` leading
/// columns), with the components it selects when every column is a unit
/// vector: then `X B` and `Bᵀ X` are gathers of columns and rows, exact, and
/// equal bit for bit to the products by the padded `B` (the identity, six
/// strains, returns `X` itself).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cols {
    pub k: usize,
    sel: Option<[usize; 6]>,
    ident: bool,
    bm: Mat6,
}

impl Cols {
    #[inline(always)]
    pub(crate) fn of(bm: &Mat6) -> Self {
        let k = (0..6)
            .rev()
            .find(|&j| bm.column(j).iter().any(|v| *v != 0.0))
            .map_or(0, |j| j + 1);
        let mut sel = [0usize; 6];
        let mut unit = true;
        for (j, s) in sel.iter_mut().enumerate().take(k) {
            let col = bm.column(j);
            match (0..6).find(|&i| col[i] != 0.0) {
                Some(c) if col[c] == 1.0 && (c + 1..6).all(|i| col[i] == 0.0) => *s = c,
                _ => unit = false,
            }
        }
        Self {
            k,
            sel: unit.then_some(sel),
            ident: unit && sel == [0, 1, 2, 3, 4, 5],
            bm: *bm,
        }
    }

    /// The components a selection basis selects (`k` of them), `None` for
    /// a general `B`.
    #[inline(always)]
    pub(crate) fn selection(&self) -> Option<&[usize]> {
        self.sel.as_ref().map(|s| &s[..self.k])
    }

    /// `X B` (the leading `k` columns).
    #[inline(always)]
    pub(crate) fn right(&self, x: &Mat6) -> Mat6 {
        if self.ident {
            return *x;
        }
        match &self.sel {
            Some(sel) => {
                let mut out = Mat6::zeros();
                for (j, &c) in sel.iter().enumerate().take(self.k) {
                    out.set_column(j, &x.column(c));
                }
                out
            }
            None => mm_part(x, &self.bm, 6, self.k),
        }
    }

    /// `Bᵀ X` (the leading `k` rows).
    #[inline(always)]
    pub(crate) fn left(&self, x: &Mat6) -> Mat6 {
        if self.ident {
            return *x;
        }
        match &self.sel {
            Some(sel) => {
                let mut out = Mat6::zeros();
                for (i, &r) in sel.iter().enumerate().take(self.k) {
                    out.set_row(i, &x.row(r));
                }
                out
            }
            None => mm_part(&self.bm.transpose(), x, self.k, 6),
        }
    }

    /// `(Bᵀ X) B` (the leading `k × k` block).
    #[inline(always)]
    pub(crate) fn both(&self, x: &Mat6) -> Mat6 {
        self.right(&self.left(x))
    }
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
            assert_eq!(mmk::<6, 6>(&a, &b), a * b);
            // Lower block forms `[[X, 0], [Y, X]]`.
            let lower = |m: &Mat6| {
                let mut l = *m;
                for i in 0..3 {
                    for j in 0..3 {
                        l[(i, j + 3)] = 0.0;
                        l[(i + 3, j + 3)] = m[(i, j)];
                    }
                }
                l
            };
            let (la, lb) = (lower(&a), lower(&b));
            assert_eq!(mm_lower(&la, &lb), la * lb);
            assert_eq!(tmk::<6, 6>(&a, &b), a.transpose() * b);
            assert_eq!(mmk::<3, 4>(&a, &b), mm_part(&a, &b, 3, 4));
            assert_eq!(tmk::<4, 3>(&a, &b), mm_part(&a.transpose(), &b, 4, 3));
        }
    }

    /// The basis products: gathers for selections, the padded products
    /// otherwise, equal to the dense products by the padded `B`.
    #[test]
    fn basis_products_equal_padded_products() {
        let x = seeded(0.7);
        let mut sel = Mat6::zeros();
        sel[(4, 0)] = 1.0;
        sel[(0, 1)] = 1.0;
        sel[(5, 2)] = 1.0;
        let mut general = sel;
        general[(1, 1)] = 0.5;
        for (bm, gathers) in [(sel, true), (general, false), (Mat6::identity(), true)] {
            let c = Cols::of(&bm);
            assert_eq!(c.sel.is_some(), gathers);
            assert_eq!(c.k, if bm == Mat6::identity() { 6 } else { 3 });
            assert_eq!(c.right(&x), x * bm);
            assert_eq!(c.left(&x), bm.transpose() * x);
            assert_eq!(c.both(&x), bm.transpose() * x * bm);
            assert_eq!(tm_part(&bm, &x, c.k, 6), bm.transpose() * x);
        }
    }
}
