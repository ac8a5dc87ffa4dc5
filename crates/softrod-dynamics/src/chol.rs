//! Cholesky factorization and solves of the leading `k×k` block of a
//! [`Mat6`], `k ≤ 6` the dof of a piece.
//!
//! Each routine is generic over `K` and dispatched once on the runtime `k`:
//! with the size a constant the loops unroll and lose their bounds checks,
//! which at these sizes is most of the cost of the scalar loops.

use softrod_lie::{Mat6, Vec6};

macro_rules! dispatch {
    ($k:expr, $f:ident($($arg:expr),*)) => {
        match $k {
            0 => $f::<0>($($arg),*),
            1 => $f::<1>($($arg),*),
            2 => $f::<2>($($arg),*),
            3 => $f::<3>($($arg),*),
            4 => $f::<4>($($arg),*),
            5 => $f::<5>($($arg),*),
            _ => $f::<6>($($arg),*),
        }
    };
}

/// In-place Cholesky `m = L Lᵀ` of the leading `k×k` block (`L` written to
/// the lower triangle). Returns `false` if a pivot is not positive (or NaN).
#[inline]
pub(crate) fn cholesky_k(m: &mut Mat6, k: usize) -> bool {
    dispatch!(k, cholesky_n(m))
}

#[inline(always)]
fn cholesky_n<const K: usize>(m: &mut Mat6) -> bool {
    for j in 0..K {
        let mut d = m[(j, j)];
        for p in 0..j {
            d -= m[(j, p)] * m[(j, p)];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        m[(j, j)] = d;
        for i in (j + 1)..K {
            let mut s = m[(i, j)];
            for p in 0..j {
                s -= m[(i, p)] * m[(j, p)];
            }
            m[(i, j)] = s / d;
        }
    }
    true
}

/// `X ← L⁻¹ X` on the leading `k` rows of every column of `X`.
#[inline]
pub(crate) fn forward_sub_cols(l: &Mat6, k: usize, x: &mut Mat6) {
    dispatch!(k, forward_sub_cols_n(l, x))
}

#[inline(always)]
fn forward_sub_cols_n<const K: usize>(l: &Mat6, x: &mut Mat6) {
    for c in 0..6 {
        for i in 0..K {
            let mut s = x[(i, c)];
            for p in 0..i {
                s -= l[(i, p)] * x[(p, c)];
            }
            x[(i, c)] = s / l[(i, i)];
        }
    }
}

/// `x = (L Lᵀ)⁻¹ b` in the leading `k` entries (the rest zero).
#[inline]
pub(crate) fn chol_solve(l: &Mat6, k: usize, b: &Vec6) -> Vec6 {
    dispatch!(k, chol_solve_n(l, b))
}

#[inline(always)]
fn chol_solve_n<const K: usize>(l: &Mat6, b: &Vec6) -> Vec6 {
    let mut x = Vec6::zeros();
    for i in 0..K {
        let mut s = b[i];
        for p in 0..i {
            s -= l[(i, p)] * x[p];
        }
        x[i] = s / l[(i, i)];
    }
    for i in (0..K).rev() {
        let mut s = x[i];
        for p in (i + 1)..K {
            s -= l[(p, i)] * x[p];
        }
        x[i] = s / l[(i, i)];
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn solves_match_dense_inverse_for_every_k() {
        for k in 1..=6 {
            let g = Mat6::from_fn(|i, j| ((i * 6 + j) as f64 * 0.61 + k as f64).sin());
            let spd = g.transpose() * g + Mat6::identity() * 0.1;
            let mut m = spd;
            assert!(cholesky_k(&mut m, k));
            let a = spd.view((0, 0), (k, k)).into_owned();
            let inv = a.clone().try_inverse().unwrap();
            let b = Vec6::from_fn(|i, _| (i as f64 + 0.5).cos());
            let x = chol_solve(&m, k, &b);
            let xr = &inv * b.rows(0, k);
            for i in 0..6 {
                let expect = if i < k { xr[i] } else { 0.0 };
                assert_relative_eq!(x[i], expect, epsilon = 1e-12, max_relative = 1e-12);
            }
            // Zᵀ Z = Xᵀ A⁻¹ X for Z = L⁻¹ X.
            let xm = Mat6::from_fn(|i, j| ((i + 2 * j) as f64).sin());
            let mut z = xm;
            forward_sub_cols(&m, k, &mut z);
            let zk = z.rows(0, k).into_owned();
            let xk = xm.rows(0, k).into_owned();
            let lhs = zk.transpose() * zk;
            let rhs = xk.transpose() * &inv * xk;
            assert_relative_eq!(lhs, rhs, epsilon = 1e-11, max_relative = 1e-11);
        }
    }

    #[test]
    fn non_positive_pivot_is_reported() {
        let mut m = Mat6::identity();
        m[(2, 2)] = -1.0;
        assert!(cholesky_k(&mut m, 2));
        let mut m2 = m;
        assert!(!cholesky_k(&mut m2, 3));
        let mut nan = Mat6::identity() * f64::NAN;
        assert!(!cholesky_k(&mut nan, 1));
    }
}
