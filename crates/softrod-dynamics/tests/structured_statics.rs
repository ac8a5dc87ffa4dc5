//! The matrix-free statics (`StaticsSolver::Structured`, docs/theory.md
//! E8–E10) against the dense Newton and against the exact circle of a
//! pure tip moment, from a few pieces to a few hundred.

mod common;

use common::{Shape, Terms, bases, model, robot};
use nalgebra::DVector;
use softrod_dynamics::{
    Data, DynamicsError, Model, Rod, StaticsOptions, StaticsSolver, static_force, statics,
};
use softrod_kinematics::{Basis, RodGeometry, RodKinematics, straight};
use softrod_lie::{Pose, Vec3};
use softrod_mechanics::{LoadFrame, Material, PointLoad, RodProperties, Section};
use std::f64::consts::PI;

fn solve(model: &Model, solver: StaticsSolver) -> Result<DVector<f64>, DynamicsError> {
    let options = StaticsOptions {
        solver,
        ..StaticsOptions::default()
    };
    let mut data = Data::new(model);
    Ok(statics(model, &mut data, &vec![0.0; model.n_dof()], &options)?.q)
}

/// `‖τ_s(q)‖∞`, the static force left at `q`, by the library's inverse
/// dynamics (not by either solver).
fn leftover(model: &Model, q: &DVector<f64>) -> f64 {
    let mut data = Data::new(model);
    static_force(model, &mut data, 0.0, q.as_slice())
        .unwrap()
        .amax()
}

/// Both solvers stop at `‖r‖∞ ≤ 10⁻¹² ‖f‖∞` (the default tolerance), so
/// their solutions differ by at most `‖K_t⁻¹‖ · 2·10⁻¹² ‖f‖`: with the
/// stiffness contrast of these soft rods (shear/bending ~10⁴) that is
/// below 10⁻⁷ of `‖q‖`, the bound asserted.
fn assert_agree(label: &str, model: &Model) {
    let dense = solve(model, StaticsSolver::Dense).unwrap();
    let structured = solve(model, StaticsSolver::Structured).unwrap();
    let diff = (&structured - &dense).amax() / dense.amax();
    assert!(
        diff < 1e-7,
        "{label}: structured and dense equilibria differ by {diff:e} of ‖q‖"
    );
    let rs = leftover(model, &structured);
    let rd = leftover(model, &dense);
    assert!(
        rs <= 10.0 * rd.max(1e-12 * dense.amax()),
        "{label}: structured leaves {rs:e}, dense {rd:e}"
    );
}

/// Every static force term (gravity, dead and follower point loads,
/// distributed loads, a cable) on every kind of basis, precurved and
/// tilted: the two solvers find the same equilibrium.
#[test]
fn structured_matches_dense_with_every_load() {
    let terms = Terms {
        damping: false,
        drag: false,
        ..Terms::ALL
    };
    assert_agree("8 mixed pieces", &model(&Shape::new(8, bases()), terms));
    let mut tapered = Shape::new(5, vec![Basis::all()]);
    tapered.tapered = true;
    assert_agree("tapered", &model(&tapered, terms));
}

/// A robot of joints with springs, bodies and rods on the tree path.
#[test]
fn structured_matches_dense_on_a_robot() {
    assert_agree("robot", &robot(true, false, false, true));
}

/// A joint without a spring leaves `K` singular: the forced structured
/// solver says so, `Auto` takes the dense path and converges.
#[test]
fn springless_joint_needs_the_dense_solver() {
    let model = robot(true, false, true, true);
    assert!(!StaticsSolver::Auto.is_structured(&model));
    assert!(matches!(
        solve(&model, StaticsSolver::Structured),
        Err(DynamicsError::NotPositiveDefinite { .. })
    ));
    solve(&model, StaticsSolver::Auto).unwrap();
}

/// A pure follower tip moment `M = κEI` curls a straight cantilever into
/// the exact circle of curvature `κ`, which constant-strain pieces contain
/// exactly (docs/theory.md §8): at `κL = 2π` the tip returns to the clamp.
/// From 8 pieces (forced structured) to 400 (`Auto`, which is structured
/// there), with load continuation.
#[test]
fn structured_statics_closes_the_exact_circle() {
    let (length, radius): (f64, f64) = (0.5, 0.01);
    let material = Material::with_poisson(1000.0, 1e7, 0.5, 0.0).unwrap();
    let ei = material.young() * PI * radius.powi(4) / 4.0;
    for (pieces, solver) in [(8, StaticsSolver::Structured), (400, StaticsSolver::Auto)] {
        let geometry =
            RodGeometry::uniform(length, pieces, Basis::all(), straight(), Pose::identity())
                .unwrap();
        let body = RodProperties::new(Section::Circle { radius }, material, length).unwrap();
        let mut rod = Rod::new("curl", geometry, body);
        let kappa = 2.0 * PI / length;
        rod.point_loads = vec![PointLoad {
            s: length,
            force: Vec3::zeros(),
            moment: Vec3::z() * kappa * ei,
            frame: LoadFrame::Body,
        }];
        let model = Model::new(vec![rod], None, 2).unwrap();
        assert!(solver.is_structured(&model));
        let q = solve(&model, solver).unwrap();
        let geometry = &model.rods()[0].spec.geometry;
        let mut kin = RodKinematics::new(geometry);
        kin.update(geometry, q.as_slice(), None, None).unwrap();
        let tip = kin.tip_pose();
        // Relative residual 1e-12 → κ to ~1e-12 relative → tip within
        // ~1e-12·L of the clamp and the frame within ~1e-12·2π of I;
        // 1e-10 allows the sum over 400 pieces' rounding.
        assert!(
            tip.translation.norm() < 1e-10,
            "N = {pieces}: tip {:e} m from the clamp",
            tip.translation.norm()
        );
        assert!(
            (tip.rotation - nalgebra::Matrix3::identity()).norm() < 1e-10,
            "N = {pieces}: tip frame not back to the identity"
        );
    }
}
