//! Dense LU (partial pivoting) and Cholesky factorizations that work in
//! buffers allocated once (nalgebra's `LU`/`Cholesky` take their matrix by
//! value and allocate).

use nalgebra::{Complex, DMatrix, DVector};

/// Which factorization the buffer holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// `P·A = L·U`: unit lower `L` below the diagonal, `U` on and above.
    Lu,
    /// `A = L·Lᵀ`: `L` on and below the diagonal (the upper part is stale);
    /// the reciprocals of `diag(L)` are kept in `inv_diag`.
    Cholesky,
}

/// A square matrix factored in place: `P·A = L·U` with row pivots, or, for a
/// symmetric positive definite `A`, `A = L·Lᵀ` (half the flops of the LU, no
/// pivoting, and it cannot silently succeed on an indefinite matrix).
#[derive(Debug, Clone)]
pub(crate) struct DenseLu {
    a: DMatrix<f64>,
    piv: Vec<usize>,
    inv_diag: Vec<f64>,
    kind: Kind,
}

impl DenseLu {
    /// Buffers for an `n×n` matrix.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            a: DMatrix::zeros(n, n),
            piv: vec![0; n],
            inv_diag: vec![0.0; n],
            kind: Kind::Lu,
        }
    }

    /// Cholesky `A = L·Lᵀ` in place, reading only the lower triangle of the
    /// matrix (left-looking by columns: column `j` of `L` is column `j` of
    /// `A` minus `Σₖ<ⱼ L[j,k]·L[j.., k]`, then scaled by `1/√pivot`; the
    /// inner loops run down contiguous columns). Returns `false` if a pivot
    /// is not positive and finite (the matrix is not numerically SPD; the
    /// buffer is then destroyed).
    pub(crate) fn factor_cholesky(&mut self) -> bool {
        let n = self.a.nrows();
        self.kind = Kind::Cholesky;
        let a = self.a.as_mut_slice();
        for j in 0..n {
            let (left, right) = a.split_at_mut(j * n);
            let col_j = &mut right[j..n];
            for k in 0..j {
                let col_k = &left[k * n + j..k * n + n];
                let ljk = col_k[0];
                if ljk != 0.0 {
                    for (x, &l) in col_j.iter_mut().zip(col_k) {
                        *x -= ljk * l;
                    }
                }
            }
            let d = col_j[0];
            if !(d > 0.0 && d.is_finite()) {
                return false;
            }
            let inv = 1.0 / d.sqrt();
            for x in col_j.iter_mut() {
                *x *= inv;
            }
            self.inv_diag[j] = inv;
        }
        true
    }

    /// The matrix to fill before [`factor`](Self::factor).
    pub(crate) fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        &mut self.a
    }

    /// Factors the matrix in place (right-looking Doolittle, partial
    /// pivoting). Returns `false` if a pivot is zero or not finite.
    pub(crate) fn factor(&mut self) -> bool {
        let n = self.a.nrows();
        self.kind = Kind::Lu;
        let a = self.a.as_mut_slice();
        // On the column-major slice: the pivot search and the scaling run
        // down column `k`, the update down the columns after it (every
        // entry takes the same operations in the same order as by rows).
        for k in 0..n {
            let col = &a[k * n..(k + 1) * n];
            let mut p = k;
            let mut best = col[k].abs();
            for (i, x) in col.iter().enumerate().skip(k + 1) {
                let v = x.abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if best == 0.0 || !best.is_finite() {
                return false;
            }
            self.piv[k] = p;
            if p != k {
                for c in a.chunks_exact_mut(n) {
                    c.swap(p, k);
                }
            }
            let (left, right) = a.split_at_mut((k + 1) * n);
            let col_k = &mut left[k * n..];
            let inv = 1.0 / col_k[k];
            for x in &mut col_k[k + 1..] {
                *x *= inv;
            }
            let l = &col_k[k + 1..];
            for col_j in right.chunks_exact_mut(n) {
                let akj = col_j[k];
                if akj != 0.0 {
                    for (x, &lik) in col_j[k + 1..].iter_mut().zip(l) {
                        *x -= lik * akj;
                    }
                }
            }
        }
        true
    }

    /// Solves `A x = b` in place with the factorization.
    pub(crate) fn solve_in_place(&self, b: &mut DVector<f64>) {
        if self.kind == Kind::Cholesky {
            self.solve_cholesky(b.as_mut_slice());
            return;
        }
        let n = self.a.nrows();
        let a = self.a.as_slice();
        let b = b.as_mut_slice();
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                b.swap(p, k);
            }
        }
        // L y = b (unit diagonal), column oriented on contiguous columns.
        for j in 0..n {
            let bj = b[j];
            if bj != 0.0 {
                let col = &a[j * n + j + 1..j * n + n];
                for (x, &l) in b[j + 1..].iter_mut().zip(col) {
                    *x -= l * bj;
                }
            }
        }
        // U x = y, column oriented.
        for j in (0..n).rev() {
            b[j] /= a[j * n + j];
            let bj = b[j];
            if bj != 0.0 {
                let col = &a[j * n..j * n + j];
                for (x, &u) in b[..j].iter_mut().zip(col) {
                    *x -= u * bj;
                }
            }
        }
    }
}

impl DenseLu {
    /// Solves `Aᵀ x = b` in place with the factorization of `A` (the
    /// discrete adjoint's transposed stage system, docs/theory-control.md
    /// G25): `Aᵀ = Uᵀ Lᵀ P`, so `Uᵀ y = b` forwards, `Lᵀ z = y` backwards
    /// (both by dot products down contiguous columns), `x = Pᵀ z` (the
    /// row swaps undone in reverse order). A Cholesky factor is symmetric.
    pub(crate) fn solve_transposed_in_place(&self, b: &mut DVector<f64>) {
        if self.kind == Kind::Cholesky {
            self.solve_cholesky(b.as_mut_slice());
            return;
        }
        let n = self.a.nrows();
        let a = self.a.as_slice();
        let x = b.as_mut_slice();
        for j in 0..n {
            let col = &a[j * n..j * n + j];
            let s = dot(col, &x[..j]);
            x[j] = (x[j] - s) / a[j * n + j];
        }
        for j in (0..n).rev() {
            let col = &a[j * n + j + 1..j * n + n];
            let s = dot(col, &x[j + 1..]);
            x[j] -= s;
        }
        for k in (0..n).rev() {
            let p = self.piv[k];
            if p != k {
                x.swap(p, k);
            }
        }
    }

    /// `L·Lᵀ x = b`: forward substitution by columns, back substitution by
    /// dot products with the columns of `L` (both contiguous).
    fn solve_cholesky(&self, b: &mut [f64]) {
        let n = self.a.nrows();
        let a = self.a.as_slice();
        for j in 0..n {
            let col = &a[j * n + j..j * n + n];
            let y = b[j] * self.inv_diag[j];
            b[j] = y;
            if y != 0.0 {
                for (x, &l) in b[j + 1..].iter_mut().zip(&col[1..]) {
                    *x -= l * y;
                }
            }
        }
        for j in (0..n).rev() {
            let col = &a[j * n + j + 1..j * n + n];
            let s = dot(col, &b[j + 1..]);
            b[j] = (b[j] - s) * self.inv_diag[j];
        }
    }
}

/// `Σ aᵢbᵢ` in four interleaved partial sums (a fixed order, so the result
/// is deterministic; the compiler keeps them in vector registers where one
/// running sum would serialize on the adder's latency).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut s = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// A complex square matrix factored in place, `P·A = L·U` with partial
/// pivoting (the complex iteration matrix of Radau IIA), in buffers
/// allocated once.
#[derive(Debug, Clone)]
pub(crate) struct ComplexLu {
    n: usize,
    /// Column-major.
    a: Vec<Complex<f64>>,
    piv: Vec<usize>,
}

impl ComplexLu {
    /// Buffers for an `n×n` matrix.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            a: vec![Complex::new(0.0, 0.0); n * n],
            piv: vec![0; n],
        }
    }

    /// Dimension.
    pub(crate) fn dim(&self) -> usize {
        self.n
    }

    /// Entry `(i, j)` of the matrix to fill before [`factor`](Self::factor).
    pub(crate) fn set(&mut self, i: usize, j: usize, v: Complex<f64>) {
        self.a[j * self.n + i] = v;
    }

    /// Factors in place (right-looking, partial pivoting on the modulus).
    /// Returns `false` if a pivot is zero or not finite.
    pub(crate) fn factor(&mut self) -> bool {
        let n = self.n;
        let a = &mut self.a;
        for k in 0..n {
            let mut p = k;
            let mut best = a[k * n + k].norm();
            for i in k + 1..n {
                let v = a[k * n + i].norm();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if best == 0.0 || !best.is_finite() {
                return false;
            }
            self.piv[k] = p;
            if p != k {
                for j in 0..n {
                    a.swap(j * n + p, j * n + k);
                }
            }
            let inv = Complex::new(1.0, 0.0) / a[k * n + k];
            for i in k + 1..n {
                a[k * n + i] *= inv;
            }
            for j in k + 1..n {
                let akj = a[j * n + k];
                if akj != Complex::new(0.0, 0.0) {
                    for i in k + 1..n {
                        let lik = a[k * n + i];
                        a[j * n + i] -= lik * akj;
                    }
                }
            }
        }
        true
    }

    /// Solves `A x = b` in place with the factorization.
    pub(crate) fn solve_in_place(&self, b: &mut [Complex<f64>]) {
        let n = self.n;
        let a = &self.a;
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                b.swap(p, k);
            }
        }
        for j in 0..n {
            let bj = b[j];
            for i in j + 1..n {
                b[i] -= a[j * n + i] * bj;
            }
        }
        for j in (0..n).rev() {
            b[j] /= a[j * n + j];
            let bj = b[j];
            for i in 0..j {
                b[i] -= a[j * n + i] * bj;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_system_like_nalgebra() {
        let m = DMatrix::from_row_slice(
            4,
            4,
            &[
                0.0, 2.0, 1.0, 3.0, //
                1.0, 1.0, 0.0, -1.0, //
                4.0, -2.0, 5.0, 0.5, //
                2.0, 0.0, 1.0, 7.0,
            ],
        );
        let b = DVector::from_row_slice(&[1.0, -2.0, 3.0, 0.25]);
        let mut lu = DenseLu::new(4);
        lu.matrix_mut().copy_from(&m);
        assert!(lu.factor());
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        let r = &m * &x - &b;
        assert!(r.amax() < 1e-13, "residual {r}");
        // The transposed system with the same factorization.
        let mut y = b.clone();
        lu.solve_transposed_in_place(&mut y);
        let r = m.transpose() * &y - &b;
        assert!(r.amax() < 1e-13, "transposed residual {r}");
    }

    #[test]
    fn cholesky_solves_an_spd_system_and_rejects_an_indefinite_one() {
        // A = BᵀB + I with a non-symmetric B: SPD, well conditioned.
        let n = 7;
        let b = DMatrix::from_fn(n, n, |i, j| ((3 * i + 5 * j) % 11) as f64 / 7.0 - 0.6);
        let m = b.transpose() * &b + DMatrix::identity(n, n);
        let rhs = DVector::from_fn(n, |i, _| (i as f64 + 1.0).sin());
        let mut f = DenseLu::new(n);
        f.matrix_mut().copy_from(&m);
        // Only the lower triangle is read.
        for j in 1..n {
            for i in 0..j {
                f.matrix_mut()[(i, j)] = f64::NAN;
            }
        }
        assert!(f.factor_cholesky());
        let mut x = rhs.clone();
        f.solve_in_place(&mut x);
        let expect = m.clone().lu().solve(&rhs).unwrap();
        assert!((&x - &expect).amax() < 1e-13, "{x} vs {expect}");
        // The same buffers then take an LU again.
        f.matrix_mut().copy_from(&m);
        assert!(f.factor());
        let mut y = rhs.clone();
        f.solve_in_place(&mut y);
        assert!((&y - &expect).amax() < 1e-13);
        // Indefinite: refused.
        f.matrix_mut()
            .copy_from(&DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]).resize(n, n, 0.0));
        assert!(!f.factor_cholesky());
    }

    #[test]
    fn complex_lu_solves_like_a_real_block_system() {
        // (A + iB) x = b against the real 2n×2n form [[A, −B], [B, A]].
        let n = 5;
        let re = DMatrix::from_fn(n, n, |i, j| {
            ((2 * i + 3 * j) % 7) as f64 - 3.0 + 4.0 * (i == j) as u8 as f64
        });
        let im = DMatrix::from_fn(n, n, |i, j| ((i + 5 * j) % 4) as f64 * 0.5 - 0.7);
        let b: Vec<Complex<f64>> = (0..n)
            .map(|i| Complex::new((i as f64).cos(), (i as f64 * 0.3).sin()))
            .collect();
        let mut lu = ComplexLu::new(n);
        for j in 0..n {
            for i in 0..n {
                lu.set(i, j, Complex::new(re[(i, j)], im[(i, j)]));
            }
        }
        assert!(lu.factor());
        let mut x = b.clone();
        lu.solve_in_place(&mut x);
        let mut big = DMatrix::zeros(2 * n, 2 * n);
        big.view_mut((0, 0), (n, n)).copy_from(&re);
        big.view_mut((0, n), (n, n)).copy_from(&(-&im));
        big.view_mut((n, 0), (n, n)).copy_from(&im);
        big.view_mut((n, n), (n, n)).copy_from(&re);
        let rhs = DVector::from_fn(2 * n, |i, _| if i < n { b[i].re } else { b[i - n].im });
        let y = big.lu().solve(&rhs).unwrap();
        for i in 0..n {
            assert!((x[i].re - y[i]).abs() < 1e-13 && (x[i].im - y[n + i]).abs() < 1e-13);
        }
    }

    #[test]
    fn reports_singular() {
        let mut lu = DenseLu::new(2);
        lu.matrix_mut()
            .copy_from(&DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]));
        assert!(!lu.factor());
    }
}
