//! Joint actuators (docs/theory-control.md IS14) against independent
//! references: the static balance of moments about an actuated revolute
//! joint and of forces along a prismatic one, a body pushed along a
//! prismatic joint by a tabled force against the closed-form motion, and
//! inverse statics recovering a joint torque used in a forward solve.

use softrod::control::{ActuationOptions, Bound, Target};
use softrod::lie::Vec3;
use softrod::{Error, Simulation};

const G: f64 = 9.81;
const MASS: f64 = 0.2;
/// Centre of mass of the link along its x axis \[m\].
const D: f64 = 0.1;
/// Spring of the revolute joint \[N·m/rad\]: keeps the tangent regular at
/// the horizontal start, where gravity's stiffness about the joint is 0.
const K: f64 = 0.2;

fn sim(text: &str) -> Simulation {
    Simulation::from_toml(text, "test.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .0
}

/// A short flexible rod clamped to the world, a link body on an actuated
/// revolute joint about y at its tip, gravity along −z.
fn arm_with_link(actuator: &str) -> String {
    format!(
        "[world]\ngravity = [0.0, 0.0, -{G}]\n\
         [[rod]]\nname = \"base\"\nlength = 0.2\npieces = 2\nstrains = [\"kx\", \"ky\", \"kz\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n\
         [[body]]\nname = \"link\"\nparent = \"base\"\n\
         joint = {{ type = \"revolute\", axis = [0, 1, 0], stiffness = {K}, actuator = {actuator} }}\n\
         mass = {MASS}\ninertia = [1e-4, 1e-4, 1e-4]\ncenter_of_mass = [{D}, 0, 0]\n"
    )
}

/// The generalized force on the joint coordinate that is not the
/// actuator's: the spring's `−kθ` and gravity's moment about the joint
/// axis, `a·(R c × m g)` (the joint axis through the body frame's origin,
/// `a = R e_y` in world axes). Exact whatever the base rod does: the link is
/// the only thing beyond the joint.
fn passive_torque(s: &Simulation, q: &[f64]) -> f64 {
    let pose = s.body_poses(q).unwrap()[0];
    let r = pose.rotation * Vec3::new(D, 0.0, 0.0);
    let a = pose.rotation * Vec3::new(0.0, 1.0, 0.0);
    let theta = q[q.len() - 1];
    -K * theta + a.dot(&r.cross(&Vec3::new(0.0, 0.0, -MASS * G)))
}

/// Forward statics with a constant joint torque: the torque balances the
/// spring and gravity's moment about the joint, to the statics' tolerance.
#[test]
fn revolute_torque_balances_gravity_moment() {
    for tau in [-0.1, 0.05, 0.3] {
        let mut s = sim(&arm_with_link(&format!("{{ force = {tau} }}")));
        let q = s.statics().unwrap().q.as_slice().to_vec();
        let theta = q[q.len() - 1];
        assert!(theta.abs() > 0.05, "the link moved: θ = {theta}");
        let residual = tau + passive_torque(&s, &q);
        assert!(
            residual.abs() < 1e-10 * MASS * G * D,
            "τ = {tau}: residual {residual:e}"
        );
    }
    // Without the actuator the same balance fails by the torque: the
    // check sees the actuator's force and nothing else.
    let mut s = sim(&arm_with_link("{ force = 0.0 }"));
    let q = s.statics().unwrap().q.as_slice().to_vec();
    assert!(passive_torque(&s, &q).abs() < 1e-10 * MASS * G * D);
}

/// A body on a vertical prismatic joint with a spring holds its weight and
/// the actuator's push: `x = (F − m g)/k`.
#[test]
fn prismatic_force_holds_a_weight() {
    let (k, f) = (10.0, 3.0);
    let text = format!(
        "[world]\ngravity = [0.0, 0.0, -{G}]\n\
         [[rod]]\nname = \"post\"\nlength = 0.2\npieces = 1\nstrains = [\"kx\", \"ky\", \"kz\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n\
         [[body]]\nname = \"slider\"\nparent = \"world\"\n\
         joint = {{ type = \"prismatic\", axis = [0, 0, 1], stiffness = {k}, actuator = {{ force = {f} }} }}\n\
         mass = {MASS}\ninertia = [1e-4, 1e-4, 1e-4]\n"
    );
    let mut s = sim(&text);
    let q = s.statics().unwrap().q.as_slice().to_vec();
    let x = q[q.len() - 1];
    let want = (f - MASS * G) / k;
    assert!((x - want).abs() < 1e-12, "x = {x}, want {want}");
    // An input replaces the schedule (and goes back to it).
    s.set_joint_forces(Some(&[2.0 * f])).unwrap();
    let q = s.statics().unwrap().q.as_slice().to_vec();
    let want2 = (2.0 * f - MASS * G) / k;
    assert!((q[q.len() - 1] - want2).abs() < 1e-12);
    assert!(s.set_joint_forces(Some(&[1.0, 2.0])).is_err());
    assert!(s.set_joint_forces(Some(&[f64::NAN])).is_err());
    s.set_joint_forces(None).unwrap();
    let q = s.statics().unwrap().q.as_slice().to_vec();
    assert!((q[q.len() - 1] - want).abs() < 1e-12);
}

/// A free body pushed along a prismatic joint by a tabled force
/// `F = 2t` N for `t ≤ 1` s, held at 2 N after: `m ẍ = F` gives
/// `x = t³/(3m)` up to 1 s and `x(1.5) = 1/(3m) + 0.5/m + 0.25/m`.
#[test]
fn tabled_force_drives_a_body_as_newton_says() {
    let text = format!(
        "[[rod]]\nname = \"post\"\nlength = 0.2\npieces = 1\nstrains = [\"kx\", \"ky\", \"kz\"]\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n\
         [[body]]\nname = \"cart\"\nparent = \"world\"\n\
         joint = {{ type = \"prismatic\", axis = [1, 0, 0], actuator = {{ force = {{ times = [0.0, 1.0], values = [0.0, 2.0] }} }} }}\n\
         mass = {MASS}\ninertia = [1e-4, 1e-4, 1e-4]\n\
         [run]\nduration = 1.5\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-12\noutput_every = 0.5\n"
    );
    let mut s = sim(&text);
    let traj = s.simulate(1.5).unwrap();
    for (t, q) in traj.t.iter().zip(&traj.q) {
        let x = q[q.len() - 1];
        let want = if *t <= 1.0 {
            t.powi(3) / (3.0 * MASS)
        } else {
            let dt = t - 1.0;
            1.0 / (3.0 * MASS) + dt / MASS + dt * dt / MASS
        };
        assert!(
            (x - want).abs() <= 1e-8 * (1.0 + want.abs()),
            "t = {t}: x = {x}, want {want}"
        );
    }
    assert!((traj.t.last().unwrap() - 1.5).abs() < 1e-12);
}

/// Inverse statics recovers the joint torque of a forward solve from the
/// link's position, and the shape; with a bound below it, the torque sits
/// on the bound and the target is reported out of reach.
#[test]
fn inverse_statics_recovers_a_joint_torque() {
    let tau = -0.1;
    let mut truth = sim(&arm_with_link(&format!("{{ force = {tau} }}")));
    let q = truth.statics().unwrap().q.as_slice().to_vec();
    let pose = truth.body_poses(&q).unwrap()[0];
    let target = Target::body_position(0, pose.translation.into());

    let mut s = sim(&arm_with_link("{ force = 0.0, max_force = 1.0 }"));
    let a = s
        .solve_actuation(std::slice::from_ref(&target), &ActuationOptions::default())
        .unwrap();
    assert!(a.converged && a.reached, "{}", a.message);
    assert_eq!(a.joint_forces.len(), 1);
    assert!(
        (a.joint_forces[0] - tau).abs() < 1e-8,
        "recovered {} for {tau}",
        a.joint_forces[0]
    );
    assert_eq!(a.joint_force_bounds, vec![Bound::Free]);
    let dq =
        a.q.iter()
            .zip(&q)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
    assert!(dq < 1e-8, "shape off by {dq:e}");
    assert!(a.tensions.is_empty() && a.forces.is_empty());

    let mut bounded = sim(&arm_with_link("{ force = 0.0, max_force = 0.05 }"));
    let b = bounded
        .solve_actuation(&[target], &ActuationOptions::default())
        .unwrap();
    assert!(b.converged && !b.reached, "{}", b.message);
    assert_eq!(b.joint_forces[0], -0.05);
    assert_eq!(b.joint_force_bounds, vec![Bound::Lower]);
    assert!(
        b.message
            .contains("\"link\" coordinate 0 at its lower bound"),
        "{}",
        b.message
    );
}

/// Bad scene input names the key path.
#[test]
fn bad_actuators_name_the_key() {
    let cases = [
        (
            "{ force = 0.1, max_force = -1.0 }",
            "body[0].joint.actuator.max_force",
        ),
        ("{ force = [0.1, 0.2] }", "body[0].joint.actuator.force"),
        ("{ force = 0.1, push = 1 }", "body[0].joint.actuator.push"),
        (
            "{ force = { times = [0.0, 0.0], values = [1.0, 2.0] } }",
            "body[0].joint.actuator.force.times[1]",
        ),
        ("{ force = nan }", "body[0].joint.actuator.force"),
    ];
    for (actuator, key) in cases {
        let text = arm_with_link(actuator);
        match Simulation::from_toml(&text, "test.toml") {
            Err(e) => assert!(e.to_string().contains(key), "{actuator}: {e}"),
            Ok(_) => panic!("{actuator} accepted"),
        }
    }
    let fixed = arm_with_link("{ force = 0.1 }").replace(
        "type = \"revolute\", axis = [0, 1, 0], stiffness = 0.2, ",
        "type = \"fixed\", ",
    );
    match Simulation::from_toml(&fixed, "test.toml") {
        Err(e) => assert!(
            e.to_string().contains("body[0].joint.actuator") && e.to_string().contains("fixed"),
            "{e}"
        ),
        Ok(_) => panic!("an actuator on a fixed joint accepted"),
    }
    // The library refuses a bad actuator too, naming the element.
    use softrod::dynamics::{Joint, JointActuator};
    let bad = [
        Joint::fixed().with_actuator(JointActuator::constant(&[1.0])),
        Joint::revolute([0.0, 1.0, 0.0]).with_actuator(JointActuator::constant(&[1.0, 2.0])),
        Joint::revolute([0.0, 1.0, 0.0])
            .with_actuator(JointActuator::constant(&[1.0]).with_max_force(&[-1.0])),
        Joint::revolute([0.0, 1.0, 0.0]).with_actuator(JointActuator::constant(&[f64::NAN])),
    ];
    for mut j in bad {
        let e = j.validate("link").unwrap_err().to_string();
        assert!(e.contains("link") && e.contains("actuator"), "{e}");
    }
    // Inverse statics with no targets is an input error.
    let mut s = sim(&arm_with_link("{ force = 0.1 }"));
    let err = s.solve_actuation(&[], &ActuationOptions::default());
    assert!(matches!(err, Err(Error::Actuation { .. })));
}
