//! derivations.md §8(h): the sanity trajectory, reproduced end to end
//! (model building, O(N) forward dynamics, adaptive integration).
//!
//! L = 0.5 m, r = 0.01 m, ρ = 1000, E = 1e7, ν = 0.5 (G = E/3), 8 equal
//! pieces with strains (ky, qx, qz), gravity (0, 0, −9.81), released from
//! straight horizontal rest, 5 Gauss points per piece. Reference tip
//! positions from the verified prototype (DOP853, rtol 1e-12).

use nalgebra::DVector;
use softrod_dynamics::{Model, Rod, energies};
use softrod_integrate::{Integrator, NoHooks, Options, RodSystem, integrate_second_order};
use softrod_kinematics::{Basis, RodGeometry, RodKinematics, Strain, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{Material, RodProperties, Section};

fn sanity_model() -> Model {
    let rod = RodGeometry::uniform(
        0.5,
        8,
        Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap(),
        straight(),
        Pose::identity(),
    )
    .unwrap();
    let body = RodProperties::new(
        Section::Circle { radius: 0.01 },
        Material::with_poisson(1000.0, 1e7, 0.5, 0.0).unwrap(),
        0.5,
    )
    .unwrap();
    Model::new(
        vec![Rod::new("arm", rod, body)],
        Some(Vec3::new(0.0, 0.0, -9.81)),
        5,
    )
    .unwrap()
}

/// (t, x_tip, z_tip) of derivations §8(h).
const REFERENCE: [(f64, f64, f64); 3] = [
    (0.25, 0.366446853, -0.314312480),
    (0.50, 0.342225557, -0.338455217),
    (1.00, 0.391295819, -0.286765539),
];

#[test]
fn sanity_trajectory_matches_the_verified_prototype() {
    let model = sanity_model();
    let n = model.n_dof();
    let mut sys = RodSystem::new(model);
    let opts = Options {
        rtol: 1e-11,
        atol: 1e-13,
        max_steps: 2_000_000,
        ..Options::default()
    }
    .with_t_eval(REFERENCE.iter().map(|r| r.0).collect());
    let zero = DVector::zeros(n);
    let sol = integrate_second_order(
        &mut sys,
        Integrator::Dopri5,
        (0.0, 1.0),
        &zero,
        &zero,
        &opts,
        &mut NoHooks,
    )
    .expect("integration succeeds");
    let rod = &sys.model.rods()[0].spec.geometry;
    let mut kin = RodKinematics::new(rod);
    let mut e0 = None;
    for (i, (t, x, z)) in REFERENCE.iter().enumerate() {
        assert!((sol.t[i] - t).abs() < 1e-12);
        let q = sol.y[i].rows(0, n).into_owned();
        let qd = sol.y[i].rows(n, n).into_owned();
        kin.update(rod, q.as_slice(), None, None).unwrap();
        let p = kin.tip_pose().translation;
        // Table digits are 1e-9 m; dopri5 at rtol 1e-11 adds ~1e-9.
        let err = ((p.x - x).powi(2) + (p.z - z).powi(2)).sqrt();
        println!("t = {t}: tip ({:.9}, {:.9}), error {err:.2e} m", p.x, p.z);
        assert!(err < 2e-8, "t = {t}: tip ({}, {}) vs ({x}, {z})", p.x, p.z);
        assert!(p.y.abs() < 1e-14);
        let e = energies(&sys.model, &mut sys.data, q.as_slice(), qd.as_slice()).unwrap();
        if *t == 0.5 {
            // derivations §8(h): KE = 0.0588, V_e = 0.1594, V_g = −0.2182 J.
            assert!((e.kinetic - 0.0588).abs() < 1e-4, "{e:?}");
            assert!((e.elastic - 0.1594).abs() < 1e-4, "{e:?}");
            assert!((e.gravitational + 0.2182).abs() < 1e-4, "{e:?}");
        }
        // Undamped: the total energy stays at its initial value (0 J).
        let total = e.total();
        let e0 = *e0.get_or_insert(0.0);
        assert!(
            (total - e0).abs() < 1e-8,
            "energy drift {total:e} J at t = {t}"
        );
    }
    println!("stats: {:?}", sol.stats);
}
