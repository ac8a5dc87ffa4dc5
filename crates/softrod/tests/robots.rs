//! The facade on scenes with joints and bodies: world poses through the
//! parents, against closed forms.

use softrod::Simulation;

const SCENE: &str = r#"
[[rod]]
name = "arm"
length = 0.4
pieces = 2
strains = ["ky"]
joint = { type = "revolute", axis = [0, 1, 0] }
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "hand"
parent = "arm"
base = { position = [0.05, 0, 0] }
mass = 0.02
inertia = [1e-6, 1e-6, 1e-6]

[[rod]]
name = "finger"
parent = "hand"
length = 0.1
pieces = 1
strains = ["ky"]
joint = { type = "prismatic", axis = [0, 0, 1] }
section = { shape = "circle", radius = 0.005 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }
"#;

#[test]
fn poses_go_through_the_joints() {
    let (sim, _, _) = Simulation::from_toml(SCENE, "robot.toml").unwrap();
    assert_eq!(sim.n_dof(), 1 + 2 + 1 + 1);
    // Straight rods, arm turned by θ about y, finger slid by d along the
    // hand's z: closed-form positions.
    let (theta, d) = (0.3_f64, 0.02);
    let q = [theta, 0.0, 0.0, d, 0.0];
    let (c, s) = (theta.cos(), theta.sin());
    // Rotation about y by θ: x ↦ (c, 0, −s), z ↦ (s, 0, c).
    let at = |x: f64, z: f64| [x * c + z * s, 0.0, -x * s + z * c];
    let tip = sim.tip_pose("arm", &q).unwrap().translation;
    let hand = sim.body_poses(&q).unwrap()[0].translation;
    let finger = sim.tip_pose("finger", &q).unwrap().translation;
    let mid = sim.pose("finger", 0.05, &q).unwrap().translation;
    for (got, want) in [
        (tip, at(0.4, 0.0)),
        (hand, at(0.45, 0.0)),
        (finger, at(0.55, d)),
        (mid, at(0.5, d)),
    ] {
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-14, "{got:?} vs {want:?}");
        }
    }
    // Time runs: the trajectory's tips are world poses too (at t = 0).
    let mut sim = sim;
    sim.set_initial_state(&q, &[0.0; 5]).unwrap();
    let traj = sim.simulate(1e-3).unwrap();
    let p = traj.tip_position(0, 1);
    let want = at(0.55, d);
    for k in 0..3 {
        assert!((p[k] - want[k]).abs() < 1e-14, "{p:?} vs {want:?}");
    }
}

/// `jacobian` on a robot has the joints' columns and agrees with central
/// differences of `pose` in every frame: body `vee(g⁻¹∂g)`, mixed
/// `(∂R Rᵀ, ∂p)` (world axes at the section), spatial `Ad_g` of the body
/// one.
#[test]
fn jacobian_has_the_joints_columns_in_every_frame() {
    use softrod::kinematics::Frame;
    let (sim, _, _) = Simulation::from_toml(SCENE, "robot.toml").unwrap();
    let q = [0.3, 0.4, -0.2, 0.02, 0.5];
    let at = 0.06;
    let g0 = sim.pose("finger", at, &q).unwrap();
    let (body, mixed, spatial) = (
        sim.jacobian("finger", at, &q, Frame::Body).unwrap(),
        sim.jacobian("finger", at, &q, Frame::Mixed).unwrap(),
        sim.jacobian("finger", at, &q, Frame::Spatial).unwrap(),
    );
    let h = 1e-6;
    for c in 0..q.len() {
        let (mut qp, mut qm) = (q, q);
        qp[c] += h;
        qm[c] -= h;
        let (gp, gm) = (
            sim.pose("finger", at, &qp).unwrap(),
            sim.pose("finger", at, &qm).unwrap(),
        );
        let dr = (gp.rotation - gm.rotation) / (2.0 * h);
        let dp = (gp.translation - gm.translation) / (2.0 * h);
        let (wb, ww) = (g0.rotation.transpose() * dr, dr * g0.rotation.transpose());
        let vb = g0.rotation.transpose() * dp;
        let want_body = [wb[(2, 1)], wb[(0, 2)], wb[(1, 0)], vb[0], vb[1], vb[2]];
        let want_mixed = [ww[(2, 1)], ww[(0, 2)], ww[(1, 0)], dp[0], dp[1], dp[2]];
        for r in 0..6 {
            // Central differences on O(0.5 m) poses: ~1e-10.
            assert!((body[(r, c)] - want_body[r]).abs() < 1e-8, "body [{r},{c}]");
            assert!(
                (mixed[(r, c)] - want_mixed[r]).abs() < 1e-8,
                "mixed [{r},{c}]"
            );
        }
    }
    // Every coordinate moves the finger's section: the arm's joint and
    // strain, the finger's joint and strain.
    for c in 0..q.len() {
        assert!(body.column(c).amax() > 1e-3, "column {c}");
    }
    let ad = g0.ad().to_mat6();
    assert!((ad * &body - &spatial).amax() < 1e-14);
}

/// The evaluations that take no time see the prescribed joints at
/// `set_time`'s time, whatever ran before: examples/oscillating_base.toml
/// shakes the base by `0.01 sin(2π·2t)` m along the world x (the joint's z
/// turned by the base rotation).
#[test]
fn evaluations_without_a_time_use_set_time_only() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/oscillating_base.toml"
    );
    let (mut sim, _, _) = Simulation::from_scene_file(path).unwrap();
    let n = sim.n_dof();
    let (q, qd) = (vec![0.0; n], vec![0.0; n]);
    let tip = |sim: &Simulation| sim.tip_pose("tentacle", &q).unwrap().translation;
    let base_x = |t: f64| 0.01 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
    let at_zero = tip(&sim);
    let m0 = sim.mass_matrix(&q).unwrap();
    let e0 = sim.energies(&q, &qd).unwrap();
    // Calls with their own time, and a run, leave the clock alone.
    sim.forward_dynamics(0.125, &q, &qd, None).unwrap();
    sim.inverse_dynamics(0.3, &q, &qd, &qd).unwrap();
    sim.simulate(0.02).unwrap();
    assert_eq!(tip(&sim), at_zero);
    assert_eq!(sim.mass_matrix(&q).unwrap(), m0);
    assert_eq!(sim.energies(&q, &qd).unwrap(), e0);
    // set_time moves it: the tip follows the base.
    sim.set_time(0.125);
    assert_eq!(sim.time(), 0.125);
    let moved = tip(&sim);
    assert!(
        ((moved - at_zero)[0] - base_x(0.125)).abs() < 1e-15,
        "{moved:?}"
    );
    assert!(base_x(0.125) > 0.009);
    // The kinetic energy at q̇ = 0 is the drive's: ½ m v² of the rod.
    let e = sim.energies(&q, &qd).unwrap();
    assert!(
        e.kinetic < e0.kinetic,
        "the base is at its crest at t = 1/8 s"
    );
}

/// `has_static_loads` sees every static force: a body load and a sprung
/// joint off its rest move the equilibrium from `q = 0`, and `modes` then
/// linearizes about the statics, where the static force vanishes.
#[test]
fn static_loads_include_body_loads_and_sprung_joints() {
    let arm = "[[rod]]\nname = \"arm\"\nlength = 0.3\npieces = 3\nstrains = [\"ky\", \"kz\", \"qx\"]\n\
               section = { shape = \"circle\", radius = 0.01 }\n\
               material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n";
    let body =
        "[[body]]\nname = \"m\"\nparent = \"arm\"\nmass = 0.05\ninertia = [1e-5, 1e-5, 1e-5]\n";
    let sprung = arm.replace(
        "strains",
        "joint = { type = \"spherical\", stiffness = 0.05, rest = [0.0, 0.8, 0.0] }\nstrains",
    );
    for (text, loaded) in [
        (format!("{arm}{body}"), false),
        (
            format!("{arm}{body}[[load]]\nbody = \"m\"\nforce = [0.0, 0.0, -0.5]\n"),
            true,
        ),
        (format!("{sprung}{body}"), true),
    ] {
        let (mut sim, _, _) = Simulation::from_toml(&text, "robot.toml").unwrap();
        assert_eq!(sim.has_static_loads(), loaded, "{text}");
        let analysis = sim.modes().unwrap();
        let q = match &analysis.equilibrium {
            softrod::Equilibrium::Rest => {
                assert!(!loaded);
                nalgebra::DVector::zeros(sim.n_dof())
            }
            softrod::Equilibrium::Statics(q) => {
                assert!(loaded);
                q.clone()
            }
        };
        let z = vec![0.0; sim.n_dof()];
        let f = sim.bias_force(0.0, q.as_slice(), &z).unwrap();
        assert!(f.amax() < 1e-9, "not an equilibrium: {f}");
    }
}
