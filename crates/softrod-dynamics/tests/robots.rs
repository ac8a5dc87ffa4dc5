//! Joints, rigid bodies and trees (docs/theory.md §11) against independent
//! answers: the compound pendulum, Euler–Bernoulli with a tip payload, free
//! fall, momentum conservation, and the cross-checks of the chain path
//! (O(N) forward dynamics = `M⁻¹(τ − b)`, forward∘inverse, energy rate,
//! generalized force = `Jᵀ F` with `J` by finite differences).

mod common;

use common::{Lcg, robot, soft_material as material, soft_rod as rod};
use nalgebra::DVector;
use softrod_dynamics::{
    Attachment, BodyLoad, BodySpec, Data, DynamicsError, Joint, Model, ModelBuilder, Rod,
    StaticsOptions, energies, forward_dynamics, forward_dynamics_cholesky, frames,
    inverse_dynamics, mass_matrix, statics,
};
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::{LoadFrame, PointLoad};

const G: f64 = 9.81;

/// Complete elliptic integral of the first kind `K(k)` by the
/// arithmetic–geometric mean (exact to round-off).
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        a = an;
        b = bn;
    }
    std::f64::consts::PI / (2.0 * a)
}

/// One classical RK4 step of `(q, q̇)` with the O(N) forward dynamics.
fn rk4(model: &Model, data: &mut Data, q: &mut DVector<f64>, v: &mut DVector<f64>, dt: f64) {
    common::rk4_step(model, data, 0.0, q, v, dt);
}

/// A rigid compound pendulum: a body hanging from a revolute joint about
/// y at the world origin, centre of mass at distance `d` below the pivot;
/// plus an unrelated clamped rod (a model needs one) that does not couple.
fn pendulum(m: f64, d: f64, iyy: f64) -> Model {
    let mut body = BodySpec::principal("bob", m, [2e-3, iyy, 3e-3]);
    body.center_of_mass = Vec3::new(0.0, 0.0, -d);
    Model::builder()
        .rod(rod("post", 0.2, 1))
        .body(
            body,
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap()
}

#[test]
fn pendulum_small_angle_period() {
    let (m, d, iyy) = (0.7, 0.3, 4e-3);
    let model = pendulum(m, d, iyy);
    assert!(model.is_articulated());
    let mut data = Data::new(&model);
    let n = model.n_dof();
    let j = model.elements()[1].joint_dofs.start;
    assert_eq!(j, 6);
    let q = vec![0.0; n];
    let mm = mass_matrix(&model, &mut data, &q).unwrap().clone();
    let pivot = iyy + m * d * d;
    assert!((mm[(j, j)] - pivot).abs() < 1e-14 * pivot);
    // The pendulum does not couple with the rod.
    for i in 0..6 {
        assert_eq!(mm[(i, j)], 0.0);
    }
    // Restoring stiffness dG/dθ at θ = 0 by central differences of ID.
    let h = 1e-6;
    let mut qp = q.clone();
    qp[j] = h;
    let zero = vec![0.0; n];
    let plus = inverse_dynamics(&model, &mut data, 0.0, &qp, &zero, &zero).unwrap()[j];
    qp[j] = -h;
    let minus = inverse_dynamics(&model, &mut data, 0.0, &qp, &zero, &zero).unwrap()[j];
    let kg = (plus - minus) / (2.0 * h);
    let period = 2.0 * std::f64::consts::PI * (mm[(j, j)] / kg).sqrt();
    let exact = 2.0 * std::f64::consts::PI * (pivot / (m * G * d)).sqrt();
    // Central difference of a sine: relative error h²/6.
    assert!((period - exact).abs() < 1e-9 * exact, "{period} vs {exact}");
}

#[test]
fn pendulum_large_amplitude_half_period_and_energy() {
    let (m, d, iyy) = (0.7, 0.3, 4e-3);
    let model = pendulum(m, d, iyy);
    let mut data = Data::new(&model);
    let n = model.n_dof();
    let j = 6;
    let theta0: f64 = 2.0;
    let pivot = iyy + m * d * d;
    let omega = (m * G * d / pivot).sqrt();
    let half = 2.0 / omega * elliptic_k((theta0 / 2.0).sin());
    let mut q = DVector::zeros(n);
    q[j] = theta0;
    let mut v = DVector::zeros(n);
    let e0 = energies(&model, &mut data, q.as_slice(), v.as_slice())
        .unwrap()
        .total();
    let dt = half / 4000.0;
    let mut t = 0.0;
    let mut crossing = None;
    let mut max_drift: f64 = 0.0;
    for _ in 0..4400 {
        let prev = v[j];
        rk4(&model, &mut data, &mut q, &mut v, dt);
        t += dt;
        let e = energies(&model, &mut data, q.as_slice(), v.as_slice())
            .unwrap()
            .total();
        max_drift = max_drift.max((e - e0).abs());
        if crossing.is_none() && prev < 0.0 && v[j] >= 0.0 {
            // θ̇ changes sign: linear interpolation inside the step.
            crossing = Some(t - dt + dt * (-prev) / (v[j] - prev));
        }
    }
    let crossing = crossing.expect("the pendulum swings back");
    // RK4 at 4000 steps per half period: phase error ~1e-12, the linear
    // interpolation of θ̇ near its zero (θ̈ ≠ 0 there) ~dt²·θ⃛/θ̈ ~ 1e-8.
    assert!(
        (crossing - half).abs() < 1e-7 * half,
        "{crossing} vs {half}"
    );
    // Energy scale m g d; RK4 drift O(dt⁴).
    assert!(max_drift < 1e-9 * m * G * d, "{max_drift}");
}

/// A cantilever along x with a payload of mass `m` at its tip under gravity
/// −z, or the same rod with a dead tip load `m g` instead.
fn cantilever(pieces: usize, payload: Option<f64>, tip_load: f64) -> Model {
    let spec = Rod::builder(0.5)
        .name("beam")
        .pieces(pieces)
        .circle(0.005)
        .material(material(2e10, 1000.0));
    let spec = if tip_load != 0.0 {
        spec.point_load(PointLoad {
            s: 0.5,
            force: Vec3::new(0.0, 0.0, -tip_load),
            moment: Vec3::zeros(),
            frame: LoadFrame::World,
        })
    } else {
        spec
    };
    let mut b = Model::builder().rod(spec).gravity([0.0, 0.0, -G]);
    if let Some(m) = payload {
        b = b.body(
            BodySpec::principal("payload", m, [1e-7, 1e-7, 1e-7]),
            Attachment::to("beam", Joint::fixed()),
        );
    }
    b.build().unwrap()
}

fn tip_z(model: &Model, q: &[f64]) -> f64 {
    let rod = &model.rods()[0].spec.geometry;
    let mut kin = softrod_kinematics::RodKinematics::new(rod);
    kin.update(rod, &q[model.rods()[0].dofs()], None, None)
        .unwrap();
    kin.tip_pose().translation[2]
}

#[test]
fn tip_payload_is_a_dead_tip_load_and_euler_bernoulli() {
    let m = 0.01;
    let opts = StaticsOptions::default();
    let solve = |model: &Model| {
        let mut data = Data::new(model);
        statics(model, &mut data, &vec![0.0; model.n_dof()], &opts)
            .unwrap()
            .q
    };
    // Payload (tree path) against a dead load m g (chain path), same rod.
    let with_body = cantilever(20, Some(m), 0.0);
    let with_load = cantilever(20, None, m * G);
    let (qb, ql) = (solve(&with_body), solve(&with_load));
    let (zb, zl) = (
        tip_z(&with_body, qb.as_slice()),
        tip_z(&with_load, ql.as_slice()),
    );
    assert!((zb - zl).abs() < 1e-9 * zl.abs(), "{zb} vs {zl}");
    // Euler–Bernoulli: P L³/3EI + w L⁴/8EI (shear and the geometric
    // nonlinearity, (δ/L)² ~ 1e-5, are below the discretization error).
    let (l, r, e): (f64, f64, f64) = (0.5, 0.005, 2e10);
    let i = std::f64::consts::PI * r.powi(4) / 4.0;
    let w = 1000.0 * std::f64::consts::PI * r * r * G;
    let exact = -(m * G * l.powi(3) / (3.0 * e * i) + w * l.powi(4) / (8.0 * e * i));
    let err = |pieces| {
        let model = cantilever(pieces, Some(m), 0.0);
        let q = solve(&model);
        (tip_z(&model, q.as_slice()) - exact).abs() / exact.abs()
    };
    let (e10, e20) = (err(10), err(20));
    // Piecewise-constant curvature: O(N⁻²) with the Gauss-averaged strain.
    assert!(e20 < 2e-3, "relative error {e20} at 20 pieces");
    assert!(e10 / e20 > 3.0, "{e10} → {e20} is not second order");
}

#[test]
fn prismatic_joint_falls_at_g() {
    for axis in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0)] {
        let model = Model::builder()
            .rod_on(
                rod("slider", 0.3, 3),
                Attachment::world_joint(Joint::prismatic(axis)),
            )
            .body(
                BodySpec::principal("tip", 0.05, [1e-5, 1e-5, 1e-5]),
                Attachment::to("slider", Joint::fixed()),
            )
            .gravity([0.0, 0.0, -G])
            .build()
            .unwrap();
        let mut data = Data::new(&model);
        let n = model.n_dof();
        let qdd =
            forward_dynamics(&model, &mut data, 0.0, &vec![0.0; n], &vec![0.0; n], None).unwrap();
        // The joint transmits no force along its axis: the momentum along
        // it, ∂T/∂q̇₀ = (M q̇)₀, grows at m_total g·a; at rest (M q̈)₀ = m g·a.
        let qdd = qdd.clone();
        let mass = 1000.0 * std::f64::consts::PI * 1e-4 * 0.3 + 0.05;
        let expected = -G * axis[2] / axis.norm();
        let mm = mass_matrix(&model, &mut data, &vec![0.0; n]).unwrap();
        let rate = (mm.row(0) * &qdd)[0];
        assert!(
            (rate - mass * expected).abs() < 1e-12,
            "{rate} vs {}",
            mass * expected
        );
        if axis[0] == 0.0 {
            // Along gravity the whole falls freely: q̈₀ = −g, no strain moves.
            assert!(
                (qdd[0] - expected).abs() < 1e-12,
                "{} vs {expected}",
                qdd[0]
            );
            // Along gravity the whole falls freely: no strain accelerates.
            assert!(
                qdd.rows(1, n - 1).amax() < 1e-10,
                "{}",
                qdd.rows(1, n - 1).amax()
            );
        }
    }
}

fn free_rod(gravity: bool) -> Model {
    let mut b = Model::builder().rod_on(
        rod("float", 0.4, 3).material(material(1e5, 1200.0)),
        Attachment::world_joint(Joint::free()),
    );
    if gravity {
        b = b.gravity([0.0, 0.0, -G]);
    }
    b.build().unwrap()
}

#[test]
fn free_floating_rod_conserves_momentum_and_falls_at_g() {
    let mass = 1200.0 * std::f64::consts::PI * 1e-4 * 0.4;
    for gravity in [false, true] {
        let model = free_rod(gravity);
        let mut data = Data::new(&model);
        let n = model.n_dof();
        assert_eq!(n, 6 + 18);
        let mut rng = Lcg(7);
        let mut q = DVector::from_vec(rng.vec(n, 0.3));
        let mut v = DVector::from_vec(rng.vec(n, 0.5));
        // The linear momentum in world axes is ∂T/∂ṗ = (M q̇)[3..6].
        let momentum = |data: &mut Data, q: &DVector<f64>, v: &DVector<f64>| {
            let m = mass_matrix(&model, data, q.as_slice()).unwrap();
            (m * v).rows(3, 3).into_owned()
        };
        let p0 = momentum(&mut data, &q, &v);
        let (dt, steps) = (2e-5, 200);
        for _ in 0..steps {
            rk4(&model, &mut data, &mut q, &mut v, dt);
        }
        let p1 = momentum(&mut data, &q, &v);
        let t = dt * steps as f64;
        let expected = p0 + Vec3::new(0.0, 0.0, if gravity { -mass * G * t } else { 0.0 });
        // RK4 at dt = 2e-5 s on strain frequencies ~1e3 rad/s.
        let err = (&p1 - expected).amax();
        assert!(err < 1e-9, "gravity {gravity}: {p1:?} vs {expected:?}");
    }
    // At rest and undeformed under gravity: pure free fall.
    let model = free_rod(true);
    let mut data = Data::new(&model);
    let n = model.n_dof();
    let qdd = forward_dynamics(&model, &mut data, 0.0, &vec![0.0; n], &vec![0.0; n], None)
        .unwrap()
        .clone();
    let mut expected = DVector::zeros(n);
    expected[5] = -G;
    assert!((qdd - expected).amax() < 1e-10);
}

fn rel(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

#[test]
fn every_joint_type_forward_equals_cholesky_and_inverts() {
    for tree in [false, true] {
        let model = robot(true, true, tree, true);
        let mut data = Data::new(&model);
        let n = model.n_dof();
        let mut rng = Lcg(11);
        for _ in 0..4 {
            let q = rng.vec(n, 0.4);
            let qd = rng.vec(n, 0.8);
            let tau = rng.vec(n, 0.02);
            let on = forward_dynamics(&model, &mut data, 0.0, &q, &qd, Some(&tau))
                .unwrap()
                .clone();
            let dense = forward_dynamics_cholesky(&model, &mut data, 0.0, &q, &qd, Some(&tau))
                .unwrap()
                .clone();
            assert!(rel(&on, &dense) < 1e-9, "tree {tree}: {}", rel(&on, &dense));
            let back = inverse_dynamics(&model, &mut data, 0.0, &q, &qd, on.as_slice())
                .unwrap()
                .clone();
            let tau = DVector::from_vec(tau);
            assert!((&back - &tau).amax() < 1e-9, "{}", (&back - &tau).amax());
            let m = mass_matrix(&model, &mut data, &q).unwrap().clone();
            assert!((&m - m.transpose()).amax() < 1e-14 * m.amax());
            assert!(m.clone().cholesky().is_some());
        }
    }
}

#[test]
fn energy_is_conserved_without_damping() {
    for tree in [false, true] {
        let model = robot(true, false, tree, false);
        let mut data = Data::new(&model);
        let n = model.n_dof();
        let mut rng = Lcg(3);
        let q = DVector::from_vec(rng.vec(n, 0.4));
        let v = DVector::from_vec(rng.vec(n, 0.8));
        let a = forward_dynamics(&model, &mut data, 0.0, q.as_slice(), v.as_slice(), None)
            .unwrap()
            .clone();
        // dE/dt along the flow: central differences in time, Richardson-
        // extrapolated (error O(h⁴ω⁴) with strain frequencies ω ~ 1e3 rad/s:
        // ~1e-9 of the power exchanged at h = 2.5e-6 s; it falls 16× per
        // halving of h, so what remains is not a modelling error).
        let e = |data: &mut Data, s: f64| {
            let qs = &q + &v * s + &a * (0.5 * s * s);
            let vs = &v + &a * s;
            energies(&model, data, qs.as_slice(), vs.as_slice())
                .unwrap()
                .total()
        };
        let h = 2.5e-6;
        let r1 = (e(&mut data, h) - e(&mut data, -h)) / (2.0 * h);
        let r2 = (e(&mut data, h / 2.0) - e(&mut data, -h / 2.0)) / h;
        let rate = (4.0 * r2 - r1) / 3.0;
        // Scale: the elastic power Σ|q̇_i (Kq)_i| exchanged with the kinetic.
        let k = softrod_dynamics::stiffness_matrix(&model);
        let power: f64 = (&k * &q).component_mul(&v).abs().sum();
        assert!(
            rate.abs() < 1e-7 * power,
            "tree {tree}: dE/dt = {rate}, power {power}"
        );
    }
}

#[test]
fn body_load_is_jacobian_transpose_of_finite_differences() {
    let force = Vec3::new(0.02, -0.01, 0.03);
    let build = |load: bool| -> Model {
        let mut b = BodySpec::principal("tool", 0.02, [1e-5, 2e-5, 3e-5]);
        if load {
            b.loads.push(BodyLoad {
                force,
                moment: Vec3::zeros(),
                frame: LoadFrame::World,
            });
        }
        let mb: ModelBuilder = Model::builder()
            .rod_on(
                rod("a", 0.3, 2),
                Attachment::world_joint(Joint::spherical()),
            )
            .rod_on(
                rod("b", 0.2, 2),
                Attachment::to("a", Joint::universal([0.0, 1.0, 0.0], [1.0, 0.0, 0.0])),
            )
            .body(
                b,
                Attachment::to("b", Joint::prismatic([0.0, 0.0, 1.0])).at(0.1),
            );
        mb.build().unwrap()
    };
    let (with, without) = (build(true), build(false));
    let n = with.n_dof();
    let mut data = Data::new(&with);
    let mut d0 = Data::new(&without);
    let mut rng = Lcg(5);
    let q = rng.vec(n, 0.5);
    let zero = vec![0.0; n];
    let tau = inverse_dynamics(&with, &mut data, 0.0, &q, &zero, &zero)
        .unwrap()
        .clone();
    let tau0 = inverse_dynamics(&without, &mut d0, 0.0, &q, &zero, &zero)
        .unwrap()
        .clone();
    // The load's generalized force is Q = J_vᵀ F = ∂(F·p)/∂q, on the
    // left-hand side as −Q.
    let h = 1e-6;
    let mut qp = q.clone();
    for i in 0..n {
        let mut pos = |x: f64| {
            qp[i] = q[i] + x;
            frames(&with, &mut data, &qp).unwrap();
            data.body_poses[0].translation.dot(&force)
        };
        let dq = (pos(h) - pos(-h)) / (2.0 * h);
        qp[i] = q[i];
        let got = tau0[i] - tau[i];
        assert!((got - dq).abs() < 1e-8, "q[{i}]: {got} vs {dq}");
    }
}

#[test]
fn chain_models_stay_on_the_chain_path() {
    let model = Model::builder().rod(rod("a", 0.3, 2)).build().unwrap();
    assert!(!model.is_articulated());
    let model = Model::builder()
        .rod_on(rod("a", 0.3, 2), Attachment::world())
        .build()
        .unwrap();
    assert!(!model.is_articulated());
}

#[test]
fn bad_robots_are_errors_naming_what() {
    let err = |b: ModelBuilder| b.build().unwrap_err();
    let e = err(Model::builder().rod_on(rod("a", 0.3, 2), Attachment::to("nope", Joint::fixed())));
    assert!(matches!(e, DynamicsError::UnknownParent { ref parent, .. } if parent == "nope"));
    let e = err(Model::builder()
        .rod_on(rod("a", 0.3, 2), Attachment::to("b", Joint::fixed()))
        .rod_on(rod("b", 0.3, 2), Attachment::to("a", Joint::fixed())));
    assert!(matches!(e, DynamicsError::ParentCycle { .. }), "{e}");
    let e = err(Model::builder().rod_on(
        rod("a", 0.3, 2),
        Attachment::world_joint(Joint::revolute([0.0, 0.0, 0.0])),
    ));
    assert!(matches!(e, DynamicsError::InvalidJoint { .. }), "{e}");
    let e = err(Model::builder().rod(rod("a", 0.3, 2)).body(
        BodySpec::principal("p", 0.0, [1.0, 1.0, 1.0]),
        Attachment::to("a", Joint::fixed()),
    ));
    assert!(matches!(e, DynamicsError::InvalidBody { .. }), "{e}");
    let e = err(Model::builder().rod(rod("a", 0.3, 2)).body(
        BodySpec::new(
            "p",
            1.0,
            Mat3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        ),
        Attachment::to("a", Joint::fixed()),
    ));
    assert!(matches!(e, DynamicsError::InvalidBody { .. }), "{e}");
    let e = err(Model::builder().rod(rod("a", 0.3, 2)).body(
        BodySpec::principal("p", 1.0, [1.0, 1.0, 1.0]),
        Attachment::to("a", Joint::fixed()).at(0.31),
    ));
    assert!(matches!(e, DynamicsError::AttachOutsideRod { .. }), "{e}");
    let e = err(Model::builder().rod_on(
        rod("a", 0.3, 2),
        Attachment::world_joint(Joint::spherical().with_stiffness(&[1.0])),
    ));
    assert!(matches!(e, DynamicsError::InvalidJoint { .. }), "{e}");
}

/// A Y of three rods: a trunk clamped to the world, two branches on
/// revolute joints at its tip, turned ±45° about z, and a third rod welded
/// at the trunk's middle piece boundary.
fn y_tree() -> Model {
    let turn = |a: f64| {
        Pose::new(
            *nalgebra::Rotation3::from_axis_angle(&Vec3::z_axis(), a).matrix(),
            Vec3::zeros(),
        )
    };
    Model::builder()
        .rod(rod("trunk", 0.3, 4))
        .rod_on(
            rod("left", 0.2, 3).base(turn(0.785)),
            Attachment::to("trunk", Joint::revolute([0.0, 1.0, 0.0])),
        )
        .rod_on(
            rod("right", 0.2, 3).base(turn(-0.785)),
            Attachment::to("trunk", Joint::revolute([0.0, 1.0, 0.0])),
        )
        .rod_on(
            rod("spur", 0.1, 2).base(turn(1.5)),
            Attachment::to("trunk", Joint::fixed()).at(0.15),
        )
        .gravity([0.0, 0.0, -G])
        .build()
        .unwrap()
}

#[test]
fn y_tree_forward_equals_cholesky_and_branches_do_not_couple() {
    let model = y_tree();
    let mut data = Data::new(&model);
    let n = model.n_dof();
    assert_eq!(n, 24 + (1 + 18) * 2 + 12);
    let mut rng = Lcg(17);
    let q = rng.vec(n, 0.3);
    let qd = rng.vec(n, 0.6);
    let on = forward_dynamics(&model, &mut data, 0.0, &q, &qd, None)
        .unwrap()
        .clone();
    let dense = forward_dynamics_cholesky(&model, &mut data, 0.0, &q, &qd, None)
        .unwrap()
        .clone();
    assert!(rel(&on, &dense) < 1e-9, "{}", rel(&on, &dense));
    let back = inverse_dynamics(&model, &mut data, 0.0, &q, &qd, on.as_slice())
        .unwrap()
        .clone();
    assert!(back.amax() < 1e-8, "{}", back.amax());
    // Mass matrix: the branches couple with the trunk, not with each other.
    let m = mass_matrix(&model, &mut data, &q).unwrap().clone();
    let el = model.elements();
    let left = el[1].joint_dofs.start..model.rods()[1].dofs().end;
    let right = el[2].joint_dofs.start..model.rods()[2].dofs().end;
    let spur = model.rods()[3].dofs();
    let trunk = model.rods()[0].dofs();
    for (a, b) in [(&left, &right), (&left, &spur), (&right, &spur)] {
        for i in a.clone() {
            for j in b.clone() {
                assert_eq!(m[(i, j)], 0.0, "M[{i}, {j}]");
            }
        }
    }
    assert!(
        m.view((trunk.start, left.start), (trunk.len(), left.len()))
            .amax()
            > 0.0
    );
    // The spur hangs at s = 0.15: it couples with the trunk's first two
    // pieces only (pieces of 0.075 m, 6 strains each).
    let outboard = m.view((12, spur.start), (12, spur.len())).amax();
    assert_eq!(outboard, 0.0);
    assert!(m.view((0, spur.start), (12, spur.len())).amax() > 0.0);
}

/// The O(N) shifted solve `(M + aK + bD)⁻¹` on the tree (every joint type
/// with springs and dampers as armature, bodies, branches, children at
/// boundaries and bases) against the dense Cholesky of the same matrix.
#[test]
fn shifted_solve_on_the_tree_equals_the_dense_solve() {
    for tree in [false, true] {
        let model = robot(true, true, tree, false);
        let q = common::wavy(model.n_dof(), 0.4, 0.3);
        let (backward, forward) = common::shifted_against_dense(&model, &q, 5);
        assert!(
            backward < 1e-15 && forward < 50.0,
            "tree {tree}: {backward:e}, {forward}"
        );
    }
    let model = y_tree();
    let q = common::wavy(model.n_dof(), 0.4, 0.9);
    let (backward, forward) = common::shifted_against_dense(&model, &q, 6);
    assert!(
        backward < 1e-15 && forward < 50.0,
        "y tree: {backward:e}, {forward}"
    );
}
