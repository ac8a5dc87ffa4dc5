//! Cholesky factorization and solves of the leading `k×k` block of a
//! [`Mat6`], `k ≤ 6` the dof of a piece.
//!
//! Each routine is generic over `K` and dispatched once on the runtime `k`:
//! with the size a constant the loops unroll and lose their bounds checks,
//! which at these sizes is most of the cost of the scalar loops.

use softrod_lie::{Mat6, Vec6};

/// Calls `$f::<K>($args)` with `K` the runtime `k` (0–6) as a
/// compile-time constant (also the derivatives' per-piece products,
/// `derivatives::vjp`).
macro_rules! with_k {
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
pub(crate) use with_k;

/// In-place Cholesky `m = L Lᵀ` of the leading `k×k` block (`L` written to
/// the lower triangle). Returns `false` if a pivot is not positive (or NaN).
#[inline(always)]
pub(crate) fn cholesky_k(m: &mut Mat6, k: usize) -> bool {
    with_k!(k, cholesky_n(m))
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
        // One division per column instead of one per entry (divisions
        // issue every ~4 cycles and sit on the factorization's chain).
        let inv = 1.0 / d;
        for i in (j + 1)..K {
            let mut s = m[(i, j)];
            for p in 0..j {
                s -= m[(i, p)] * m[(j, p)];
            }
            m[(i, j)] = s * inv;
        }
    }
    true
}

/// `W ← W L⁻ᵀ` on the leading `k` columns of `W` (6×k): the right-hand
/// triangular solve, column operations on whole 6-vectors.
#[inline(always)]
pub(crate) fn right_solve_lt(l: &Mat6, k: usize, w: &mut Mat6) {
    with_k!(k, right_solve_lt_n(l, w))
}

#[inline(always)]
fn right_solve_lt_n<const K: usize>(l: &Mat6, w: &mut Mat6) {
    for i in 0..K {
        let mut col = w.column(i).into_owned();
        for p in 0..i {
            col -= w.column(p) * l[(i, p)];
        }
        w.set_column(i, &(col * (1.0 / l[(i, i)])));
    }
}

/// `b ← L⁻¹ b` in the leading `k` entries.
#[inline(always)]
pub(crate) fn forward_sub(l: &Mat6, k: usize, b: &mut Vec6) {
    with_k!(k, forward_sub_n(l, b))
}

#[inline(always)]
fn forward_sub_n<const K: usize>(l: &Mat6, b: &mut Vec6) {
    for i in 0..K {
        let mut s = b[i];
        for p in 0..i {
            s -= l[(i, p)] * b[p];
        }
        b[i] = s * (1.0 / l[(i, i)]);
    }
}

/// `b ← L⁻ᵀ b` in the leading `k` entries.
#[inline(always)]
pub(crate) fn backward_sub(l: &Mat6, k: usize, b: &mut Vec6) {
    with_k!(k, backward_sub_n(l, b))
}

#[inline(always)]
fn backward_sub_n<const K: usize>(l: &Mat6, b: &mut Vec6) {
    for i in (0..K).rev() {
        let mut s = b[i];
        for p in (i + 1)..K {
            s -= l[(p, i)] * b[p];
        }
        b[i] = s * (1.0 / l[(i, i)]);
    }
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
            let mut x = b;
            forward_sub(&m, k, &mut x);
            backward_sub(&m, k, &mut x);
            let xr = &inv * b.rows(0, k);
            for i in 0..k {
                assert_relative_eq!(x[i], xr[i], epsilon = 1e-12, max_relative = 1e-12);
            }
            // W Wᵀ = X A⁻¹ Xᵀ for W = X L⁻ᵀ (X 6×k).
            let xm = Mat6::from_fn(|i, j| {
                if j < k {
                    ((i + 2 * j) as f64).sin()
                } else {
                    0.0
                }
            });
            let mut wm = xm;
            right_solve_lt(&m, k, &mut wm);
            let xk = xm.columns(0, k).into_owned();
            let wk = wm.columns(0, k).into_owned();
            let lhs = &wk * wk.transpose();
            let rhs = &xk * &inv * xk.transpose();
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
