//! Trajectory gradients of a linear(ized) rod against the closed-form
//! sensitivity of its modal response (docs/theory-control.md G31).
//!
//! A straight rod with no gravity, incompressible (`ν = ½`, so `G = E/3`)
//! and Kelvin–Voigt viscous, released at rest from a small bend. Near the
//! straight configuration its equations of motion are
//! `M q̈ + D q̇ + K q = 0` with `M ∝ ρ`, `K ∝ E` and, at `ν = ½`,
//! `D = (3μ/E) K` exactly (the viscosity diagonal `diag(μJx, 3μJy, 3μJz,
//! 3μA, μA, μA)` is `3μ/E` times the stiffness diagonal `diag(GJx, EJy,
//! EJz, EA, GA, GA)`): proportional damping, so the modes of `(K, M)`
//! decouple it. Each modal coordinate obeys `ẍ + τω² ẋ + ω² x = 0`,
//! `τ = 3μ/E`, `ω² = λ E ρ₀/(E₀ ρ)` with `λ` the eigenvalues at `(E₀, ρ₀)`,
//! and from rest
//!
//! ```text
//! x(t) = x₀ (s₊ e^{s₋t} − s₋ e^{s₊t}) / (s₊ − s₋),   s± = −a ± √(a² − ω²),   a = τω²/2
//! ```
//!
//! (complex `s±` for the underdamped modes, real for the overdamped
//! ones). The closed form's derivatives in `E`, `ρ` and `μ` are taken by
//! central differences of that formula (smooth, cheap, independent of
//! the code under test); the adjoint's are of the computed trajectory. At
//! a small amplitude the two differ by the linearization (relative
//! `O(θ²)`: the planar rod is mirror-symmetric, so `M(q) = M(0) + O(q²)`)
//! and by the integrator's error, which falls at its order as the step
//! halves. Unlike the time scaling of G10 this covers the viscosity, whose
//! sensitivity is not a change of time scale.

use nalgebra::{Complex, DMatrix, DVector};
use softrod::{GradientMethod, GradientOptions, LossTerm, Simulation};

const E: f64 = 1.0e6;
const RHO: f64 = 1000.0;
const MU: f64 = 5.0e2;
const RADIUS: f64 = 0.01;
const LENGTH: f64 = 0.4;
const PIECES: usize = 4;
const DURATION: f64 = 1.2;
const TIMES: [f64; 4] = [0.3, 0.6, 0.9, 1.2];

fn scene(integrator: &str) -> String {
    format!(
        r#"
[run]
integrator = "{integrator}"
[world]
gravity = [0.0, 0.0, 0.0]
[[rod]]
name = "arm"
length = {LENGTH:e}
pieces = {PIECES}
strains = ["ky", "qx", "qz"]
section = {{ shape = "circle", radius = {RADIUS:e} }}
material = {{ density = {RHO:e}, young = {E:e}, poisson = 0.5, viscosity = {MU:e} }}
"#
    )
}

/// The stiffness of the straight rod in its coordinates: per piece of
/// length `ℓ`, the constant strains `ky, qx, qz` carry `ℓ·(EJy, EA, GA)`
/// (the elastic force `∫ Bᵀ Γ B q ds` with a constant basis per piece).
fn stiffness() -> DMatrix<f64> {
    let area = std::f64::consts::PI * RADIUS * RADIUS;
    let jy = std::f64::consts::PI * RADIUS.powi(4) / 4.0;
    let g = E / 3.0;
    let l = LENGTH / PIECES as f64;
    let per_piece = [E * jy * l, E * area * l, g * area * l];
    DMatrix::from_diagonal(&DVector::from_fn(3 * PIECES, |i, _| per_piece[i % 3]))
}

/// The modes of `(K, M)` at `(E, ρ)`: eigenvalues `ω²` and `M`-orthonormal
/// shapes (columns).
fn modes(k: &DMatrix<f64>, m: &DMatrix<f64>) -> (DVector<f64>, DMatrix<f64>) {
    let l = m
        .clone()
        .cholesky()
        .expect("M is positive definite")
        .unpack();
    let li = l.clone().try_inverse().unwrap();
    let a = &li * k * li.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let eig = a.symmetric_eigen();
    (eig.eigenvalues, li.transpose() * eig.eigenvectors)
}

/// The closed-form response `q(t)` at `(e, rho, mu)` from `q(0) = q0`,
/// `q̇(0) = 0`, given the modes at `(E, ρ)`.
fn response(
    lambda: &DVector<f64>,
    phi: &DMatrix<f64>,
    x0: &DVector<f64>,
    (e, rho, mu): (f64, f64, f64),
    t: f64,
) -> DVector<f64> {
    let tau = 3.0 * mu / e;
    let mut q = DVector::zeros(phi.nrows());
    for k in 0..lambda.len() {
        let w2 = lambda[k] * (e / E) * (RHO / rho);
        let a = 0.5 * tau * w2;
        let root = Complex::new(a * a - w2, 0.0).sqrt();
        let (sp, sm) = (-a + root, -a - root);
        let x = (sp * (sm * t).exp() - sm * (sp * t).exp()) / (sp - sm);
        q += phi.column(k) * (x0[k] * x.re);
    }
    q
}

#[test]
fn young_density_and_viscosity_gradients_follow_the_modal_closed_form() {
    let errors = modal_errors("esdirk", &[4e-3, 2e-3]);
    // The integrator's error dominates and falls at its order, 4 on fixed
    // steps (when written: 8.6e-7 at h = 4e-3, 5.4e-8 at 2e-3, then 3.4e-9
    // and 2.6e-10 at 1e-3 and 5e-4, the viscosity's 1.7e-9 there the
    // floor of this comparison).
    assert!(errors[1] < 1e-7, "{errors:?}");
    assert!(errors[0] / errors[1] > 10.0, "{errors:?}");
}

/// ESDIRK5(4)7L[2]SA's gradients (its own discrete adjoint, G27) against
/// the same closed form: the error falls at its order, 5.
#[test]
fn esdirk5_gradients_follow_the_modal_closed_form_at_order_5() {
    let errors = modal_errors("esdirk5", &[1e-2, 5e-3, 2.5e-3]);
    // When written: 1.5e-6, 5.9e-8, 4.7e-10 (halving ratios 26 and 125;
    // ESDIRK4(3) needs h = 2e-3 for 5.4e-8). Each halving must beat order
    // 4's 16, and the two together order 4.5 (2⁹); the linearization's and
    // the closed form's own errors are below 1e-10.
    assert!(errors[1] < 1e-7, "{errors:?}");
    assert!(
        errors[0] / errors[1] > 20.0 && errors[1] / errors[2] > 20.0,
        "{errors:?}"
    );
    assert!(errors[0] / errors[2] > 512.0, "{errors:?}");
}

/// Radau IIA's gradients (its own discrete adjoint, G25) against the same
/// closed form: on this linear problem the method has its classical order
/// `2s − 1 = 5`, so each halving must beat order 4's 16 and the two
/// together order 4.5 (2⁹), as ESDIRK5(4)'s. When written: 6.2e-6,
/// 2.1e-7, 5.0e-9 (ratios 30 and 41; the viscosity entry the worst, its
/// error constant larger than ESDIRK5(4)'s 1.5e-6 at 10 ms), so the finest
/// step must be below 1e-8, above this comparison's ~2e-9 floor.
#[test]
fn radau5_gradients_follow_the_modal_closed_form_at_order_5() {
    let errors = modal_errors("radau5", &[1e-2, 5e-3, 2.5e-3]);
    assert!(errors[2] < 1e-8, "{errors:?}");
    assert!(
        errors[0] / errors[1] > 20.0 && errors[1] / errors[2] > 20.0,
        "{errors:?}"
    );
    assert!(errors[0] / errors[2] > 512.0, "{errors:?}");
}

/// The worst relative error of the adjoint's `∂L/∂(E, ρ, μ)` against the
/// closed form, with `integrator` on fixed steps of each of `steps`.
fn modal_errors(integrator: &str, steps: &[f64]) -> Vec<f64> {
    let n = 3 * PIECES;
    let mut s = Simulation::from_toml(&scene(integrator), "modal")
        .unwrap()
        .0;
    assert_eq!(s.n_dof(), n);
    let m = s.mass_matrix(&vec![0.0; n]).unwrap();
    let (lambda, phi) = modes(&stiffness(), &m);
    // The modes are those of the rod's own linearization: the stiffness
    // above is what the inverse dynamics gives at rest (its q-derivative
    // by central differences of the residual at q̈ = 0 would be the same).
    let w1 = lambda.min().sqrt();
    assert!(w1 > 1.0 && w1 < 10.0, "first bending frequency {w1} rad/s");

    // A small bend (tip rotation ~4e-5 rad): the linearization's error is
    // relative θ² ~ 1e-9 (at ten times the amplitude the comparison
    // bottoms out at 2e-8, a hundred times higher, as θ² says).
    let amplitude = 1e-4;
    let q0 = DVector::from_fn(n, |i, _| {
        if i % 3 == 0 {
            amplitude * (1.0 - 0.3 * (i / 3) as f64)
        } else {
            0.0
        }
    });
    let x0 = phi.transpose() * &m * &q0;
    let weights: Vec<f64> = (0..n)
        .map(|i| {
            if i % 3 == 0 {
                1.0 + 0.1 * i as f64
            } else {
                1e3
            }
        })
        .collect();

    // The loss ½ Σ_t Σ_i wᵢ qᵢ(t)² and its closed-form derivative.
    let closed_loss = |p: (f64, f64, f64)| -> f64 {
        TIMES
            .iter()
            .map(|&t| {
                let q = response(&lambda, &phi, &x0, p, t);
                0.5 * (0..n).map(|i| weights[i] * q[i] * q[i]).sum::<f64>()
            })
            .sum()
    };
    let closed_gradient = |which: usize| -> f64 {
        let base = [E, RHO, MU];
        let d = 1e-6 * base[which];
        let at = |sign: f64| {
            let mut p = base;
            p[which] += sign * d;
            closed_loss((p[0], p[1], p[2]))
        };
        (at(1.0) - at(-1.0)) / (2.0 * d)
    };
    let closed = [closed_gradient(0), closed_gradient(1), closed_gradient(2)];

    let names = ["arm.young", "arm.density", "arm.viscosity"];
    let mut errors = Vec::new();
    for &h in steps {
        let mut s = Simulation::from_toml(&scene(integrator), "modal")
            .unwrap()
            .0;
        s.set_initial_state(q0.as_slice(), &vec![0.0; n]).unwrap();
        let mut loss = vec![LossTerm::Quadratic {
            times: TIMES.to_vec(),
            q_weights: weights.clone(),
            qdot_weights: vec![0.0; n],
            q_ref: None,
        }];
        let options = GradientOptions {
            fixed_step: Some(h),
            newton_tol: Some(1e-10),
            method: GradientMethod::Adjoint,
        };
        let g = s
            .value_and_gradient(&mut loss, &names, DURATION, &options)
            .unwrap();
        let value_error = (g.value - closed_loss((E, RHO, MU))).abs() / closed_loss((E, RHO, MU));
        let mut worst: f64 = 0.0;
        for (name, c) in names.iter().zip(closed) {
            let a = g.get(name).unwrap()[0];
            let rel = ((a - c) / c).abs();
            eprintln!(
                "{integrator}, h = {h:e}: {name}: adjoint {a:e}, closed form {c:e}, relative {rel:e}"
            );
            worst = worst.max(rel);
        }
        eprintln!("h = {h:e}: loss relative error {value_error:e}");
        assert!(
            value_error < 1e-6,
            "loss {} vs {}",
            g.value,
            closed_loss((E, RHO, MU))
        );
        errors.push(worst);
    }
    eprintln!("{integrator}: {errors:?}");
    errors
}
