//! A dense LU factorization with partial pivoting that works in buffers
//! allocated once (nalgebra's `LU` takes its matrix by value and allocates).

use nalgebra::{DMatrix, DVector};

/// `P·A = L·U` of a square matrix, stored in place (unit lower `L` below the
/// diagonal, `U` on and above), with row pivots.
#[derive(Debug, Clone)]
pub(crate) struct DenseLu {
    a: DMatrix<f64>,
    piv: Vec<usize>,
}

impl DenseLu {
    /// Buffers for an `n×n` matrix.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            a: DMatrix::zeros(n, n),
            piv: vec![0; n],
        }
    }

    /// The matrix to fill before [`factor`](Self::factor).
    pub(crate) fn matrix_mut(&mut self) -> &mut DMatrix<f64> {
        &mut self.a
    }

    /// Factors the matrix in place (right-looking Doolittle, partial
    /// pivoting). Returns `false` if a pivot is zero or not finite.
    pub(crate) fn factor(&mut self) -> bool {
        let n = self.a.nrows();
        let a = &mut self.a;
        for k in 0..n {
            let mut p = k;
            let mut best = a[(k, k)].abs();
            for i in k + 1..n {
                let v = a[(i, k)].abs();
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
                a.swap_rows(p, k);
            }
            let inv = 1.0 / a[(k, k)];
            for i in k + 1..n {
                a[(i, k)] *= inv;
            }
            for j in k + 1..n {
                let akj = a[(k, j)];
                if akj != 0.0 {
                    for i in k + 1..n {
                        let lik = a[(i, k)];
                        a[(i, j)] -= lik * akj;
                    }
                }
            }
        }
        true
    }

    /// Solves `A x = b` in place with the factorization.
    pub(crate) fn solve_in_place(&self, b: &mut DVector<f64>) {
        let n = self.a.nrows();
        let a = &self.a;
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                b.swap_rows(p, k);
            }
        }
        // L y = b (unit diagonal), column oriented.
        for j in 0..n {
            let bj = b[j];
            if bj != 0.0 {
                for i in j + 1..n {
                    b[i] -= a[(i, j)] * bj;
                }
            }
        }
        // U x = y, column oriented.
        for j in (0..n).rev() {
            b[j] /= a[(j, j)];
            let bj = b[j];
            if bj != 0.0 {
                for i in 0..j {
                    b[i] -= a[(i, j)] * bj;
                }
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
    }

    #[test]
    fn reports_singular() {
        let mut lu = DenseLu::new(2);
        lu.matrix_mut()
            .copy_from(&DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 4.0]));
        assert!(!lu.factor());
    }
}
