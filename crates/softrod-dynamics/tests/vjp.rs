//! The O(N) vector–Jacobian products of the inverse dynamics
//! (`inverse_dynamics_linearization_with` + `inverse_dynamics_vjp`,
//! docs/theory-derivatives.md D81–D83), and the Jacobian–vector products
//! (`inverse_dynamics_jvp`, D84), and `M v` (`inverse_dynamics_mass_product`,
//! D86, against `mass_matrix`), against `uᵀ` times (or times `a`, `b`) the dense
//! derivatives (`inverse_dynamics_derivatives`, themselves checked against
//! differences in id_derivatives.rs and tree_derivatives.rs): a six-strain
//! chain with every force term and cables (with friction, and as inputs),
//! mixed bases on two rods, a planar rod, a tree with revolute, universal,
//! spherical, free and prescribed joints, bodies and inside attachments.

mod common;

use common::{
    Lcg, Shape, Terms, driven_tree, model, robot, rod_spec, state, tilted_base, two_rods,
};
use nalgebra::DVector;
use softrod_dynamics::*;
use softrod_kinematics::{Basis, Strain};
use softrod_lie::{Pose, Vec6};
use softrod_mechanics::{Cable, Routing, Tension};

/// `max_j |vjp_j − (uᵀD)_j| / max_j Σᵢ |uᵢ||D_ij|` for `D = ∂τ/∂q` and
/// `∂τ/∂q̇`, over three random `u`, and the same measure of
/// `∂τ/∂q·a + ∂τ/∂q̇·b` for two random pairs: the products sum the same per-piece
/// quantities in another order, so they agree to round-off of the sums
/// `Σ |u||D|`, amplified at most by the world-frame lever arms the pairing
/// quantities carry (≤ 1 m here).
fn vjp_error(m: &Model, t: f64, q: &[f64], qd: &[f64], qdd: &[f64], rng: &mut Lcg) -> f64 {
    let n = m.n_dof();
    let mut dense = IdDerivatives::new(m);
    inverse_dynamics_derivatives(m, &mut dense, t, q, qd, qdd).unwrap();
    let mut work = IdDerivatives::for_products(m);
    assert_eq!(work.dtau_dq.nrows(), 0);
    inverse_dynamics_linearization_with(m, &mut work, Forces::ALL, t, q, qd, qdd).unwrap();
    // τ is the same evaluation's, bit for bit (the same sweeps).
    assert_eq!(work.tau, dense.tau);
    let (mut oq, mut ov) = (vec![0.0; n], vec![0.0; n]);
    let mut worst: f64 = 0.0;
    for _ in 0..3 {
        let u = DVector::from_vec(rng.vec(n, 1.0));
        inverse_dynamics_vjp(m, &mut work, u.as_slice(), &mut oq, &mut ov).unwrap();
        for (d, out) in [(&dense.dtau_dq, &oq), (&dense.dtau_dqd, &ov)] {
            let reference = d.tr_mul(&u);
            let scale = d.abs().tr_mul(&u.abs()).amax();
            assert!(scale > 0.0);
            let e = (DVector::from_column_slice(out) - reference).amax() / scale;
            worst = worst.max(e);
        }
    }
    // The forward products of the same linearization (D84).
    for _ in 0..2 {
        let a = DVector::from_vec(rng.vec(n, 1.0));
        let b = DVector::from_vec(rng.vec(n, 1.0));
        let mut out = vec![0.0; n];
        inverse_dynamics_jvp(m, &mut work, a.as_slice(), b.as_slice(), &mut out).unwrap();
        let reference = &dense.dtau_dq * &a + &dense.dtau_dqd * &b;
        let scale = (dense.dtau_dq.abs() * a.abs() + dense.dtau_dqd.abs() * b.abs()).amax();
        let e = (DVector::from_column_slice(&out) - reference).amax() / scale;
        worst = worst.max(e);
    }
    // The mass products of the same linearization (D86) against the mass
    // matrix of the composite-rigid-body sweep (another algorithm).
    let mut data = Data::new(m);
    m.set_time(&mut data, t);
    let mm = mass_matrix(m, &mut data, q).unwrap().clone();
    for _ in 0..2 {
        let v = DVector::from_vec(rng.vec(n, 1.0));
        let mut out = vec![0.0; n];
        inverse_dynamics_mass_product(m, &mut work, v.as_slice(), &mut out).unwrap();
        let scale = (mm.abs() * v.abs()).amax();
        let e = (DVector::from_column_slice(&out) - &mm * &v).amax() / scale;
        worst = worst.max(e);
    }
    // A dense evaluation keeps no mass blocks: refused.
    let mut out = vec![0.0; n];
    assert!(matches!(
        inverse_dynamics_mass_product(m, &mut dense, &vec![1.0; n], &mut out),
        Err(DynamicsError::NotLinearized { .. })
    ));
    // The products after a dense evaluation (same workspace kept).
    let u = DVector::from_vec(rng.vec(n, 1.0));
    inverse_dynamics_vjp(m, &mut dense, u.as_slice(), &mut oq, &mut ov).unwrap();
    let reference = dense.dtau_dq.tr_mul(&u);
    let scale = dense.dtau_dq.abs().tr_mul(&u.abs()).amax();
    worst.max((DVector::from_column_slice(&oq) - reference).amax() / scale)
}

/// Measured ≤ 3e-16 on every model below.
const TOL: f64 = 1e-13;

#[test]
fn six_strain_chain_with_every_term_and_cables() {
    let mut rng = Lcg(3);
    for pieces in [1, 6] {
        let m = model(&Shape::new(pieces, vec![Basis::all()]), Terms::ALL);
        let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.8, 2.0, 5.0);
        let e = vjp_error(&m, 0.3, &q, &qd, &qdd, &mut rng);
        println!("six strains, {pieces} pieces: {e:.1e}");
        assert!(e < TOL, "{pieces} pieces: {e:e}");
    }
    // Mixed bases on two rods.
    let m = two_rods(3, Terms::ALL, 2e6);
    let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.8, 2.0, 5.0);
    let e = vjp_error(&m, 0.1, &q, &qd, &qdd, &mut rng);
    println!("two rods, mixed bases: {e:.1e}");
    assert!(e < TOL, "two rods: {e:e}");
}

#[test]
fn cables_with_friction_and_as_inputs() {
    let mut rng = Lcg(11);
    let mut shape = Shape::new(5, vec![Basis::all()]);
    shape.length = 0.3;
    let mut rod = rod_spec("arm", &shape, Terms::NONE, tilted_base());
    rod.cables = vec![
        Cable::new(Routing::Offset { y: 0.006, z: 0.0 }, Tension::Constant(2.0)).with_friction(0.3),
        Cable::new(
            Routing::Offset {
                y: -0.004,
                z: 0.005,
            },
            Tension::Constant(1.0),
        ),
    ];
    let m = Model::new(vec![rod], Some(softrod_lie::Vec3::new(0.0, 0.0, -9.81)), 4).unwrap();
    let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.5, 1.0, 2.0);
    let e = vjp_error(&m, 0.2, &q, &qd, &qdd, &mut rng);
    println!("cables with friction: {e:.1e}");
    assert!(e < TOL, "friction: {e:e}");
    // Tensions given as inputs replace the schedules in both evaluations.
    let n = m.n_dof();
    let mut dense = IdDerivatives::new(&m);
    let mut work = IdDerivatives::for_products(&m);
    let u_in = DVector::from_vec(vec![3.5, 0.25]);
    dense.tensions = Some(u_in.clone());
    work.tensions = Some(u_in);
    inverse_dynamics_derivatives(&m, &mut dense, 0.2, &q, &qd, &qdd).unwrap();
    inverse_dynamics_linearization_with(&m, &mut work, Forces::ALL, 0.2, &q, &qd, &qdd).unwrap();
    let u = DVector::from_vec(rng.vec(n, 1.0));
    let (mut oq, mut ov) = (vec![0.0; n], vec![0.0; n]);
    inverse_dynamics_vjp(&m, &mut work, u.as_slice(), &mut oq, &mut ov).unwrap();
    let scale = dense.dtau_dq.abs().tr_mul(&u.abs()).amax();
    let e = (DVector::from_column_slice(&oq) - dense.dtau_dq.tr_mul(&u)).amax() / scale;
    assert!(e < TOL, "tension inputs: {e:e}");
}

#[test]
fn planar_rod() {
    use Strain::*;
    let mut rng = Lcg(17);
    let sel = |s: &[Strain]| Basis::select(s).unwrap();
    let mut shape = Shape::new(4, vec![sel(&[Ky, Qx, Qz]), sel(&[Ky]), sel(&[Qx, Ky])]);
    shape.rest = Vec6::new(0.0, 0.8, 0.0, 1.0, 0.0, 0.1);
    let m = Model::new(
        vec![rod_spec("planar", &shape, Terms::NONE, Pose::identity())],
        Some(softrod_lie::Vec3::new(0.0, 0.0, -9.81)),
        4,
    )
    .unwrap();
    assert!(m.rods()[0].is_planar());
    let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.5, 1.0, 2.0);
    let e = vjp_error(&m, 0.0, &q, &qd, &qdd, &mut rng);
    println!("planar: {e:.1e}");
    assert!(e < TOL, "planar: {e:e}");
}

/// The chain's products run each piece in its basis's `k` directions
/// (D101, one compile-time size per `k`): every size from 1 to 6 on one
/// rod, against the dense matrices and the mass matrix.
#[test]
fn every_basis_size_on_one_rod() {
    use Strain::*;
    let mut rng = Lcg(29);
    let sel = |s: &[Strain]| Basis::select(s).unwrap();
    let shape = Shape::new(
        6,
        vec![
            sel(&[Ky]),
            sel(&[Kx, Qz]),
            sel(&[Kx, Ky, Kz]),
            sel(&[Kx, Ky, Kz, Qx]),
            sel(&[Kx, Ky, Qx, Qy, Qz]),
            Basis::all(),
        ],
    );
    let m = model(&shape, Terms::ALL);
    let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.8, 2.0, 5.0);
    let e = vjp_error(&m, 0.2, &q, &qd, &qdd, &mut rng);
    println!("bases of 1 to 6 strains: {e:.1e}");
    assert!(e < TOL, "every basis size: {e:e}");
}

#[test]
fn trees_with_joints_bodies_and_branches() {
    let mut rng = Lcg(23);
    for (gravity, damping, tree, loads) in [(true, true, true, true), (true, false, false, false)] {
        let m = robot(gravity, damping, tree, loads);
        assert!(m.is_articulated());
        let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.4, 1.5, 3.0);
        let e = vjp_error(&m, 0.0, &q, &qd, &qdd, &mut rng);
        println!("robot g{gravity} d{damping} tree{tree} loads{loads}: {e:.1e}");
        assert!(e < TOL, "robot: {e:e}");
    }
}

/// A rod on a revolute joint carrying a branch inside its second piece (a
/// universal joint) and, at its tip, a rod on a prescribed prismatic joint:
/// the exits at a section and at a tip, a node without coordinates on the
/// path, cables and dead loads on every rod.
#[test]
fn tree_with_revolute_inside_branch_and_prescribed_joint() {
    let mut rng = Lcg(29);
    let m = driven_tree();
    assert_eq!(m.n_prescribed(), 1);
    for t in [0.0, 0.37] {
        let (q, qd, qdd) = state(&mut rng, m.n_dof(), 0.3, 1.0, 2.0);
        let e = vjp_error(&m, t, &q, &qd, &qdd, &mut rng);
        println!("tree, t = {t}: {e:.1e}");
        assert!(e < TOL, "tree, t = {t}: {e:e}");
    }
}

#[test]
fn misuse_is_an_error() {
    let m = model(&Shape::new(2, vec![Basis::all()]), Terms::ALL);
    let n = m.n_dof();
    let mut work = IdDerivatives::for_products(&m);
    let (mut oq, mut ov) = (vec![0.0; n], vec![0.0; n]);
    let u = vec![1.0; n];
    assert!(matches!(
        inverse_dynamics_vjp(&m, &mut work, &u, &mut oq, &mut ov),
        Err(DynamicsError::NotLinearized { .. })
    ));
    // The dense evaluation needs the dense matrices.
    let z = vec![0.0; n];
    assert!(matches!(
        inverse_dynamics_derivatives(&m, &mut work, 0.0, &z, &z, &z),
        Err(DynamicsError::WorkspaceMismatch { .. })
    ));
    inverse_dynamics_linearization_with(&m, &mut work, Forces::ALL, 0.0, &z, &z, &z).unwrap();
    let short = vec![1.0; n - 1];
    assert!(matches!(
        inverse_dynamics_vjp(&m, &mut work, &short, &mut oq, &mut ov),
        Err(DynamicsError::SizeMismatch { .. })
    ));
    let mut bad = u.clone();
    bad[1] = f64::NAN;
    assert!(matches!(
        inverse_dynamics_vjp(&m, &mut work, &bad, &mut oq, &mut ov),
        Err(DynamicsError::NotFinite { .. })
    ));
    // A failed linearization leaves none behind.
    let mut nan = z.clone();
    nan[0] = f64::NAN;
    assert!(
        inverse_dynamics_linearization_with(&m, &mut work, Forces::ALL, 0.0, &nan, &z, &z).is_err()
    );
    assert!(matches!(
        inverse_dynamics_vjp(&m, &mut work, &u, &mut oq, &mut ov),
        Err(DynamicsError::NotLinearized { .. })
    ));
}

/// Contact forces enter the dense derivatives only: the linearization
/// refuses a model with contact, naming it.
#[test]
fn contact_is_refused() {
    use softrod_mechanics::contact::{Obstacle, Shape as Body};
    let material = softrod_mechanics::Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .build()
        .unwrap();
    let m = Model::builder()
        .rod(Rod::builder(0.3).pieces(3).circle(0.01).material(material))
        .obstacle(Obstacle::new(
            "table",
            Body::Plane {
                point: softrod_lie::Vec3::new(0.0, 0.0, -0.5),
                normal: softrod_lie::Vec3::z(),
            },
        ))
        .build()
        .unwrap();
    let z = vec![0.0; m.n_dof()];
    let mut work = IdDerivatives::for_products(&m);
    let err = inverse_dynamics_linearization_with(&m, &mut work, Forces::ALL, 0.0, &z, &z, &z)
        .unwrap_err();
    assert!(matches!(err, DynamicsError::UnsupportedContact { .. }));
    assert!(err.to_string().contains("contact"), "{err}");
}
