//! The bounded quadratic program of each Gauss–Newton step (IS4):
//! `min ½ xᵀH x + gᵀx` subject to `lo ≤ x ≤ hi`, by clarabel's interior
//! point method, then *polished* on the active set it finds: the bounds it
//! holds are fixed and the free components solved exactly from
//! `H_FF x_F = −(g_F + H_FA x_A)`. An interior point method stops a little
//! inside the bounds (its tolerance, ~1e-8 relative); the polished step is
//! exact to round-off, so the outer iteration converges to its own
//! tolerance rather than to the QP's.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use nalgebra::{DMatrix, DVector};

/// The minimizer of the bounded QP, or why there is none. `h` symmetric
/// positive semidefinite (n × n), `lo[i] ≤ hi[i]`, `hi[i]` may be `+∞`
/// (no upper bound), `lo` finite.
pub(super) fn bounded_qp(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    lo: &[f64],
    hi: &[f64],
) -> Result<DVector<f64>, String> {
    let n = g.len();
    // A convex QP whose unconstrained minimizer is feasible has it as its
    // solution: the common step of a warm-started sequence, which then
    // costs one small Cholesky instead of an interior-point solve.
    if let Some(c) = h.clone().cholesky() {
        let x = c.solve(&(-g));
        if x.iter()
            .enumerate()
            .all(|(i, v)| v.is_finite() && *v >= lo[i] && *v <= hi[i])
        {
            return Ok(x);
        }
    }
    // P: the upper triangle, column by column (clarabel reads only it).
    let mut colptr = Vec::with_capacity(n + 1);
    let mut rowval = Vec::with_capacity(n * (n + 1) / 2);
    let mut nzval = Vec::with_capacity(n * (n + 1) / 2);
    colptr.push(0);
    for j in 0..n {
        for i in 0..=j {
            rowval.push(i);
            nzval.push(0.5 * (h[(i, j)] + h[(j, i)]));
        }
        colptr.push(rowval.len());
    }
    let p = CscMatrix::new(n, n, colptr, rowval, nzval);
    // Constraints A x + s = b, s ≥ 0: −x_i + s = −lo_i and x_i + s = hi_i.
    let mut rows: Vec<(usize, f64, f64)> = Vec::with_capacity(2 * n);
    for i in 0..n {
        rows.push((i, -1.0, -lo[i]));
        if hi[i].is_finite() {
            rows.push((i, 1.0, hi[i]));
        }
    }
    let m = rows.len();
    let mut colptr = vec![0usize; n + 1];
    let mut rowval = Vec::with_capacity(m);
    let mut nzval = Vec::with_capacity(m);
    for j in 0..n {
        for (r, (i, sign, _)) in rows.iter().enumerate() {
            if *i == j {
                rowval.push(r);
                nzval.push(*sign);
            }
        }
        colptr[j + 1] = rowval.len();
    }
    let a = CscMatrix::new(m, n, colptr, rowval, nzval);
    let b: Vec<f64> = rows.iter().map(|r| r.2).collect();
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(1e-10)
        .tol_gap_rel(1e-10)
        .build()
        .map_err(|e| format!("QP settings: {e:?}"))?;
    let cones = [NonnegativeConeT(m)];
    let mut solver = DefaultSolver::new(&p, g.as_slice(), &a, &b, &cones, settings)
        .map_err(|e| format!("QP setup: {e:?}"))?;
    solver.solve();
    let status = solver.solution.status;
    if !matches!(status, SolverStatus::Solved | SolverStatus::AlmostSolved) {
        return Err(format!("the bounded QP of the step failed ({status:?})"));
    }
    let mut x = DVector::from_column_slice(&solver.solution.x);
    for i in 0..n {
        x[i] = x[i].clamp(lo[i], hi[i]);
    }
    Ok(polish(h, g, lo, hi, x))
}

/// The exact minimizer by a primal active-set method started at `x` (the
/// interior point's answer, clamped): the bounds `x` is near form the
/// working set; each iteration solves the free components exactly, steps
/// to the first bound it would cross (adding it), or, when the step is
/// feasible, drops the bound whose multiplier has the wrong sign. From a
/// good start it ends in one or two solves; where the interior point's
/// tolerance cannot see a direction (an eigenvalue of `H` 1e-9 of the
/// largest: the effort term along redundant tensions) this is what finds
/// it. Returns `x` if it does not finish within its iteration budget.
fn polish(
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    lo: &[f64],
    hi: &[f64],
    x: DVector<f64>,
) -> DVector<f64> {
    let n = g.len();
    let width = |i: usize| {
        if hi[i].is_finite() {
            hi[i] - lo[i]
        } else {
            1.0 + lo[i].abs()
        }
    };
    let near = |i: usize| 1e-6 * width(i).max(f64::MIN_POSITIVE);
    let mut y = x.clone();
    // Working set: None free, Some(false) at lo, Some(true) at hi.
    let mut fixed: Vec<Option<bool>> = (0..n)
        .map(|i| {
            if y[i] - lo[i] <= near(i) {
                Some(false)
            } else if hi[i] - y[i] <= near(i) {
                Some(true)
            } else {
                None
            }
        })
        .collect();
    for i in 0..n {
        match fixed[i] {
            Some(false) => y[i] = lo[i],
            Some(true) => y[i] = hi[i],
            None => {}
        }
    }
    for _ in 0..4 * n + 4 {
        let free: Vec<usize> = (0..n).filter(|i| fixed[*i].is_none()).collect();
        let mut target = y.clone();
        if !free.is_empty() {
            let k = free.len();
            let mut hff = DMatrix::zeros(k, k);
            let mut rhs = DVector::zeros(k);
            for (a, &i) in free.iter().enumerate() {
                let mut r = -g[i];
                for j in 0..n {
                    if fixed[j].is_some() {
                        r -= h[(i, j)] * y[j];
                    }
                }
                rhs[a] = r;
                for (b, &j) in free.iter().enumerate() {
                    hff[(a, b)] = h[(i, j)];
                }
            }
            let Some(sol) = hff.cholesky().map(|c| c.solve(&rhs)) else {
                return x;
            };
            for (a, &i) in free.iter().enumerate() {
                target[i] = sol[a];
            }
        }
        if target.iter().any(|v| !v.is_finite()) {
            return x;
        }
        // The longest feasible step towards the free minimizer.
        let mut alpha = 1.0;
        let mut blocking = None;
        for &i in &free {
            let d = target[i] - y[i];
            let room = if d < 0.0 { lo[i] - y[i] } else { hi[i] - y[i] };
            if d != 0.0 && room / d < alpha {
                alpha = (room / d).max(0.0);
                blocking = Some((i, d > 0.0));
            }
        }
        if let Some((i, upper)) = blocking {
            y += (&target - &y) * alpha;
            y[i] = if upper { hi[i] } else { lo[i] };
            fixed[i] = Some(upper);
            continue;
        }
        y = target;
        // Multipliers: at a lower bound the gradient must not be negative
        // (moving up would pay), at an upper one not positive.
        // A multiplier that is zero up to round-off of the gradient's
        // terms is zero: dropping it would cycle.
        let hy = h * &y;
        let grad = &hy + g;
        let tol = 1e-12 * g.amax().max(hy.amax());
        let worst = (0..n)
            .filter_map(|i| match fixed[i] {
                Some(false) if grad[i] < -tol => Some((i, -grad[i])),
                Some(true) if grad[i] > tol => Some((i, grad[i])),
                _ => None,
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match worst {
            Some((i, _)) => fixed[i] = None,
            None => return y,
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the solution by hand: `min ½(x₀² + x₁²) − 2x₀ + x₁` on
    /// `[0, 1]²` is `x = (1, 0)` (both bounds active, the unconstrained
    /// minimum `(2, −1)` clipped, separable).
    #[test]
    fn separable_box() {
        let h = DMatrix::identity(2, 2);
        let g = DVector::from_vec(vec![-2.0, 1.0]);
        let x = bounded_qp(&h, &g, &[0.0, 0.0], &[1.0, 1.0]).unwrap();
        assert_eq!(x.as_slice(), &[1.0, 0.0]);
    }

    /// A coupled problem with one free component: `H = [[2,1],[1,2]]`,
    /// `g = (−1, 3)`, `x ≥ 0`: `x₁ = 0` held, `x₀ = 1/2` from `2x₀ − 1 = 0`;
    /// the multiplier of `x₁` is `x₀ + 3 > 0`.
    #[test]
    fn coupled_lower_bound() {
        let h = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        let g = DVector::from_vec(vec![-1.0, 3.0]);
        let inf = f64::INFINITY;
        let x = bounded_qp(&h, &g, &[0.0, 0.0], &[inf, inf]).unwrap();
        assert!((x[0] - 0.5).abs() < 1e-15 && x[1] == 0.0, "{x}");
    }
}
