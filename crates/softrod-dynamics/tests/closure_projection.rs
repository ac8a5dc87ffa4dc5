//! The projection of a state onto the closures (docs/theory.md D121),
//! checked by what it must produce, each with a quantity computed another
//! way: the closure residual of `constraint_residual` at the projected
//! positions, the closures' rate by central differences of that residual
//! along the projected motion (the drive's time included), the velocity
//! correction orthogonal to every motion the closures allow in the metric
//! of the dense mass matrix (`mass_matrix`, the composite algorithm, not the
//! O(N) solves the projection uses), and the position correction of a
//! small step off the manifold the same to first order.

mod common;

use common::closed::{catenary, driven, four_bar, redundant, two_closures};
use common::wavy;

use nalgebra::{DMatrix, DVector};
use softrod_dynamics::{
    ClosureKind, Data, Model, constraint_jacobian, constraint_residual, mass_matrix,
    project_onto_closures, projection_tolerance,
};

/// An orthonormal basis of the null space of `J` (the motions the closures
/// allow): the right singular vectors of the singular values below `1e-10`
/// of the largest, and those past `J`'s rows.
fn null_space(j: &DMatrix<f64>) -> DMatrix<f64> {
    let n = j.ncols();
    let jtj = j.transpose() * j;
    let eig = jtj.symmetric_eigen();
    let top = eig.eigenvalues.iter().fold(0.0_f64, |a, &b| a.max(b));
    let cols: Vec<_> = (0..n)
        .filter(|&i| eig.eigenvalues[i] <= 1e-20 * top)
        .map(|i| eig.eigenvectors.column(i).into_owned())
        .collect();
    DMatrix::from_columns(&cols)
}

fn phi_at(model: &Model, data: &mut Data, t: f64, q: &[f64]) -> DVector<f64> {
    model.set_time(data, t);
    constraint_residual(model, data, q).unwrap()
}

fn check(name: &str, model: &Model, t: f64, seed: f64) {
    let n = model.n_dof();
    let mut data = Data::new(model);
    let tol = projection_tolerance(model);
    let (mut q, mut qd) = (wavy(n, 0.05, seed), wavy(n, 0.8, seed + 1.0));
    let qd0 = qd.clone();
    let p = project_onto_closures(model, &mut data, t, &mut q, &mut qd, tol).unwrap();
    assert!(p.converged, "{name}: {p:?}");
    assert!(
        p.iterations > 0 && p.residual_before > 1e3 * tol,
        "{name}: {p:?}"
    );

    // Positions: every row of φ at the projected q (the norm of D66 is
    // at most the rows' largest entry times ℓ for welds; 1e-11 ℓ here).
    let phi = phi_at(model, &mut data, t, &q);
    assert!(phi.amax() <= tol, "{name}: φ {}", phi.amax());

    // Velocities: dφ/dt along (q̇, 1) by central differences, against the
    // closures' rate before (J q̇₀ + the drive's part, same differences).
    let rate = |data: &mut Data, v: &[f64]| {
        let e = 1e-6;
        let shift = |s: f64| {
            q.iter()
                .zip(v)
                .map(|(a, b)| a + s * e * b)
                .collect::<Vec<_>>()
        };
        let (qp, qm) = (shift(1.0), shift(-1.0));
        (phi_at(model, data, t + e, &qp) - phi_at(model, data, t - e, &qm)) / (2.0 * e)
    };
    let before = rate(&mut data, &qd0).amax();
    let after = rate(&mut data, &qd).amax();
    assert!(
        before > 1e-2,
        "{name}: the start must move off the closures ({before})"
    );
    assert!(
        after <= 1e-7 * before,
        "{name}: rate {after} (before {before})"
    );

    // The velocity correction is M-orthogonal to the allowed motions.
    let m = mass_matrix(model, &mut data, &q).unwrap().clone();
    let j = constraint_jacobian(model, &mut data, &q).unwrap();
    let z = null_space(&j);
    assert!(
        z.ncols() > 0 && z.ncols() < n,
        "{name}: null space {}",
        z.ncols()
    );
    let dv = DVector::from_column_slice(&qd) - DVector::from_column_slice(&qd0);
    // Rounding of the O(N) solves is relative to ‖M‖‖Δq̇‖, amplified by
    // M's condition number (up to 3e6 here: light rods, stiff in stretch
    // and shear per unit inertia); Zᵀ M Δq̇ is exactly 0 in exact arithmetic.
    let ev = m.clone().symmetric_eigen().eigenvalues;
    let cond = ev.max() / ev.min();
    let tangential = (z.transpose() * &m * &dv).norm();
    let scale = ev.max() * dv.norm();
    let bound = 100.0 * f64::EPSILON * cond * scale;
    assert!(
        tangential <= bound,
        "{name}: {tangential:e} > {bound:e} (cond {cond:e})"
    );

    // Again: nothing to do on the positions, the velocities kept.
    let (q1, qd1) = (q.clone(), qd.clone());
    let again = project_onto_closures(model, &mut data, t, &mut q, &mut qd, tol).unwrap();
    assert_eq!(again.iterations, 0, "{name}");
    assert_eq!(q, q1, "{name}");
    let moved = qd
        .iter()
        .zip(&qd1)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        moved <= 1e-12 * qd1.iter().fold(1.0_f64, |a, b| a.max(b.abs())),
        "{name}: {moved}"
    );

    // A small step off the manifold comes back M-orthogonally to first
    // order: its tangential part is O(ε²).
    let eps = 1e-5;
    let dir = wavy(n, 1.0, seed + 2.0);
    let mut qe: Vec<f64> = q1.iter().zip(&dir).map(|(a, b)| a + eps * b).collect();
    let mut qde = qd1.clone();
    let back = project_onto_closures(model, &mut data, t, &mut qe, &mut qde, tol).unwrap();
    assert!(back.converged && back.iterations > 0, "{name}: {back:?}");
    let dq: DVector<f64> = DVector::from_iterator(n, qe.iter().zip(&q1).map(|(a, b)| a - b))
        - DVector::from_column_slice(&dir) * eps;
    let tangential = (z.transpose() * &m * &dq).amax();
    let scale = (&m * &dq).amax();
    assert!(
        tangential <= 1e-3 * scale,
        "{name}: position {tangential} of {scale}"
    );
}

#[test]
fn four_bar_projects_onto_its_loop() {
    check("four-bar", &four_bar(), 0.0, 0.2);
}

#[test]
fn pinned_rod_projects_onto_its_pins() {
    check("catenary", &catenary(4), 0.0, 0.7);
}

#[test]
fn sliders_project_onto_their_axes() {
    check(
        "sliders",
        &two_closures(ClosureKind::Slider {
            axis: softrod_lie::Vec3::z(),
        }),
        0.0,
        1.3,
    );
}

#[test]
fn welds_project_with_their_drive() {
    // The drive moves the weld's frames: the projected velocities carry
    // the drive's rate at t, not zero.
    for t in [0.0, 0.37] {
        check(&format!("driven t = {t}"), &driven(), t, 0.4);
    }
}

#[test]
fn redundant_rows_are_dropped() {
    check("redundant", &redundant(), 0.0, 2.1);
}

#[test]
fn a_model_without_closures_is_left_alone() {
    let model = Model::builder()
        .rod(common::soft_rod("a", 0.3, 3))
        .build()
        .unwrap();
    let mut data = Data::new(&model);
    let n = model.n_dof();
    let (mut q, mut qd) = (wavy(n, 0.3, 0.1), wavy(n, 0.8, 0.2));
    let (q0, qd0) = (q.clone(), qd.clone());
    let p = project_onto_closures(&model, &mut data, 0.0, &mut q, &mut qd, 1e-12).unwrap();
    assert!(p.converged && p.iterations == 0);
    assert_eq!((q, qd), (q0, qd0));
}
