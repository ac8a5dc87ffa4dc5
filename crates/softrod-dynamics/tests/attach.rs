//! Children hanging inside a parent piece (docs/theory.md §11, D62), against
//! independent answers: a payload at mid-piece weighs on the rod exactly as
//! a dead point load (the chain path's in-piece loads, a second
//! algorithm); the O(N) forward dynamics equals `M⁻¹(τ − b)` with the
//! composite mass matrix and inverts the inverse dynamics; the kinetic
//! energy summed point by point equals `½q̇ᵀMq̇`.

mod common;

use common::{soft_rod as rod, wavy as state};

use nalgebra::DVector;
use softrod_dynamics::{
    Attachment, BodySpec, Data, Joint, Model, StaticsOptions, bias_force, energies,
    forward_dynamics, inverse_dynamics, mass_matrix, statics,
};
use softrod_mechanics::{LoadFrame, PointLoad};

const G: f64 = 9.81;

#[test]
fn payload_inside_a_piece_is_a_dead_point_load() {
    // 0.4 m cantilever in 4 pieces; 30 g at s = 0.17 m (inside piece 1).
    let (m, s) = (0.03, 0.17);
    let with_body = Model::builder()
        .rod(rod("arm", 0.4, 4))
        .body(
            BodySpec::principal("payload", m, [1e-9, 1e-9, 1e-9]),
            Attachment::to("arm", Joint::fixed()).at(s),
        )
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap();
    let with_load = Model::builder()
        .rod(rod("arm", 0.4, 4).point_load(PointLoad {
            s,
            force: [0.0, 0.0, -m * G].into(),
            moment: [0.0, 0.0, 0.0].into(),
            frame: LoadFrame::World,
        }))
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap();
    assert!(with_body.is_articulated() && !with_load.is_articulated());
    let n = with_body.n_dof();
    let opts = StaticsOptions::default();
    let a = statics(&with_body, &mut Data::new(&with_body), &vec![0.0; n], &opts).unwrap();
    let b = statics(&with_load, &mut Data::new(&with_load), &vec![0.0; n], &opts).unwrap();
    let e = (&a.q - &b.q).amax() / b.q.amax();
    assert!(e < 1e-9, "{e}");
}

/// A tree with children inside pieces: a body inside the trunk's second
/// piece, a branch rod on a revolute joint inside the trunk's first piece,
/// and a body on a spherical joint inside the branch's only piece.
fn tree() -> Model {
    Model::builder()
        .rod_on(
            rod("trunk", 0.4, 3),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.3])),
        )
        .body(
            BodySpec::principal("mid", 0.02, [1e-6, 2e-6, 3e-6]),
            Attachment::to("trunk", Joint::fixed()).at(0.21),
        )
        .rod_on(
            rod("branch", 0.2, 1),
            Attachment::to("trunk", Joint::revolute([0.0, 0.0, 1.0])).at(0.05),
        )
        .body(
            BodySpec::principal("bud", 0.01, [1e-6, 1e-6, 2e-6]),
            Attachment::to("branch", Joint::spherical()).at(0.13),
        )
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap()
}

#[test]
fn forward_dynamics_equals_the_dense_solve_and_inverts() {
    let model = tree();
    let n = model.n_dof();
    let mut data = Data::new(&model);
    for seed in [0.0, 1.0, 2.5] {
        let q = state(n, 0.6, seed);
        let v = state(n, 1.5, seed + 0.3);
        let qdd = forward_dynamics(&model, &mut data, 0.0, &q, &v, None)
            .unwrap()
            .clone();
        let b = bias_force(&model, &mut data, 0.0, &q, &v).unwrap().clone();
        let m = mass_matrix(&model, &mut data, &q).unwrap().clone();
        let sym = (&m - m.transpose()).amax() / m.amax();
        assert!(sym < 1e-13, "M is not symmetric: {sym}");
        let dense = m.clone().cholesky().expect("M > 0").solve(&(-&b));
        let e = (&dense - &qdd).amax() / qdd.amax();
        assert!(e < 1e-10, "O(N) vs M⁻¹(τ − b): {e}");
        let tau = inverse_dynamics(&model, &mut data, 0.0, &q, &v, qdd.as_slice())
            .unwrap()
            .clone();
        assert!(
            tau.amax() < 1e-9 * b.amax(),
            "forward∘inverse: {}",
            tau.amax()
        );
        let vv = DVector::from_column_slice(&v);
        let kinetic = energies(&model, &mut data, &q, &v).unwrap().kinetic;
        let quad = 0.5 * vv.dot(&(&m * &vv));
        assert!((kinetic - quad).abs() < 1e-12 * quad, "{kinetic} vs {quad}");
    }
}

#[test]
fn attaching_off_the_rod_is_an_error() {
    let e = Model::builder()
        .rod(rod("arm", 0.4, 4))
        .body(
            BodySpec::principal("p", 0.01, [1e-6, 1e-6, 1e-6]),
            Attachment::to("arm", Joint::fixed()).at(0.41),
        )
        .build()
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("at = 0.41 m is not on rod 'arm' (0 to 0.4 m)"),
        "{e}"
    );
}

#[test]
fn closure_jacobian_through_an_inside_attachment_is_the_derivative() {
    // A ball closure from the bud (a body hanging inside the branch, which
    // hangs inside the trunk) to a world point: J against central
    // differences of φ, so the columns of the trunk and the branch are
    // taken where the path leaves them.
    use softrod_dynamics::{
        Closure, ClosureFrame, ClosureKind, constraint_jacobian, constraint_residual,
    };
    use softrod_lie::Pose;
    let model = tree()
        .with_closures(vec![Closure::new(
            "hold",
            ClosureKind::Ball,
            ClosureFrame::on("bud", None, Pose::identity()),
            ClosureFrame::world(Pose::identity()),
        )])
        .unwrap();
    let n = model.n_dof();
    let mut data = Data::new(&model);
    let q = state(n, 0.5, 0.7);
    let j = constraint_jacobian(&model, &mut data, &q).unwrap();
    let h = 1e-6;
    let mut qp = q.clone();
    for c in 0..n {
        qp[c] = q[c] + h;
        let plus = constraint_residual(&model, &mut data, &qp).unwrap();
        qp[c] = q[c] - h;
        let minus = constraint_residual(&model, &mut data, &qp).unwrap();
        qp[c] = q[c];
        let fd = (plus - minus) / (2.0 * h);
        let e = (&fd - j.column(c)).amax();
        assert!(e < 1e-7, "column {c}: {e}");
    }
}

/// The shifted solve through children inside pieces (D62) against the
/// dense Cholesky of `M + aK + bD`.
#[test]
fn shifted_solve_through_inside_attachments_equals_the_dense_solve() {
    let model = tree();
    let q = common::wavy(model.n_dof(), 0.5, 0.2);
    let (backward, forward) = common::shifted_against_dense(&model, &q, 8);
    assert!(
        backward < 1e-15 && forward < 50.0,
        "{backward:e}, {forward}"
    );
}
