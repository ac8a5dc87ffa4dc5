//! Prescribed joints (docs/theory.md §11, D59) against independent answers:
//! a base accelerated by `a` without gravity moves the rod as gravity `−a`
//! on a fixed base; the force a prescribed joint reports, applied to the
//! same joint left free, reproduces the prescribed motion (forward
//! dynamics of a second model); the work of that force is the change of
//! the total energy; inverse and forward dynamics agree on it.

mod common;

use common::{soft_rod as rod, wavy as state};

use nalgebra::DVector;
use softrod_dynamics::{
    Attachment, BodySpec, Curve, Data, Joint, Model, Prescribed, StaticsOptions, bias_force,
    energies, forward_dynamics, inverse_dynamics, mass_matrix, statics,
};
use softrod_mechanics::Material;

const G: f64 = 9.81;

/// `x(t) = ½at²` sampled at three points: the not-a-knot spline is that
/// parabola exactly.
fn constant_acceleration(a: f64) -> Prescribed {
    let times = [0.0, 1.0, 2.0];
    let values: Vec<Vec<f64>> = times.iter().map(|t| vec![0.5 * a * t * t]).collect();
    Prescribed::samples(&times, &values).unwrap()
}

#[test]
fn base_acceleration_equals_reversed_gravity() {
    // Horizontal cantilever along x; the base accelerates up at a = g.
    let a = G;
    let driven = Model::builder()
        .rod_on(
            rod("arm", 0.4, 4),
            Attachment::world_joint(
                Joint::prismatic([0.0, 0.0, 1.0]).with_prescribed(constant_acceleration(a)),
            ),
        )
        .body(
            BodySpec::principal("tip", 0.02, [1e-6, 2e-6, 3e-6]),
            Attachment::to("arm", Joint::fixed()),
        )
        .build()
        .unwrap();
    let fixed = Model::builder()
        .rod(rod("arm", 0.4, 4))
        .body(
            BodySpec::principal("tip", 0.02, [1e-6, 2e-6, 3e-6]),
            Attachment::to("arm", Joint::fixed()),
        )
        .gravity([0.0, 0.0, -a])
        .build()
        .unwrap();
    assert_eq!(
        driven.n_dof(),
        fixed.n_dof(),
        "a prescribed joint adds no DoF"
    );
    assert_eq!(driven.n_prescribed(), 1);
    let n = driven.n_dof();
    let (mut dd, mut df) = (Data::new(&driven), Data::new(&fixed));
    for (k, t) in [0.0, 0.3, 1.7].into_iter().enumerate() {
        let q = state(n, 0.8, k as f64);
        let v = state(n, 2.0, 0.5 + k as f64);
        let qa = forward_dynamics(&driven, &mut dd, t, &q, &v, None)
            .unwrap()
            .clone();
        let qb = forward_dynamics(&fixed, &mut df, t, &q, &v, None)
            .unwrap()
            .clone();
        let err = (&qa - &qb).amax() / qb.amax();
        assert!(err < 1e-12, "t = {t}: relative difference {err}");
        // The base's velocity a·t does not matter (Galilean invariance),
        // nor its position.
        assert!((dd.prescribed_qd[0] - a * t).abs() < 1e-12);
    }
}

/// A rod on a joint with the given prescribed motion, and the same model
/// with the joint free.
fn pair(joint: Joint, motion: Prescribed) -> (Model, Model) {
    pair_with(joint, motion, 0.0)
}

fn pair_with(joint: Joint, motion: Prescribed, viscosity: f64) -> (Model, Model) {
    let arm = || {
        rod("arm", 0.3, 3).material(
            Material::builder()
                .density(1000.0)
                .young(1e6)
                .poisson(0.5)
                .viscosity(viscosity)
                .build()
                .unwrap(),
        )
    };
    let build = |j: Joint| {
        Model::builder()
            .rod_on(arm(), Attachment::world_joint(j))
            .body(
                BodySpec::principal("tip", 0.01, [1e-6, 1e-6, 1e-6]),
                Attachment::to("arm", Joint::fixed()),
            )
            .gravity([0.0, 0.0, -G])
            .build()
            .unwrap()
    };
    (build(joint.clone().with_prescribed(motion)), build(joint))
}

#[test]
fn reported_force_drives_the_free_joint_along_the_prescribed_motion() {
    let sine = |k: usize| {
        Prescribed::new(
            (0..k)
                .map(|c| Curve::Sine {
                    amplitude: 0.3 + 0.1 * c as f64,
                    frequency: 1.5,
                    phase: 0.2 * c as f64,
                    offset: 0.05,
                })
                .collect(),
        )
    };
    for (joint, k) in [
        (Joint::revolute([0.0, 1.0, 0.3]), 1),
        (Joint::prismatic([1.0, 0.0, 0.5]), 1),
        (Joint::universal([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]), 2),
        (Joint::spherical(), 3),
        (Joint::free(), 6),
    ] {
        let name = joint.kind.name();
        let (driven, free) = pair(joint, sine(k));
        let n = driven.n_dof();
        assert_eq!(free.n_dof(), n + k);
        let (mut dd, mut df) = (Data::new(&driven), Data::new(&free));
        let t = 0.37;
        let q = state(n, 0.5, 1.0);
        let v = state(n, 1.5, 2.0);
        let qdd = forward_dynamics(&driven, &mut dd, t, &q, &v, None)
            .unwrap()
            .clone();
        let force = dd.prescribed_force.clone();
        // The free model at the same state: joint coordinates first.
        let mut qf = dd.prescribed_q.as_slice().to_vec();
        qf.extend_from_slice(&q);
        let mut vf = dd.prescribed_qd.as_slice().to_vec();
        vf.extend_from_slice(&v);
        let mut tau = force.as_slice().to_vec();
        tau.extend(std::iter::repeat_n(0.0, n));
        let qddf = forward_dynamics(&free, &mut df, t, &qf, &vf, Some(&tau))
            .unwrap()
            .clone();
        let scale = qddf.amax();
        for c in 0..k {
            let e = (qddf[c] - dd.prescribed_qdd[c]).abs() / scale;
            assert!(e < 1e-10, "{name}: joint acceleration {c}: {e}");
        }
        let e = (qddf.rows(k, n) - &qdd).amax() / scale;
        assert!(e < 1e-10, "{name}: strain accelerations differ by {e}");
        // Inverse dynamics at (q, q̇, q̈) needs no strain force and reports
        // the same joint force.
        let tau_id = inverse_dynamics(&driven, &mut dd, t, &q, &v, qdd.as_slice())
            .unwrap()
            .clone();
        assert!(
            tau_id.amax() < 1e-9 * force.amax().max(1.0),
            "{name}: {tau_id}"
        );
        let e = (&dd.prescribed_force - &force).amax() / force.amax();
        assert!(e < 1e-10, "{name}: inverse vs forward joint force {e}");
        // The O(N) recursion against M⁻¹(τ − b) (dense mass matrix and the
        // bias `b`, both at the drive's state at t), from a fresh Data so
        // nothing of the evaluations above is reused.
        let mut fresh = Data::new(&driven);
        let b = bias_force(&driven, &mut fresh, t, &q, &v).unwrap().clone();
        let m = mass_matrix(&driven, &mut fresh, &q).unwrap().clone();
        let dense = m.cholesky().unwrap().solve(&(-b));
        let e = (&dense - &qdd).amax() / qdd.amax();
        assert!(e < 1e-10, "{name}: O(N) vs M⁻¹(τ − b): {e}");
    }
}

#[test]
fn work_of_the_prescribed_force_is_the_energy_change() {
    for viscosity in [0.0, 300.0] {
        work_balance(viscosity);
    }
}

fn work_balance(viscosity: f64) {
    // A pendulum-like rod on a revolute joint swung by θ(t) = 0.4 sin(2πt).
    let (driven, _) = pair_with(
        Joint::revolute([0.0, 1.0, 0.0]),
        Prescribed::new(vec![Curve::Sine {
            amplitude: 0.4,
            frequency: 1.0,
            phase: 0.0,
            offset: 0.0,
        }]),
        viscosity,
    );
    let n = driven.n_dof();
    let mut data = Data::new(&driven);
    let dmat = softrod_dynamics::damping_matrix(&driven);
    let mut q = DVector::zeros(n);
    let mut v = DVector::zeros(n);
    let dt = 2e-4;
    let steps = 2500;
    let power = |data: &mut Data, t: f64, q: &DVector<f64>, v: &DVector<f64>| {
        forward_dynamics(&driven, data, t, q.as_slice(), v.as_slice(), None).unwrap();
        data.prescribed_force[0] * data.prescribed_qd[0] - v.dot(&(&dmat * v))
    };
    driven.set_time(&mut data, 0.0);
    let e0 = energies(&driven, &mut data, q.as_slice(), v.as_slice())
        .unwrap()
        .total();
    let mut work = 0.0;
    let mut p_prev = power(&mut data, 0.0, &q, &v);
    let mut t = 0.0;
    let mut scale: f64 = 0.0;
    for _ in 0..steps {
        common::rk4_step(&driven, &mut data, t, &mut q, &mut v, dt);
        t += dt;
        let p = power(&mut data, t, &q, &v);
        work += 0.5 * dt * (p + p_prev);
        p_prev = p;
        scale = scale.max(work.abs());
    }
    driven.set_time(&mut data, t);
    let e1 = energies(&driven, &mut data, q.as_slice(), v.as_slice())
        .unwrap()
        .total();
    let err = ((e1 - e0) - work).abs();
    // Trapezoidal work: error O(dt²) relative to the work in play.
    assert!(scale > 1e-3, "the drive does work: {scale}");
    assert!(
        err < 1e-5 * scale,
        "ΔE = {}, W = {work}, scale {scale}",
        e1 - e0
    );
}

#[test]
fn pointwise_kinetic_energy_equals_the_mass_matrix_form() {
    // A tree without prescribed joints: ½q̇ᵀMq̇ from the composite mass
    // matrix against the point-by-point sum of the energies.
    let model = Model::builder()
        .rod_on(
            rod("a", 0.3, 3),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.2])),
        )
        .body(
            BodySpec::principal("p", 0.03, [1e-6, 2e-6, 3e-6]),
            Attachment::to("a", Joint::spherical()),
        )
        .rod_on(
            rod("b", 0.2, 2),
            Attachment::to("a", Joint::prismatic([1.0, 0.0, 0.0])).at(0.1),
        )
        .build()
        .unwrap();
    let n = model.n_dof();
    let mut data = Data::new(&model);
    let q = state(n, 0.4, 3.0);
    let v = DVector::from_vec(state(n, 1.3, 4.0));
    let t = energies(&model, &mut data, &q, v.as_slice())
        .unwrap()
        .kinetic;
    let m = mass_matrix(&model, &mut data, &q).unwrap();
    let expected = 0.5 * v.dot(&(m * &v));
    assert!((t - expected).abs() < 1e-12 * expected, "{t} vs {expected}");
}

#[test]
fn statics_holds_the_prescribed_joint_at_rest() {
    // A cantilever on a base that rotates: statics at t = 0.25 s holds the
    // joint at θ(0.25) = 0.5 rad with no motion: the same equilibrium as
    // a base pose turned by 0.5 rad, i.e. a fixed joint there.
    let motion = Prescribed::samples(&[0.0, 0.5], &[vec![0.0], vec![1.0]]).unwrap();
    let driven = Model::builder()
        .rod_on(
            rod("arm", 0.3, 3),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0]).with_prescribed(motion)),
        )
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap();
    let turned = Model::builder()
        .rod(rod("arm", 0.3, 3).base(softrod_lie::Pose::new(
            *nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::y_axis(), 0.5).matrix(),
            softrod_lie::Vec3::zeros(),
        )))
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap();
    let n = driven.n_dof();
    let opts = StaticsOptions {
        time: 0.25,
        ..StaticsOptions::default()
    };
    let a = statics(&driven, &mut Data::new(&driven), &vec![0.0; n], &opts).unwrap();
    let b = statics(&turned, &mut Data::new(&turned), &vec![0.0; n], &opts).unwrap();
    let e = (&a.q - &b.q).amax() / b.q.amax();
    assert!(e < 1e-9, "{e}");
}

#[test]
fn invalid_prescribed_joints_are_errors() {
    let with = |j: Joint| {
        Model::builder()
            .rod_on(rod("arm", 0.3, 3), Attachment::world_joint(j))
            .build()
    };
    let m = || constant_acceleration(1.0);
    let e = with(
        Joint::prismatic([0.0, 0.0, 1.0])
            .with_stiffness(&[1.0])
            .with_prescribed(m()),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("stiffness on a prescribed joint"), "{e}");
    let e = with(Joint::spherical().with_prescribed(m()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("1 curves for a joint of 3 coordinates"), "{e}");
    let e = with(Joint::fixed().with_prescribed(m()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no coordinate to prescribe"), "{e}");
}

/// A rod on a base driven sideways, its tip held by a ball to the world:
/// a closed chain with a drive (`driven = false`: the joint left free).
fn pinned(driven: bool) -> Model {
    use softrod_dynamics::{Closure, ClosureFrame, ClosureKind};
    use softrod_lie::Pose;
    let j = Joint::prismatic([0.0, 1.0, 0.0]);
    let j = if driven {
        // x = A(1 − cos 2πft): at rest at t = 0, so q = q̇ = 0 is an
        // assembled state (φ = 0 and φ̇ = 0).
        j.with_prescribed(Prescribed::new(vec![Curve::Sine {
            amplitude: 0.01,
            frequency: 3.0,
            phase: -std::f64::consts::FRAC_PI_2,
            offset: 0.01,
        }]))
    } else {
        j
    };
    let tip = Pose::new(
        nalgebra::Matrix3::identity(),
        softrod_lie::Vec3::new(0.3, 0.0, 0.0),
    );
    Model::builder()
        .rod_on(rod("arm", 0.3, 3), Attachment::world_joint(j))
        .closure(Closure::new(
            "pin",
            ClosureKind::Ball,
            ClosureFrame::on("arm", None, Pose::identity()),
            ClosureFrame::world(tip),
        ))
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap()
}

#[test]
fn a_closed_chain_with_a_drive_reports_the_force_that_drives_it() {
    // The driven closed model against the same model with the joint free
    // and the reported force applied: the same multipliers, so the joint
    // follows its curve and the strains accelerate alike.
    let (driven, free) = (pinned(true), pinned(false));
    let n = driven.n_dof();
    let (mut dd, mut df) = (Data::new(&driven), Data::new(&free));
    for t in [0.05, 0.2] {
        let q = state(n, 0.3, t);
        let v = state(n, 1.0, 2.0 * t);
        let qdd = forward_dynamics(&driven, &mut dd, t, &q, &v, None)
            .unwrap()
            .clone();
        let mut qf = vec![dd.prescribed_q[0]];
        qf.extend_from_slice(&q);
        let mut vf = vec![dd.prescribed_qd[0]];
        vf.extend_from_slice(&v);
        let mut tau = vec![dd.prescribed_force[0]];
        tau.extend(std::iter::repeat_n(0.0, n));
        let qddf = forward_dynamics(&free, &mut df, t, &qf, &vf, Some(&tau))
            .unwrap()
            .clone();
        let scale = qddf.amax();
        let e = (qddf[0] - dd.prescribed_qdd[0]).abs() / scale;
        assert!(e < 1e-9, "t = {t}: joint acceleration off by {e}");
        let e = (qddf.rows(1, n) - &qdd).amax() / scale;
        assert!(e < 1e-9, "t = {t}: strain accelerations off by {e}");
    }
}

#[test]
fn a_closed_chain_with_a_drive_gains_the_drive_s_work() {
    // The ball to the world does no work (at an assembled state): the
    // energy change along the motion is the drive's work, ∫ F_p q̇_p dt.
    let model = pinned(true);
    let n = model.n_dof();
    let mut data = Data::new(&model);
    let (mut q, mut v) = (DVector::zeros(n), DVector::zeros(n));
    let (dt, steps) = (2e-4, 1500);
    let acc = |data: &mut Data, t: f64, q: &DVector<f64>, v: &DVector<f64>| {
        let a = forward_dynamics(&model, data, t, q.as_slice(), v.as_slice(), None)
            .unwrap()
            .clone();
        (a, data.prescribed_force[0] * data.prescribed_qd[0])
    };
    let e0 = energies(&model, &mut data, q.as_slice(), v.as_slice())
        .unwrap()
        .total();
    let (mut work, mut scale, mut t) = (0.0, 0.0_f64, 0.0);
    let mut p_prev = acc(&mut data, 0.0, &q, &v).1;
    for _ in 0..steps {
        common::rk4_step(&model, &mut data, t, &mut q, &mut v, dt);
        t += dt;
        let p = acc(&mut data, t, &q, &v).1;
        work += 0.5 * dt * (p + p_prev);
        p_prev = p;
        scale = scale.max(work.abs());
    }
    model.set_time(&mut data, t);
    let e1 = energies(&model, &mut data, q.as_slice(), v.as_slice())
        .unwrap()
        .total();
    assert!(scale > 1e-5, "the drive does work: {scale}");
    let err = ((e1 - e0) - work).abs();
    assert!(
        err < 1e-4 * scale,
        "ΔE = {}, W = {work}, scale {scale}",
        e1 - e0
    );
}

/// The shifted solve with a prescribed revolute joint holds the model where
/// the drive stands at the time given to `factor_at` (the mass matrix
/// depends on it): against the dense `M + aK + bD` at that time.
#[test]
fn shifted_solve_follows_the_prescribed_joint() {
    use softrod_dynamics::{ShiftedSolver, damping_matrix, stiffness_matrix};
    // The drive sits between two rods, so where it stands changes M (a
    // drive at the root would only turn the whole model rigidly).
    let motion = Prescribed::samples(&[0.0, 1.0, 2.0], &[vec![0.0], vec![1.2], vec![0.4]]).unwrap();
    let model = Model::builder()
        .rod(rod("upper", 0.2, 2))
        .rod_on(
            rod("lower", 0.2, 2),
            Attachment::to(
                "upper",
                Joint::revolute([0.0, 1.0, 0.0]).with_prescribed(motion),
            ),
        )
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap();
    let q = state(model.n_dof(), 0.3, 0.4);
    let r = DVector::from_vec(state(model.n_dof(), 1.0, 1.1));
    let mut solver = ShiftedSolver::new(&model);
    let mut data = Data::new(&model);
    for t in [0.0, 0.7, 1.5] {
        model.set_time(&mut data, t);
        let s = mass_matrix(&model, &mut data, &q).unwrap().clone()
            + stiffness_matrix(&model) * 1e-4
            + damping_matrix(&model) * 1e-2;
        solver.factor_at(&model, t, &q, 1e-4, 1e-2).unwrap();
        let mut x = r.as_slice().to_vec();
        solver.solve(&model, &mut x).unwrap();
        let reference = s.cholesky().unwrap().solve(&r);
        let e = (DVector::from_vec(x) - &reference).amax() / reference.amax();
        assert!(e < 1e-11, "t = {t}: {e:e}");
    }
}

#[test]
fn breakpoints_are_the_drives_ends_and_the_tension_knots() {
    use softrod_mechanics::{Cable, Routing, Tension};
    let motion = Prescribed::samples(&[0.5, 1.0, 2.5], &[vec![0.0], vec![0.3], vec![0.4]]).unwrap();
    let cable = Cable::new(
        Routing::Offset { y: 0.0, z: 0.005 },
        Tension::Table {
            times: vec![0.0, 1.0, 3.0],
            values: vec![0.0, 1.0, 1.0],
        },
    );
    let model = Model::builder()
        .rod_on(
            rod("arm", 0.3, 3).cable(cable),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0]).with_prescribed(motion)),
        )
        .build()
        .unwrap();
    // The spline's ends 0.5 and 2.5 (not its inner sample 1.0, where it is
    // C²) and the table's times 0, 1, 3 (its kinks), sorted, 1.0 once.
    assert_eq!(model.breakpoints(), vec![0.0, 0.5, 1.0, 2.5, 3.0]);
    // A model without drives has none.
    assert!(
        Model::builder()
            .rod(rod("a", 0.3, 2))
            .build()
            .unwrap()
            .breakpoints()
            .is_empty()
    );
}
