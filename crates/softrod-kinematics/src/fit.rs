//! Strains from a centreline: the coordinates `q` whose PCS shape passes
//! closest to given points (docs/theory.md §2, (D70)).
//!
//! Least squares on positions, `min_q Σ_i |p(s_i; q) − p_i|²`, by
//! Gauss–Newton with the exact Jacobian `∂p/∂q` (the linear rows of the
//! mixed-frame geometric Jacobian, D11) and a backtracking line search.
//! It stops at a stationary point (the linearized step would lower the
//! cost by at most 1e-10 of it) and gives up a start from which the line
//! search keeps cutting the steps (five in a row below 1/32).
//! Positions alone do not fix every strain (the twist of a straight rod,
//! say): each step is the least-norm solution of the linearized problem
//! (singular values below 1e-10 of the largest dropped), so such
//! coordinates stay near the starting guess (exactly at it when they are
//! undetermined all along the way).
//!
//! **The starting point.** Gauss–Newton from a straight rod does not reach
//! a coiled shape: each piece of a 20-turn coil turns by π, far outside
//! the basin of the straight guess (it converged to a piece at stretch
//! −3215). The global iteration therefore starts from a guess built piece
//! by piece from the base ("marching"): with the frame `g_n` at piece
//! `n`'s start already placed by the pieces before it, the piece's
//! strain is fitted alone, in `g_n`'s axes, to the points on it and —
//! with half the weight, and the same constant strain continued — those of
//! the next piece (which fix what the piece's own points leave open: the
//! direction it leaves in). That small problem (at most six unknowns) is
//! solved by Gauss–Newton from several guesses, and the best kept:
//! - the arc leaving tangent to the section's `x` axis through the
//!   farthest point `p` (local axes, `p = (p_x, p_⊥)`): radius
//!   `R = |p|²/(2|p_⊥|)`, turning `θ = 2 atan2(|p_⊥|, p_x) ∈ (0, 2π)`,
//!   curvature `(κ_y, κ_z) = (x × p̂_⊥)/R`, stretch `Rθ/σ` for the
//!   abscissa `σ` of `p` — exact for a circle, and for any piece of
//!   planar constant curvature without shear, whatever it turns;
//! - the same arc through the farthest point of the piece's own;
//! - the previous piece's strain (a helix or a coil repeats it);
//! - the starting guess `q0`.
//!
//! The components the arc does not set (torsion, shear) come from `q0`.
//! Where the points lie on a shape the rod's pieces and basis can
//! represent, the marched guess is that shape to round-off and the
//! global iteration only confirms it. When the marched fit is not exact,
//! the global iteration is also run from `q0` itself and the better of
//! the two kept, so the marching never makes a fit worse.

use crate::error::KinematicsError;
use crate::rod::Piece;
use crate::rod::RodGeometry;
use crate::state::{Frame, RodKinematics};
use nalgebra::{DMatrix, DVector, Matrix6xX};
use softrod_lie::{Pose, Vec3, Vec6, exp_twist, tangent_minus};

/// The result of [`fit_centerline`].
#[derive(Clone, Debug, PartialEq)]
pub struct CenterlineFit {
    /// The fitted coordinates (the rod's `n_dof`).
    pub q: Vec<f64>,
    /// Root-mean-square distance of the shape to the points \[m\].
    pub rms: f64,
    /// Largest distance of the shape to a point \[m\].
    pub max: f64,
    /// Gauss–Newton iterations.
    pub iterations: usize,
}

/// Fits the rod's coordinates to points `targets = [(s_i, p_i)]`
/// (arc length \[m\] in `[0, L]`, position \[m\] in the frame the rod's
/// kinematics works in: the world for a rod clamped to it), starting from
/// `q0` (the rod's `n_dof`).
///
/// Errors: no target, a target off the rod or not finite, `q0` of the
/// wrong size.
pub fn fit_centerline(
    rod: &RodGeometry,
    targets: &[(f64, Vec3)],
    q0: &[f64],
) -> Result<CenterlineFit, KinematicsError> {
    let n = rod.n_dof();
    if q0.len() != n {
        return Err(KinematicsError::SizeMismatch {
            what: "q0",
            got: q0.len(),
            expected: n,
        });
    }
    if targets.is_empty() {
        return Err(KinematicsError::SizeMismatch {
            what: "centreline points",
            got: 0,
            expected: 1,
        });
    }
    for (i, (s, p)) in targets.iter().enumerate() {
        if let Some(v) = std::iter::once(s).chain(p.iter()).find(|v| !v.is_finite()) {
            return Err(KinematicsError::NotFinite {
                what: "centreline point",
                index: i,
                value: *v,
            });
        }
        if *s < 0.0 || *s > rod.length() * (1.0 + 1e-12) {
            return Err(KinematicsError::OutOfRod {
                s: *s,
                length: rod.length(),
            });
        }
    }
    let scale = rod.length();
    let exact = |f: &CenterlineFit| f.max <= 1e-10 * scale;
    let marched = marching_guess(rod, targets, q0);
    let fit = gauss_newton(rod, targets, &marched)?;
    if exact(&fit) {
        return Ok(fit);
    }
    let plain = gauss_newton(rod, targets, q0)?;
    Ok(if plain.rms < fit.rms { plain } else { fit })
}

/// [`gauss_newton`] stops when its linearized step would lower the cost
/// by at most this fraction of it (a stationary point to round-off: the
/// root-mean-square distance could change by 5e-11 of itself).
const FIT_PTOL: f64 = 1e-10;
/// [`gauss_newton`] gives up a start when CRAWL_STEPS iterations in a row
/// took less than CRAWL_ALPHA of their Gauss–Newton step.
const CRAWL_ALPHA: f64 = 1.0 / 32.0;
const CRAWL_STEPS: usize = 5;

/// Gauss–Newton on all coordinates from `q_start` (module documentation).
fn gauss_newton(
    rod: &RodGeometry,
    targets: &[(f64, Vec3)],
    q_start: &[f64],
) -> Result<CenterlineFit, KinematicsError> {
    let n = rod.n_dof();
    let m = targets.len();
    let mut kin = RodKinematics::new(rod);
    let mut jac6 = Matrix6xX::zeros(n);
    let mut j = DMatrix::zeros(3 * m, n);
    let mut r = DVector::zeros(3 * m);
    // Residual r = p(s; q) − p and (when asked) its Jacobian.
    let mut eval = |q: &DVector<f64>,
                    r: &mut DVector<f64>,
                    j: Option<&mut DMatrix<f64>>|
     -> Result<f64, KinematicsError> {
        kin.update(rod, q.as_slice(), None, None)?;
        for (i, (s, p)) in targets.iter().enumerate() {
            let g = kin.pose_at(rod, s.min(rod.length()))?;
            let d = g.translation - p;
            r.fixed_rows_mut::<3>(3 * i).copy_from(&d);
        }
        if let Some(j) = j {
            for (i, (s, _)) in targets.iter().enumerate() {
                kin.jacobian_at(rod, s.min(rod.length()), Frame::Mixed, &mut jac6)?;
                for c in 0..n {
                    for k in 0..3 {
                        j[(3 * i + k, c)] = jac6[(3 + k, c)];
                    }
                }
            }
        }
        Ok(r.norm_squared())
    };
    let mut q = DVector::from_column_slice(q_start);
    let mut cost = eval(&q, &mut r, Some(&mut j))?;
    let scale = rod.length();
    let mut iterations = 0;
    let mut rt = DVector::zeros(3 * m);
    let mut crawling = 0;
    for _ in 0..200 {
        if !cost.is_finite() || cost.sqrt() <= 1e-14 * scale * (m as f64).sqrt() {
            break;
        }
        iterations += 1;
        // Gauss–Newton step of least norm (singular values below 1e-10 of
        // the largest dropped), halved until the cost decreases.
        let svd = j.clone().svd(true, true);
        let tol = 1e-10 * svd.singular_values.max();
        let Ok(step) = svd.solve(&r, tol) else {
            break;
        };
        let step = -step;
        // Converged when the linearized problem promises to lower the cost
        // by no more than FIT_PTOL of it: at a misfit left by a shape the
        // pieces cannot take, the least-norm steps along the near-null
        // directions (singular values just above the cut) go on changing q
        // by 1e-3 to 1e-6 for a cost equal to 7 digits, and the step test
        // below alone then ran all 200 iterations (a 100-piece capstan
        // rope: converged in 3, ~100 taken, 25 s per fit).
        let predicted = &r + &j * &step;
        if cost - predicted.norm_squared() <= FIT_PTOL * cost {
            break;
        }
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..40 {
            let trial = &q + &step * alpha;
            if let Ok(c) = eval(&trial, &mut rt, None)
                && c.is_finite()
                && c < cost
            {
                q = trial;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            break;
        }
        // Crawling: the line search cut the step below CRAWL_ALPHA
        // CRAWL_STEPS times in a row, so the linearization does not model
        // the cost here (a marched guess with nearly singular pieces: the
        // 100-piece capstan rope crawled 200 iterations from it, cost
        // 1.75e-3 → 1.61e-3 m², steps of norm 1e4, while the start q0
        // converged in 4 to 3.9e-9 m²). fit_centerline also runs the other
        // start and keeps the better, so stopping loses only what the
        // crawl would have gained.
        crawling = if alpha < CRAWL_ALPHA { crawling + 1 } else { 0 };
        if crawling >= CRAWL_STEPS {
            cost = eval(&q, &mut r, None)?;
            break;
        }
        cost = eval(&q, &mut r, Some(&mut j))?;
        if step.norm() * alpha <= 1e-14 * (1.0 + q.norm()) {
            break;
        }
    }
    eval(&q, &mut r, None)?;
    let max = (0..m)
        .map(|i| r.fixed_rows::<3>(3 * i).norm())
        .fold(0.0, f64::max);
    Ok(CenterlineFit {
        q: q.as_slice().to_vec(),
        rms: (cost / m as f64).sqrt(),
        max,
        iterations,
    })
}

/// A point of a one-piece problem: abscissa `σ` from the piece's start
/// \[m\] (beyond its length: the same strain continued), position in the
/// piece's start frame \[m\], weight.
type LocalPoint = (f64, Vec3, f64);

/// The marched starting guess (module documentation): piece by piece from
/// the base, each fitted alone in the frame the pieces before it placed.
fn marching_guess(rod: &RodGeometry, targets: &[(f64, Vec3)], q0: &[f64]) -> Vec<f64> {
    let mut sorted: Vec<(f64, Vec3)> = targets.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut q = q0.to_vec();
    let mut g: Pose = *rod.base();
    let mut prev: Option<Vec6> = None;
    let pieces = rod.pieces();
    let mut first = 0; // first target beyond the current piece's start
    let mut local: Vec<LocalPoint> = Vec::new();
    // A point within round-off of a boundary belongs to the piece that
    // ends there (boundaries are sums of lengths; points are often
    // `L·i/n`).
    let tol = 1e-12 * rod.length();
    for (n, piece) in pieces.iter().enumerate() {
        let (a, b) = (piece.start + tol, piece.end() + tol);
        while first < sorted.len() && sorted[first].0 <= a {
            first += 1;
        }
        if first == sorted.len() {
            break;
        }
        // The piece's own points, then the next piece's (half weight), or,
        // when the piece has none, every point up to the end of the piece
        // holding the next one.
        let own_end = first + sorted[first..].partition_point(|t| t.0 <= b);
        let ahead_to = if own_end > first {
            pieces.get(n + 1).map_or(b, |p| p.end() + tol)
        } else {
            let s_next = sorted[first].0;
            pieces
                .iter()
                .find(|p| p.end() + tol >= s_next)
                .map_or(rod.length(), Piece::end)
                + tol
        };
        let ahead_end = first + sorted[first..].partition_point(|t| t.0 <= ahead_to);
        let inv = g.inverse();
        local.clear();
        for (s, p) in &sorted[first..ahead_end] {
            local.push((s - piece.start, inv.transform_point(p), 1.0));
        }
        // Fitted to its own points (all of them when it has none); among
        // the guesses' results the lowest cost there wins, and near-ties
        // (several shapes through the own points) go to the one that
        // continues best into the next piece.
        let n_own = if own_end > first {
            own_end - first
        } else {
            local.len()
        };
        let (own, ahead) = local.split_at(n_own);
        let here = piece.strain(&q);
        let mut guesses = vec![here];
        if let Some(&(sig, p, _)) = local.last() {
            guesses.push(arc_strain(&here, sig, &p));
        }
        if let Some(&(sig, p, _)) = own.last() {
            guesses.push(arc_strain(&here, sig, &p));
        }
        if let Some(xi) = prev {
            guesses.push(xi);
        }
        // Where the own points fix the piece up to discrete alternatives
        // (an arc and the same arc with whole loops added, or run
        // backwards), near-ties go to the least turning with a positive
        // stretch; where they leave a continuum open (more unknowns than
        // equations), to the best continuation into the next piece.
        let open = piece.basis.dof() > 3 * own.len();
        let tie = 1e-20 * piece.length * piece.length * own.len() as f64;
        let mut best: Option<(f64, (bool, f64), Vec<f64>)> = None;
        for xi in guesses {
            let (c, cost) = local_fit(piece, own, coordinates_of(piece, &xi));
            if !cost.is_finite() {
                continue;
            }
            let fitted = piece.basis.apply(&c) + piece.rest_strain;
            let secondary = if open {
                local_cost(piece, ahead, &c)
            } else {
                piece.length * fitted.fixed_rows::<3>(0).norm() + (fitted[3] - 1.0).abs()
            };
            let key = (fitted[3] <= 0.0, secondary);
            let better = match &best {
                None => true,
                Some((b, bk, _)) => {
                    let t = tie.max(1e-9 * b);
                    cost < *b - t
                        || (cost <= *b + t && key.partial_cmp(bk) == Some(std::cmp::Ordering::Less))
                }
            };
            if better {
                best = Some((cost, key, c));
            }
        }
        if let Some((_, _, c)) = best {
            q[piece.dofs()].copy_from_slice(&c);
        }
        let xi = piece.strain(&q);
        g = g.compose(&exp_twist(piece.length, &xi));
        prev = Some(xi);
    }
    q
}

/// The strain of the arc that leaves the origin tangent to `x` and reaches
/// `p` (local axes) at abscissa `σ` (module documentation); torsion and
/// shear are `base`'s.
fn arc_strain(base: &Vec6, sigma: f64, p: &Vec3) -> Vec6 {
    let mut xi = *base;
    let perp = Vec3::new(0.0, p.y, p.z);
    let (d, c) = (perp.norm(), p.norm());
    if sigma <= 0.0 || c == 0.0 {
        return xi;
    }
    if d <= 1e-12 * c {
        xi[1] = 0.0;
        xi[2] = 0.0;
        xi[3] = c / sigma;
        return xi;
    }
    let radius = c * c / (2.0 * d);
    let turn = 2.0 * d.atan2(p.x);
    // dt/ds = κ × x must point to the centre, along p_⊥: κ = x × p̂_⊥ / R.
    let k = Vec3::x().cross(&(perp / d)) / radius;
    xi[1] = k.y;
    xi[2] = k.z;
    xi[3] = radius * turn / sigma;
    xi
}

/// The piece coordinates whose strain `B q + ξ̄` is closest to `xi`.
fn coordinates_of(piece: &Piece, xi: &Vec6) -> Vec<f64> {
    let d = xi - piece.rest_strain;
    if let Some(sel) = piece.basis.selection() {
        return sel.iter().map(|&i| d[i]).collect();
    }
    let b = DMatrix::from_column_slice(6, piece.basis.dof(), piece.basis.matrix().as_slice());
    b.svd(true, true)
        .solve(&DVector::from_column_slice(d.as_slice()), 1e-12)
        .map_or_else(|_| vec![0.0; piece.basis.dof()], |v| v.as_slice().to_vec())
}

/// `Σ w²|p(σ) − p|²` of one piece's coordinates `c` at local points.
fn local_cost(piece: &Piece, pts: &[LocalPoint], c: &[f64]) -> f64 {
    let xi = piece.basis.apply(c) + piece.rest_strain;
    pts.iter()
        .map(|(sig, p, w)| ((exp_twist(*sig, &xi).translation - p) * *w).norm_squared())
        .sum()
}

/// Weighted least squares of one piece's coordinates to local points, by
/// Gauss–Newton (least-norm steps, halving line search) from `start`;
/// returns the coordinates and the cost `Σ w²|p(σ) − p|²`.
fn local_fit(piece: &Piece, pts: &[LocalPoint], start: Vec<f64>) -> (Vec<f64>, f64) {
    let k = piece.basis.dof();
    let bm = piece.basis.matrix();
    let strain = |c: &[f64]| piece.basis.apply(c) + piece.rest_strain;
    let cost_of = |c: &[f64]| local_cost(piece, pts, c);
    let mut c = start;
    let mut cost = cost_of(&c);
    let mut j = DMatrix::zeros(3 * pts.len(), k);
    let mut r = DVector::zeros(3 * pts.len());
    for _ in 0..100 {
        if !cost.is_finite() || cost.sqrt() <= 1e-15 * (1.0 + piece.length) {
            break;
        }
        let xi = strain(&c);
        for (i, (sig, p, w)) in pts.iter().enumerate() {
            let g = exp_twist(*sig, &xi);
            // δp = R · lin(T₋(σ) δξ), δξ = B δc (D8).
            let t = tangent_minus(*sig, &xi).to_mat6();
            let lin = g.rotation * t.fixed_rows::<3>(3) * bm * *w;
            j.fixed_rows_mut::<3>(3 * i).copy_from(&lin);
            r.fixed_rows_mut::<3>(3 * i)
                .copy_from(&((g.translation - p) * *w));
        }
        let svd = j.clone().svd(true, true);
        let tol = 1e-10 * svd.singular_values.max();
        let Ok(step) = svd.solve(&r, tol) else {
            break;
        };
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let trial: Vec<f64> = c
                .iter()
                .zip(step.iter())
                .map(|(a, d)| a - alpha * d)
                .collect();
            let tc = cost_of(&trial);
            if tc.is_finite() && tc < cost {
                c = trial;
                cost = tc;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted
            || step.norm() * alpha <= 1e-15 * (1.0 + c.iter().map(|x| x * x).sum::<f64>().sqrt())
        {
            break;
        }
    }
    (c, cost)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Basis, Strain};
    use softrod_lie::Pose;

    fn rod(pieces: usize, basis: Basis) -> RodGeometry {
        RodGeometry::uniform(0.5, pieces, basis, crate::straight(), Pose::identity()).unwrap()
    }

    #[test]
    fn circle_arc_gives_its_curvature() {
        // Points on a circle of radius R in the x–z plane: a section turning
        // about +y at κ_y = 1/R bends the rod towards −z,
        // p(s) = (R sin(s/R), 0, −R(1 − cos(s/R))).
        let radius = 0.3;
        let pts: Vec<(f64, Vec3)> = (0..=20)
            .map(|i| {
                let s = 0.5 * i as f64 / 20.0;
                let a = s / radius;
                (
                    s,
                    Vec3::new(radius * a.sin(), 0.0, -radius * (1.0 - a.cos())),
                )
            })
            .collect();
        let r = rod(4, Basis::select(&[Strain::Ky, Strain::Kz]).unwrap());
        let fit = fit_centerline(&r, &pts, &[0.0; 8]).unwrap();
        assert!(fit.max < 1e-12, "{fit:?}");
        for p in 0..4 {
            assert!((fit.q[2 * p] - 1.0 / radius).abs() < 1e-10, "{:?}", fit.q);
            assert!(fit.q[2 * p + 1].abs() < 1e-10, "{:?}", fit.q);
        }
    }

    #[test]
    fn representable_shape_is_recovered() {
        // A 3-D shape of the same pieces and basis: fitted exactly, every
        // coordinate recovered.
        let r = rod(
            3,
            Basis::select(&[Strain::Ky, Strain::Kz, Strain::Qx]).unwrap(),
        );
        let truth = [1.2, -0.4, 0.05, -2.0, 0.8, -0.02, 0.5, 1.5, 0.1];
        let mut k = RodKinematics::new(&r);
        k.update(&r, &truth, None, None).unwrap();
        let pts: Vec<(f64, Vec3)> = (0..=12)
            .map(|i| {
                let s = 0.5 * i as f64 / 12.0;
                (s, k.pose_at(&r, s).unwrap().translation)
            })
            .collect();
        let fit = fit_centerline(&r, &pts, &[0.0; 9]).unwrap();
        assert!(fit.max < 1e-11, "{fit:?}");
        for (a, b) in fit.q.iter().zip(truth) {
            assert!((a - b).abs() < 1e-8, "{:?}", fit.q);
        }
    }

    #[test]
    fn twist_of_a_straight_rod_stays_at_the_guess() {
        // Straight points fix no torsion: it stays near its starting value
        // (no torsion from nothing) while the bending is fitted to zero.
        let r = rod(2, Basis::select(&[Strain::Kx, Strain::Ky]).unwrap());
        let pts: Vec<(f64, Vec3)> = (0..=6)
            .map(|i| {
                (
                    0.5 * i as f64 / 6.0,
                    Vec3::new(0.5 * i as f64 / 6.0, 0.0, 0.0),
                )
            })
            .collect();
        let fit = fit_centerline(&r, &pts, &[0.3, 0.7, -0.2, -0.5]).unwrap();
        assert!(fit.max < 1e-12, "{fit:?}");
        // Torsion moves the points only while the rod is bent, so the
        // least-norm steps change it little on the way to straight.
        assert!(
            (fit.q[0] - 0.3).abs() < 0.01 && (fit.q[2] + 0.2).abs() < 0.01,
            "{:?}",
            fit.q
        );
        assert!(
            fit.q[1].abs() < 1e-12 && fit.q[3].abs() < 1e-12,
            "{:?}",
            fit.q
        );
    }

    #[test]
    fn curve_outside_the_model_leaves_a_residual_that_falls_with_pieces() {
        // A parabola z = −x² is not piecewise circular: the residual is
        // reported, and halves at least with twice the pieces (O(ℓ²)).
        let pts: Vec<(f64, Vec3)> = (0..=40)
            .map(|i| {
                let x = 0.4 * i as f64 / 40.0;
                // Arc length of z = −x² from 0: ∫√(1+4x²).
                let s = 0.5 * x * (1.0 + 4.0 * x * x).sqrt()
                    + 0.25 * (2.0 * x + (1.0 + 4.0 * x * x).sqrt()).ln();
                (s, Vec3::new(x, 0.0, -x * x))
            })
            .collect();
        let length = pts.last().unwrap().0;
        let fit = |pieces: usize| {
            let r = RodGeometry::uniform(
                length,
                pieces,
                Basis::select(&[Strain::Ky]).unwrap(),
                crate::straight(),
                Pose::identity(),
            )
            .unwrap();
            fit_centerline(&r, &pts, &vec![0.0; pieces]).unwrap()
        };
        let (a, b) = (fit(2), fit(4));
        assert!(a.rms > 1e-6, "{a:?}");
        assert!(b.rms < 0.5 * a.rms, "{} → {}", a.rms, b.rms);
    }

    #[test]
    fn bad_targets_are_errors() {
        let r = rod(2, Basis::all());
        let q = vec![0.0; 12];
        assert!(fit_centerline(&r, &[], &q).is_err());
        assert!(fit_centerline(&r, &[(0.6, Vec3::zeros())], &q).is_err());
        assert!(fit_centerline(&r, &[(0.1, Vec3::new(f64::NAN, 0.0, 0.0))], &q).is_err());
        assert!(fit_centerline(&r, &[(0.1, Vec3::zeros())], &q[..3]).is_err());
    }

    #[test]
    fn misfit_stops_at_a_stationary_point_in_few_iterations() {
        // Straight, then a circular arc (R = 0.1 m turning about y) from
        // s = 0.2312 m, inside a piece: no PCS shape of these pieces takes
        // it, so a misfit is left. The fit must stop at a stationary point
        // of the cost — its gradient, by central differences of the cost
        // here, ~0 against the start's — and not wander the near-null
        // directions until the step itself is round-off (before the
        // predicted-decrease test; 26 here, 14 with it).
        let (length, pieces, knee, radius) = (0.5, 40, 0.2312, 0.1);
        let pts: Vec<(f64, Vec3)> = (0..=200)
            .map(|i| {
                let s = length * i as f64 / 200.0;
                let p = if s <= knee {
                    Vec3::new(s, 0.0, 0.0)
                } else {
                    let a = (s - knee) / radius;
                    Vec3::new(knee + radius * a.sin(), 0.0, -radius * (1.0 - a.cos()))
                };
                (s, p)
            })
            .collect();
        let r = rod(
            pieces,
            Basis::select(&[Strain::Ky, Strain::Kz, Strain::Qx]).unwrap(),
        );
        let q0 = vec![0.0; r.n_dof()];
        let fit = fit_centerline(&r, &pts, &q0).unwrap();
        assert!(fit.max > 1e-5, "a misfit is left: {fit:?}");
        assert!(fit.iterations < 20, "{}", fit.iterations);
        let mut kin = RodKinematics::new(&r);
        let mut cost = |q: &[f64]| -> f64 {
            kin.update(&r, q, None, None).unwrap();
            pts.iter()
                .map(|(s, p)| (kin.pose_at(&r, *s).unwrap().translation - p).norm_squared())
                .sum()
        };
        let mut gradient = |q: &[f64]| -> f64 {
            let h = 1e-6;
            (0..q.len())
                .map(|c| {
                    let (mut a, mut b) = (q.to_vec(), q.to_vec());
                    a[c] += h;
                    b[c] -= h;
                    ((cost(&a) - cost(&b)) / (2.0 * h)).powi(2)
                })
                .sum::<f64>()
                .sqrt()
        };
        let (at_fit, at_start) = (gradient(&fit.q), gradient(&q0));
        assert!(at_fit < 1e-6 * at_start, "{at_fit:e} against {at_start:e}");
    }
}
