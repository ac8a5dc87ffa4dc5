//! Restarted GMRES with a right preconditioner, in buffers allocated once:
//! the adjoint's transposed stage solves `Sᵀν = b` with the structured
//! O(N) factorization of the forward run as the preconditioner
//! (docs/theory-control.md G11).

use nalgebra::{DMatrix, DVector};

/// The buffers of GMRES(m) for systems of dimension `n`.
#[derive(Clone, Debug)]
pub(crate) struct Gmres {
    m: usize,
    /// The Arnoldi basis `v₀ … v_m`.
    basis: Vec<DVector<f64>>,
    /// `P⁻¹ vⱼ`, then `A P⁻¹ vⱼ`.
    z: DVector<f64>,
    w: DVector<f64>,
    /// The Hessenberg matrix, `(m + 1) × m`, rotated to upper triangular.
    h: DMatrix<f64>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    /// The rotated right-hand side `βe₁`; `|g[j+1]|` is the residual.
    g: Vec<f64>,
    y: Vec<f64>,
}

impl Gmres {
    /// Buffers for dimension `n`, at most `m` iterations per cycle.
    pub(crate) fn new(n: usize, m: usize) -> Self {
        let m = m.max(1);
        Self {
            m,
            basis: (0..=m).map(|_| DVector::zeros(n)).collect(),
            z: DVector::zeros(n),
            w: DVector::zeros(n),
            h: DMatrix::zeros(m + 1, m),
            cs: vec![0.0; m],
            sn: vec![0.0; m],
            g: vec![0.0; m + 1],
            y: vec![0.0; m],
        }
    }

    /// Solves `A x = b` from `x = 0` with iterates `x = P⁻¹ V y` (right
    /// preconditioning: the residual minimized is the true one). `apply(v,
    /// out)` writes `A v`, `precond(v)` overwrites `v` with `P⁻¹ v`.
    ///
    /// Converged when the true residual is at round-off of the product:
    /// `‖b − A x‖∞ ≤ rtol · (anorm ‖x‖∞ + ‖b‖∞)` (`anorm` = `‖A‖∞`), the
    /// normwise backward error of a stable direct solve. At most `cycles`
    /// cycles of at most `m` iterations, each restarted from the true
    /// residual. Returns the iterations, `None` when not converged (`x` is
    /// then the last iterate).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve<E>(
        &mut self,
        b: &DVector<f64>,
        x: &mut DVector<f64>,
        anorm: f64,
        rtol: f64,
        cycles: usize,
        mut apply: impl FnMut(&DVector<f64>, &mut DVector<f64>),
        mut precond: impl FnMut(&mut DVector<f64>) -> Result<(), E>,
    ) -> Result<Option<usize>, E> {
        let bnorm = b.amax();
        x.fill(0.0);
        if bnorm == 0.0 {
            return Ok(Some(0));
        }
        let mut iterations = 0;
        // An estimate of ‖x‖∞ for the inner stopping test: P⁻¹b at first.
        let mut xnorm = f64::NAN;
        for _ in 0..cycles {
            // r = b − A x into v₀.
            let (first, rest) = self.basis.split_at_mut(1);
            let r = &mut first[0];
            r.copy_from(b);
            if iterations > 0 {
                apply(x, &mut rest[0]);
                *r -= &rest[0];
                xnorm = x.amax();
                if r.amax() <= rtol * (anorm * xnorm + bnorm) {
                    return Ok(Some(iterations));
                }
            }
            let beta = r.norm();
            if !beta.is_finite() {
                return Ok(None);
            }
            *r /= beta;
            self.g.fill(0.0);
            self.g[0] = beta;
            let mut k = 0;
            for j in 0..self.m {
                self.z.copy_from(&self.basis[j]);
                precond(&mut self.z)?;
                if xnorm.is_nan() {
                    xnorm = beta * self.z.amax();
                }
                apply(&self.z, &mut self.w);
                iterations += 1;
                // Modified Gram–Schmidt.
                for i in 0..=j {
                    let hij = self.w.dot(&self.basis[i]);
                    self.h[(i, j)] = hij;
                    self.w.axpy(-hij, &self.basis[i], 1.0);
                }
                let hn = self.w.norm();
                self.h[(j + 1, j)] = hn;
                if hn > 0.0 {
                    self.basis[j + 1].copy_from(&self.w);
                    self.basis[j + 1] /= hn;
                }
                for i in 0..j {
                    let (a, c) = (self.h[(i, j)], self.h[(i + 1, j)]);
                    self.h[(i, j)] = self.cs[i] * a + self.sn[i] * c;
                    self.h[(i + 1, j)] = -self.sn[i] * a + self.cs[i] * c;
                }
                let (a, c) = (self.h[(j, j)], self.h[(j + 1, j)]);
                let d = a.hypot(c);
                if !(d > 0.0 && d.is_finite()) {
                    return Ok(None);
                }
                self.cs[j] = a / d;
                self.sn[j] = c / d;
                self.h[(j, j)] = d;
                self.h[(j + 1, j)] = 0.0;
                self.g[j + 1] = -self.sn[j] * self.g[j];
                self.g[j] *= self.cs[j];
                k = j + 1;
                let tol = rtol * (anorm * xnorm + bnorm);
                if self.g[j + 1].abs() <= tol || hn == 0.0 {
                    break;
                }
            }
            // H y = g (upper triangular k×k), x += P⁻¹ V y.
            for i in (0..k).rev() {
                let mut s = self.g[i];
                for l in i + 1..k {
                    s -= self.h[(i, l)] * self.y[l];
                }
                self.y[i] = s / self.h[(i, i)];
            }
            self.w.fill(0.0);
            for i in 0..k {
                self.w.axpy(self.y[i], &self.basis[i], 1.0);
            }
            precond(&mut self.w)?;
            *x += &self.w;
        }
        // The last cycle's result, checked.
        apply(x, &mut self.w);
        let mut worst: f64 = 0.0;
        for r in 0..b.len() {
            worst = worst.max((b[r] - self.w[r]).abs());
        }
        Ok((worst <= rtol * (anorm * x.amax() + bnorm)).then_some(iterations))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A nonsymmetric, diagonally dominant system against a dense LU, with
    /// the diagonal as the preconditioner.
    #[test]
    fn solves_a_nonsymmetric_system_to_round_off() {
        let n = 40;
        let a = DMatrix::from_fn(n, n, |i, j| {
            if i == j {
                10.0 + i as f64
            } else {
                ((3 * i + 7 * j) % 11) as f64 / 11.0 - 0.4
            }
        });
        let b = DVector::from_fn(n, |i, _| (i as f64).sin());
        let exact = a.clone().lu().solve(&b).unwrap();
        let mut x = DVector::zeros(n);
        let mut gmres = Gmres::new(n, 30);
        let anorm = (0..n).map(|i| a.row(i).abs().sum()).fold(0.0, f64::max);
        let diag = a.diagonal();
        let it = gmres
            .solve::<()>(
                &b,
                &mut x,
                anorm,
                4.0 * f64::EPSILON,
                3,
                |v, out| out.gemv(1.0, &a, v, 0.0),
                |v| {
                    v.component_div_assign(&diag);
                    Ok(())
                },
            )
            .unwrap();
        assert!(it.is_some(), "not converged");
        assert!((&x - &exact).amax() <= 1e-14 * exact.amax());
    }
}
