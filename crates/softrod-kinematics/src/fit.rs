//! Strains from a centreline: the coordinates `q` whose PCS shape passes
//! closest to given points (docs/theory.md §2, (D70)).
//!
//! Least squares on positions, `min_q Σ_i |p(s_i; q) − p_i|²`, by
//! Gauss–Newton with the exact Jacobian `∂p/∂q` (the linear rows of the
//! mixed-frame geometric Jacobian, D11) and a backtracking line search.
//! Positions alone do not fix every strain (the twist of a straight rod,
//! say): each step is the least-norm solution of the linearized problem
//! (singular values below 1e-10 of the largest dropped), so such
//! coordinates stay near the starting guess (exactly at it when they are
//! undetermined all along the way). Where the points lie on a shape
//! the rod's pieces and basis can represent, the fit is exact to round-off
//! (quadratic convergence on a zero residual).

use crate::error::KinematicsError;
use crate::rod::RodGeometry;
use crate::state::{Frame, RodKinematics};
use nalgebra::{DMatrix, DVector, Matrix6xX};
use softrod_lie::Vec3;

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
    let m = targets.len();
    let mut kin = RodKinematics::new(rod);
    let mut jac6 = Matrix6xX::zeros(n);
    let mut j = DMatrix::zeros(3 * m, n);
    let mut r = DVector::zeros(3 * m);
    let q_start = DVector::from_column_slice(q0);
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
    let mut q = q_start.clone();
    let mut cost = eval(&q, &mut r, Some(&mut j))?;
    let scale = rod.length();
    let mut iterations = 0;
    let mut rt = DVector::zeros(3 * m);
    for _ in 0..200 {
        if cost.sqrt() <= 1e-14 * scale * (m as f64).sqrt() {
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
}
