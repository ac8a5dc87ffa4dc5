//! `linearize` of closed models (docs/theory-derivatives.md CD9): the
//! state-space matrices of the constrained, Baumgarte-stabilized dynamics
//! in the model's coordinates, against central differences of the
//! production constrained `q̈` (`A` and the cables' `B`), against the
//! small-swing frequency of a pendulum made by a ball closure (a hand
//! value), and against the constrained `modes` of a rod pinned at both
//! ends (a second algorithm: `K`, `M` on the null space of `J`).

mod common;

use common::{soft_rod as rod, wavy};

use nalgebra::DMatrix;
use softrod_dynamics::{
    Attachment, BodySpec, Closure, ClosureFrame, ClosureKind, Data, FdDerivatives, Joint, Model,
    StaticsOptions, closure_statics, forward_dynamics, linearize, modes, statics,
};
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::{Cable, Drag, Routing, Tension};

const G: f64 = 9.81;

fn at(p: [f64; 3]) -> Pose {
    Pose::new(Mat3::identity(), Vec3::from(p))
}

/// Two flexible links on revolute joints closed by a ball (a four-bar),
/// link `a` with two cables and drag.
fn four_bar() -> Model {
    Model::builder()
        .rod_on(
            rod("a", 0.3, 3)
                .drag(Drag {
                    translational: 0.3,
                    rotational: 1e-4,
                })
                .cable(Cable::new(
                    Routing::Offset { y: 0.0, z: 0.008 },
                    Tension::Constant(0.7),
                ))
                .cable(Cable::new(
                    Routing::Offset { y: 0.006, z: 0.0 },
                    Tension::Constant(0.3),
                )),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.1])),
        )
        .rod_on(
            rod("b", 0.25, 2).base(at([0.2, 0.0, 0.0])),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .gravity([0.0, 0.0, -G])
        .closure(Closure::new(
            "coupler",
            ClosureKind::Ball,
            ClosureFrame::on("a", None, at([0.0, 0.0, 0.02])),
            ClosureFrame::on("b", Some(0.25), Pose::identity()),
        ))
        .build()
        .unwrap()
}

#[test]
fn closed_linearization_matches_central_differences_of_the_constrained_dynamics() {
    let model = four_bar();
    let (n, nu) = (model.n_dof(), model.n_cables());
    assert_eq!(nu, 2);
    // Off the manifold and moving: every term counts.
    let (q, qd) = (wavy(n, 0.3, 0.2), wavy(n, 0.8, 1.2));
    let t = 0.1;
    let mut data = Data::new(&model);
    let mut work = FdDerivatives::new(&model);
    let lin = linearize(&model, &mut data, &mut work, t, &q, &qd, None).unwrap();
    assert_eq!(
        (lin.a.nrows(), lin.a.ncols(), lin.b.ncols()),
        (2 * n, 2 * n, nu)
    );
    assert_eq!(lin.u.as_slice(), &[0.7, 0.3]);
    let qdd = forward_dynamics(&model, &mut data, t, &q, &qd, None)
        .unwrap()
        .clone();
    assert!((lin.xdot.rows(n, n) - &qdd).amax() <= 1e-12 * qdd.amax());
    assert_eq!(lin.xdot.rows(0, n).as_slice(), qd.as_slice());
    // The kinematic rows: [0 I].
    let top = lin.a.view((0, 0), (n, 2 * n));
    let mut eye = DMatrix::zeros(n, 2 * n);
    eye.view_mut((0, n), (n, n)).fill_with_identity();
    assert_eq!(top, eye);
    // ∂q̈/∂x by central differences of the constrained forward dynamics
    // (q̈ is quadratic in q̇: exact at the long step).
    let mut fd_x = DMatrix::zeros(n, 2 * n);
    for j in 0..2 * n {
        let h = if j < n { 1e-6 } else { 0.05 };
        let mut cols = [qdd.clone(), qdd.clone()];
        for (c, s) in cols.iter_mut().zip([1.0, -1.0]) {
            let (mut qx, mut qdx) = (q.clone(), qd.clone());
            if j < n {
                qx[j] += s * h;
            } else {
                qdx[j - n] += s * h;
            }
            c.copy_from(forward_dynamics(&model, &mut data, t, &qx, &qdx, None).unwrap());
        }
        fd_x.set_column(j, &((&cols[0] - &cols[1]) / (2.0 * h)));
    }
    for (what, got, want) in [
        (
            "dqdd/dq",
            lin.a.view((n, 0), (n, n)),
            fd_x.view((0, 0), (n, n)),
        ),
        (
            "dqdd/dqdot",
            lin.a.view((n, n), (n, n)),
            fd_x.view((0, n), (n, n)),
        ),
    ] {
        let err = (got - want).amax();
        let scale = want.amax();
        eprintln!("{what}: error {err:.2e} of {scale:.2e}");
        assert!(err <= 2e-6 * scale, "{what}: {err:e} of {scale:e}");
    }
    // ∂q̈/∂u: q̈ is affine in the tensions, a central difference is exact
    // to rounding at any step.
    let mut fd_u = DMatrix::zeros(n, nu);
    for c in 0..nu {
        let mut cols = [qdd.clone(), qdd.clone()];
        for (col, s) in cols.iter_mut().zip([1.0, -1.0]) {
            let mut u = lin.u.clone();
            u[c] += s * 0.1;
            data.set_cable_tensions(&model, Some(u.as_slice())).unwrap();
            col.copy_from(forward_dynamics(&model, &mut data, t, &q, &qd, None).unwrap());
        }
        fd_u.set_column(c, &((&cols[0] - &cols[1]) / 0.2));
    }
    assert_eq!(lin.b.view((0, 0), (n, nu)).amax(), 0.0);
    let err = (lin.b.view((n, 0), (n, nu)) - &fd_u).amax();
    eprintln!("dqdd/du: error {err:.2e} of {:.2e}", fd_u.amax());
    assert!(fd_u.amax() > 0.0);
    assert!(err <= 1e-8 * fd_u.amax(), "dqdd/du: {err:e}");
}

/// The eigenvalues of `A`, sorted by imaginary part then real part.
fn eigenvalues(a: &DMatrix<f64>) -> Vec<(f64, f64)> {
    let mut ev: Vec<(f64, f64)> = a
        .clone()
        .complex_eigenvalues()
        .iter()
        .map(|z| (z.re, z.im))
        .collect();
    ev.sort_by(|x, y| x.1.total_cmp(&y.1).then(x.0.total_cmp(&y.0)));
    ev
}

/// A rigid bob on a free joint hung from a world point by a ball closure
/// a distance `l` above its centre: a spherical pendulum. About the
/// hanging rest, the linearization's eigenvalues are the swings'
/// `±i ω`, `ω² = m g l / (I + m l²)` (twice: about x and y), the spin
/// about the vertical `0` (twice), and the Baumgarte stabilization's
/// `−α` (twice per row, three rows). A clamped stub carries the model's
/// rod, its modes far above.
#[test]
fn a_ball_closure_pendulum_swings_at_the_hand_frequency() {
    let (m, l, inertia) = (0.3, 0.2, 2e-3);
    let mut bob = BodySpec::principal("bob", m, [inertia, inertia, 5e-4]);
    bob.base = at([0.0, 0.0, -l]);
    // A model needs a rod: a short clamped stub far away, whose own
    // modes (above 1000 rad/s) do not mix with the pendulum's.
    let model = Model::builder()
        .rod(rod("stub", 0.02, 1).base(at([1.0, 0.0, 0.0])))
        .body(bob, Attachment::world_joint(Joint::free()))
        .gravity([0.0, 0.0, -G])
        .closure(Closure::new(
            "pivot",
            ClosureKind::Ball,
            ClosureFrame::on("bob", None, at([0.0, 0.0, l])),
            ClosureFrame::world(Pose::identity()),
        ))
        .build()
        .unwrap();
    let n = model.n_dof();
    let zero = vec![0.0; n];
    let mut data = Data::new(&model);
    // The stub sags: its equilibrium from the statics of the stub alone
    // (its coordinates come first); the bob's is the rest.
    let stub = Model::builder()
        .rod(rod("stub", 0.02, 1).base(at([1.0, 0.0, 0.0])))
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap();
    let mut q = vec![0.0; n];
    let ns = stub.n_dof();
    let rest = vec![0.0; ns];
    let res = statics(
        &stub,
        &mut Data::new(&stub),
        &rest,
        &StaticsOptions::default(),
    )
    .unwrap();
    q[..ns].copy_from_slice(res.q.as_slice());
    let q = q.as_slice();
    let mut work = FdDerivatives::new(&model);
    let lin = linearize(&model, &mut data, &mut work, 0.0, q, &zero, None).unwrap();
    assert!(
        lin.xdot.amax() < 1e-6,
        "an equilibrium: {}",
        lin.xdot.amax()
    );
    let omega = (m * G * l / (inertia + m * l * l)).sqrt();
    let alpha = model.baumgarte_rate();
    let all = eigenvalues(&lin.a);
    let ev: Vec<(f64, f64)> = all
        .iter()
        .copied()
        .filter(|z| z.0.hypot(z.1) < 500.0)
        .collect();
    eprintln!("ω = {omega:.9}, α = {alpha}: {ev:?}");
    // The stabilization's −α, three rows, a double (defective: the
    // computed pair splits by about the square root of the rows' error
    // relative to α², here up to 2e-4 α).
    let stab = all
        .iter()
        .filter(|z| (z.0 + alpha).hypot(z.1) < 1e-3 * alpha)
        .count();
    assert_eq!(stab, 6, "{all:?}");
    let mut want: Vec<(f64, f64)> = vec![(0.0, -omega), (0.0, -omega), (0.0, omega), (0.0, omega)];
    want.extend([(0.0, 0.0); 2]);
    want.sort_by(|x, y| x.1.total_cmp(&y.1).then(x.0.total_cmp(&y.0)));
    assert_eq!(ev.len(), want.len(), "{ev:?}");
    // The rows' central differences (1e-10 relative) seen through the
    // α² ≈ 2e8 of the stabilization: ~1e-7 on the swings.
    for (got, w) in ev.iter().zip(&want) {
        let tol = 1e-7 * omega;
        assert!(
            (got.0 - w.0).abs() < tol && (got.1 - w.1).abs() < tol,
            "{got:?} vs {w:?}"
        );
    }
}

/// A rod pinned at both ends (spherical joint, ball closure at the tip,
/// the pins closer than the rod is long) sagging under gravity: about the
/// static equilibrium, the undamped linearization's eigenvalues off the
/// stabilization's `−α` are `±i ω` with `ω` the constrained modes'.
#[test]
fn a_pinned_pinned_rod_linearizes_to_its_constrained_modes() {
    let model = Model::builder()
        .rod_on(
            rod("rope", 0.5, 4),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity([0.0, 0.0, -G])
        .closure(Closure::new(
            "pin",
            ClosureKind::Ball,
            ClosureFrame::on("rope", None, Pose::identity()),
            ClosureFrame::world(at([0.5, 0.0, 0.0])),
        ))
        .build()
        .unwrap();
    let n = model.n_dof();
    let mut data = Data::new(&model);
    let rest = vec![0.0; n];
    let (res, _) = closure_statics(&model, &mut data, &rest, &StaticsOptions::default()).unwrap();
    let q = res.q.as_slice();
    let zero = vec![0.0; n];
    let mut work = FdDerivatives::new(&model);
    let lin = linearize(&model, &mut data, &mut work, 0.0, q, &zero, None).unwrap();
    let alpha = model.baumgarte_rate();
    let modes = modes(&model, &mut Data::new(&model), q, 0.0).unwrap();
    let mut want: Vec<f64> = modes.omega.iter().copied().collect();
    want.sort_by(f64::total_cmp);
    // The physical eigenvalues: on the imaginary axis (no damping), the
    // upper half-plane's; the stabilization's sit at −α (a defective
    // double per row, split by ~1e-4 α).
    let ev = eigenvalues(&lin.a);
    let stab = ev
        .iter()
        .filter(|z| (z.0 + alpha).hypot(z.1) < 1e-3 * alpha)
        .count();
    let mut got: Vec<f64> = ev
        .iter()
        .filter(|z| z.0.abs() < 1e-6 * z.1.abs().max(1.0) && z.1 >= 0.0)
        .map(|z| z.1)
        .collect();
    got.sort_by(f64::total_cmp);
    eprintln!("modes {want:?}\nlinearization {got:?}, {stab} at −α");
    assert_eq!(stab, 2 * 3, "three rows, a double −α each");
    // A rigid mode (the rope's twist about its chord, ω = 0) is a pair
    // at 0 in the linearization.
    let rigid = want.iter().filter(|w| **w == 0.0).count();
    let small = ev.iter().filter(|z| z.0.hypot(z.1) < 1e-3).count();
    assert_eq!(small, 2 * rigid, "{ev:?}");
    let got: Vec<f64> = got.into_iter().filter(|g| *g >= 1e-3).collect();
    let want: Vec<f64> = want.into_iter().filter(|w| *w != 0.0).collect();
    assert_eq!(got.len(), want.len(), "{got:?} vs {want:?}");
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-6 * w, "{g} vs {w}");
    }
}
