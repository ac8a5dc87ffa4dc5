//! The matrix-free lowest modes (`lowest_modes`, docs/theory.md E11)
//! against the dense eigensolve of `modes` at small N and against the
//! Euler–Bernoulli cantilever frequencies at N = 1 000.

mod common;

use common::{Shape, Terms, bases, cantilever_root, model, ritz_constant};
use softrod_dynamics::{
    Data, Model, Rod, StaticsOptions, lowest_modes, mass_matrix, modes, statics,
};
use softrod_kinematics::{Basis, RodGeometry, Strain, straight};
use softrod_lie::Pose;
use softrod_mechanics::{Material, RodProperties, Section};
use std::f64::consts::PI;

fn equilibrium(model: &Model) -> Vec<f64> {
    let mut data = Data::new(model);
    let q0 = vec![0.0; model.n_dof()];
    statics(model, &mut data, &q0, &StaticsOptions::default())
        .unwrap()
        .q
        .as_slice()
        .to_vec()
}

/// Six precurved mixed-basis pieces under gravity (conservative, so
/// `K_eff` is symmetric to round-off), about their equilibrium: the lowest
/// four frequencies equal the dense solver's, and each shape is the dense
/// shape up to sign (`|v_sᵀ M v_d| = 1` for `M`-normalized shapes of
/// simple eigenvalues).
#[test]
fn lowest_modes_match_the_dense_eigensolve() {
    let terms = Terms {
        gravity: true,
        ..Terms::NONE
    };
    let model = model(&Shape::new(6, bases()), terms);
    let q = equilibrium(&model);
    let mut data = Data::new(&model);
    let dense = modes(&model, &mut data, &q, 0.0).unwrap();
    let low = lowest_modes(&model, &mut data, &q, 0.0, 4).unwrap();
    assert!(
        dense.asymmetry < 1e-12,
        "dense asymmetry {:e}",
        dense.asymmetry
    );
    assert!(
        low.asymmetry < 1e-9,
        "estimated asymmetry {:e}",
        low.asymmetry
    );
    let m = mass_matrix(&model, &mut data, &q).unwrap().clone();
    for i in 0..4 {
        // The products K_eff v are differenced to ~1e-10 of ‖τ‖ and the
        // GMRES solves stop at 1e-11: 1e-7 of ω leaves a margin of 100.
        let rel = (low.omega[i] - dense.omega[i]).abs() / dense.omega[i];
        assert!(
            rel < 1e-7,
            "mode {i}: {} vs dense {} rad/s",
            low.omega[i],
            dense.omega[i]
        );
        let overlap = (low.shapes.column(i).transpose() * &m * dense.shapes.column(i))[0].abs();
        assert!((overlap - 1.0).abs() < 1e-6, "mode {i}: overlap {overlap}");
    }
}

/// The lowest 10 modes of a 1 000-piece cantilever (bending κ_y only,
/// L/r = 1 000, no gravity) against `ω_k = β_k² √(EI/ρA L⁴)`, roots of
/// `cosh β cos β = −1` (the fourth onward near `(k − ½)π`).
#[test]
fn lowest_modes_of_a_long_cantilever_are_euler_bernoulli() {
    let (length, rho, young) = (0.5_f64, 1000.0, 1e7);
    let r = length / 1000.0;
    let material = Material::builder()
        .density(rho)
        .young(young)
        .shear_modulus(young / 3.0)
        .build()
        .unwrap();
    let n = 1000;
    let geometry = RodGeometry::uniform(
        length,
        n,
        Basis::select(&[Strain::Ky]).unwrap(),
        straight(),
        Pose::identity(),
    )
    .unwrap();
    let body = RodProperties::new(Section::Circle { radius: r }, material, length).unwrap();
    let model = Model::new(vec![Rod::new("beam", geometry, body)], None, 2).unwrap();
    let mut data = Data::new(&model);
    let low = lowest_modes(&model, &mut data, &vec![0.0; n], 0.0, 10).unwrap();
    let ei = young * PI * r.powi(4) / 4.0;
    let scale = (ei / (rho * PI * r * r * length.powi(4))).sqrt();
    for k in 0..10 {
        let beta = cantilever_root((k as f64 + 0.5) * PI + if k == 0 { 0.33 } else { 0.0 });
        let exact = beta * beta * scale;
        let err = (low.omega[k] - exact) / exact;
        // Ritz error C_k/N² above, the rotary inertia that PCS carries
        // (Rayleigh beam) ½β²(r_g/L)², r_g² = r²/4, below: each ≤ 1.2e-4
        // here; twice their sum bounds the error.
        let ritz = ritz_constant(beta) / (n * n) as f64;
        let rotary = 0.5 * beta * beta * (r / length).powi(2) / 4.0;
        assert!(
            err < 2.0 * ritz + 1e-9 && err > -2.0 * rotary - 1e-9,
            "mode {}: ω = {} vs {exact} rad/s (relative {err:e}, Ritz {ritz:e}, rotary {rotary:e})",
            k + 1,
            low.omega[k]
        );
    }
}

/// World-frame point moments are not conservative (a couple of fixed
/// direction does path-dependent work on a rotating section): with the
/// dead point loads (forces and moments) `K_eff` is asymmetric by ~2.5e-6,
/// which K⁻¹ amplifies past what Lanczos tolerates, so `lowest_modes`
/// refuses, naming the asymmetry, while the dense `modes` (symmetric part)
/// reports the same asymmetry.
#[test]
fn non_conservative_loads_are_refused() {
    let terms = Terms {
        gravity: true,
        dead_point: true,
        ..Terms::NONE
    };
    let model = model(&Shape::new(6, bases()), terms);
    let q = equilibrium(&model);
    let mut data = Data::new(&model);
    let dense = modes(&model, &mut data, &q, 0.0).unwrap();
    assert!(dense.asymmetry > 1e-6, "{:e}", dense.asymmetry);
    match lowest_modes(&model, &mut data, &q, 0.0, 4) {
        Err(softrod_dynamics::DynamicsError::NotSymmetric { asymmetry, .. }) => {
            // The probes' estimate of the exact ratio (±30 %).
            assert!(
                (asymmetry / dense.asymmetry - 1.0).abs() < 0.5,
                "{asymmetry:e}"
            );
        }
        other => panic!("not refused: {other:?}"),
    }
}
