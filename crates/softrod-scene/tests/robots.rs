//! `parent`, `at`, `base`, `joint` on rods and `[[body]]`
//! (scene-format.md, "Bodies, joints, bases and closures"): the order of `q`,
//! the model built, and key-path errors for bad input.

use softrod_dynamics::{ElementKind, JointKind};
use softrod_scene::Scene;

const ROBOT: &str = r#"
[world]
gravity = [0, 0, -9.81]

[[rod]]
name = "upper"
length = 0.4
pieces = 2
strains = ["ky", "kz"]
joint = { type = "revolute", axis = [0, 1, 0], stiffness = 0.5, damping = [0.01], rest = 0.1 }
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "elbow"
parent = "upper"
mass = 0.05
inertia = [[2e-6, 0, 0], [0, 3e-6, 0], [0, 0, 2e-6]]
center_of_mass = [0.01, 0, 0]
joint = { type = "universal", axes = [[0, 1, 0], [0, 0, 1]] }

[[rod]]
name = "lower"
parent = "elbow"
base = { position = [0.02, 0, 0] }
length = 0.3
pieces = 3
strains = ["ky"]
joint = { type = "spherical" }
section = { shape = "circle", radius = 0.008 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "gripper"
parent = "lower"
at = 0.2
mass = 0.02
inertia = [1e-6, 1e-6, 1e-6]
joint = { type = "prismatic", axis = [1, 0, 0] }

[[body]]
name = "float"
parent = "world"
mass = 0.1
inertia = [1e-4, 1e-4, 1e-4]
joint = { type = "free" }

[[load]]
body = "gripper"
force = [0, 0, -0.1]
"#;

#[test]
fn robot_scene_orders_q_as_written_and_builds() {
    let (scene, warnings) = Scene::from_str(ROBOT, "robot.toml").unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let r = &scene.robot;
    assert_eq!(
        r.order,
        vec![
            ElementKind::Rod(0),
            ElementKind::Body(0),
            ElementKind::Rod(1),
            ElementKind::Body(1),
            ElementKind::Body(2)
        ]
    );
    // upper: 1 + 4, elbow: 2, lower: 3 + 3, gripper: 1, float: 6.
    assert_eq!(scene.n_dof(), 5 + 2 + 6 + 1 + 6);
    assert_eq!(scene.rod_dof_offset(0), 1);
    assert_eq!(scene.rod_dof_offset(1), 5 + 2 + 3);
    assert_eq!(r.rod_attachments[0].joint.stiffness, vec![0.5]);
    assert_eq!(r.bodies[1].loads.len(), 1);
    let built = scene.build().unwrap();
    let m = &built.model;
    assert!(m.is_articulated());
    assert_eq!(m.n_dof(), 20);
    assert_eq!(m.rods()[1].dof_offset, 10);
    let joints: Vec<_> = m
        .elements()
        .iter()
        .map(|e| {
            (
                e.name.as_str(),
                e.attachment.joint.kind.name(),
                e.joint_dofs.clone(),
            )
        })
        .collect();
    assert_eq!(
        joints,
        vec![
            ("upper", "revolute", 0..1),
            ("elbow", "universal", 5..7),
            ("lower", "spherical", 7..10),
            ("gripper", "prismatic", 13..14),
            ("float", "free", 14..20)
        ]
    );
    assert!(matches!(
        m.elements()[3].attachment.joint.kind,
        JointKind::Prismatic { .. }
    ));
    let mut data = softrod_dynamics::Data::new(m);
    let q = vec![0.0; 20];
    let qdd = softrod_dynamics::forward_dynamics(m, &mut data, 0.0, &q, &q, None)
        .unwrap()
        .clone();
    // The free body falls at g.
    assert!((qdd[19] + 9.81).abs() < 1e-12);
}

#[test]
fn prescribed_joints_are_not_dof_and_follow_their_curves() {
    // The elbow's universal joint follows samples; the gripper's prismatic
    // joint a sinusoid.
    let text = ROBOT
        .replacen(
            "joint = { type = \"universal\", axes = [[0, 1, 0], [0, 0, 1]] }",
            "joint = { type = \"universal\", axes = [[0, 1, 0], [0, 0, 1]], prescribed = { times = [0, 1, 2], values = [[0, 0], [0.5, 1], [2, 4]] } }",
            1,
        )
        .replacen(
            "joint = { type = \"prismatic\", axis = [1, 0, 0] }",
            "joint = { type = \"prismatic\", axis = [1, 0, 0], prescribed = { sine = { amplitude = 0.01, frequency = 2, phase = 0.5 } } }",
            1,
        );
    assert_ne!(text, ROBOT);
    let (scene, _) = Scene::from_str(&text, "robot.toml").unwrap();
    assert_eq!(scene.n_dof(), 20 - 3);
    let m = scene.build().unwrap().model;
    assert_eq!(m.n_dof(), 17);
    assert_eq!(m.n_prescribed(), 3);
    let ranges: Vec<_> = m
        .elements()
        .iter()
        .map(|e| (e.joint_dofs.clone(), e.prescribed_dofs.clone()))
        .collect();
    assert_eq!(
        ranges,
        vec![
            (0..1, 0..0),
            (5..5, 0..2),
            (5..8, 2..2),
            (11..11, 2..3),
            (11..17, 3..3)
        ]
    );
    let mut data = softrod_dynamics::Data::new(&m);
    m.set_time(&mut data, 1.5);
    // Parabolas through the samples (x = t²/2, x = t²): rates t, 2t.
    let pq = data.prescribed_q.as_slice();
    assert!(
        (pq[0] - 1.125).abs() < 1e-12 && (pq[1] - 2.25).abs() < 1e-12,
        "{pq:?}"
    );
    let w = 2.0 * std::f64::consts::PI * 2.0;
    assert!((pq[2] - 0.01 * (w * 1.5 + 0.5).sin()).abs() < 1e-15);
    assert!((data.prescribed_qd[1] - 3.0).abs() < 1e-12);
    assert!((data.prescribed_qdd[2] + 0.01 * w * w * (w * 1.5 + 0.5).sin()).abs() < 1e-12);
    // No bounds given: none.
    assert_eq!(m.prescribed_bounds(0), None);

    // Bounds: one pair for every coordinate, or one per coordinate.
    let bounded = text
        .replacen(
            "values = [[0, 0], [0.5, 1], [2, 4]] }",
            "values = [[0, 0], [0.5, 1], [2, 4]], bounds = [[-1, 1], [0, 2.5]] }",
            1,
        )
        .replacen(
            "phase = 0.5 } }",
            "phase = 0.5 }, bounds = [-0.02, 0.03] }",
            1,
        );
    assert_ne!(bounded, text);
    let (scene, _) = Scene::from_str(&bounded, "robot.toml").unwrap();
    let m = scene.build().unwrap().model;
    let b: Vec<_> = (0..4).map(|i| m.prescribed_bounds(i)).collect();
    assert_eq!(
        b,
        vec![
            Some([-1.0, 1.0]),
            Some([0.0, 2.5]),
            Some([-0.02, 0.03]),
            None
        ]
    );
}

#[test]
fn plain_scene_has_an_empty_robot() {
    let text = ROBOT.split("[[body]]").next().unwrap().replace(
        "joint = { type = \"revolute\", axis = [0, 1, 0], stiffness = 0.5, damping = [0.01], rest = 0.1 }\n",
        "",
    );
    let (scene, _) = Scene::from_str(&text, "plain.toml").unwrap();
    assert!(scene.robot.is_trivial());
    assert!(!scene.build().unwrap().model.is_articulated());
}

/// Each edit of [`ROBOT`] must fail naming this key path and saying this.
#[test]
fn bad_robots_name_the_key() {
    let cases: &[(&str, &str, &str, &str)] = &[
        (
            "parent = \"elbow\"",
            "parent = \"elbo\"",
            "rod[1].parent",
            "elbo",
        ),
        (
            "name = \"upper\"\n",
            "name = \"upper\"\nparent = \"lower\"\n",
            "rod[0].parent",
            "cycle",
        ),
        (
            "axis = [0, 1, 0], stiffness",
            "axis = [0, 0, 0], stiffness",
            "rod[0].joint.axis",
            "zero",
        ),
        (
            "axes = [[0, 1, 0], [0, 0, 1]]",
            "axes = [[0, 1, 0], [0, 2, 0]]",
            "body[0].joint.axes",
            "parallel",
        ),
        (
            "type = \"spherical\"",
            "type = \"ball\"",
            "rod[1].joint.type",
            "ball",
        ),
        ("mass = 0.05", "mass = 0.0", "body[0].mass", "> 0"),
        (
            "inertia = [[2e-6, 0, 0], [0, 3e-6, 0], [0, 0, 2e-6]]",
            "inertia = [[2e-6, 0, 0], [0, -3e-6, 0], [0, 0, 2e-6]]",
            "body[0].inertia",
            "positive definite",
        ),
        (
            "inertia = [[2e-6, 0, 0], [0, 3e-6, 0], [0, 0, 2e-6]]",
            "inertia = [[2e-6, 1e-6, 0], [0, 3e-6, 0], [0, 0, 2e-6]]",
            "body[0].inertia",
            "symmetric",
        ),
        ("at = 0.2", "at = -0.05", "body[1].at", "in [0, 0.3]"),
        ("at = 0.2", "at = 0.5", "body[1].at", "0.3"),
        (
            "stiffness = 0.5, damping = [0.01]",
            "stiffness = 0.5, damping = [0.01, 0.02]",
            "rod[0].joint.damping",
            "1 coordinates",
        ),
        (
            "stiffness = 0.5,",
            "stiffness = -0.5,",
            "rod[0].joint.stiffness[0]",
            ">= 0",
        ),
        (
            "type = \"prismatic\", axis = [1, 0, 0]",
            "type = \"prismatic\"",
            "body[1].joint.axis",
            "missing",
        ),
        (
            "body = \"gripper\"",
            "body = \"grip\"",
            "load[0].body",
            "grip",
        ),
        (
            "name = \"float\"",
            "name = \"elbow\"",
            "body[2].name",
            "duplicate",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [0, 1], values = [0, 1] } }",
            "body[2].joint.prescribed.values[0]",
            "expected a list of numbers",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [0, 1], values = [[0, 1, 0, 0, 0, 0]] } }",
            "body[2].joint.prescribed.values",
            "1 values for 2 times",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [0, 1], values = [[0, 0, 0, 0, 0, 0], [0, 1, 0]] } }",
            "body[2].joint.prescribed.values[1]",
            "3 values, but the joint has 6 coordinates",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [1, 0], values = [[0, 0, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0]] } }",
            "body[2].joint.prescribed",
            "times must increase strictly",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { sine = { amplitude = 0.1 } } }",
            "body[2].joint.prescribed.sine.frequency",
            "missing",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { sine = { amplitude = 0.1, frequency = -1 } } }",
            "body[2].joint.prescribed.sine.frequency[0]",
            ">= 0",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { sine = { amplitude = 0.1, frequency = 1, omega = 2 } } }",
            "body[2].joint.prescribed.sine.omega",
            "amplitude, frequency, phase or offset",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { time = [0] } }",
            "body[2].joint.prescribed.time",
            "times, values, sine or bounds",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [0], values = [[0, 0, 0, 0, 0, 0]], bounds = [[0, 1], [0, 1]] } }",
            "body[2].joint.prescribed.bounds",
            "2 pairs, but the joint has 6 coordinates",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [0], values = [[0, 0, 0, 0, 0, 0]], bounds = [1, 0] } }",
            "body[2].joint.prescribed.bounds",
            "must be below",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [0], values = [[0, 0, 0, 0, 0, 0]], bounds = [0, 1, 2] } }",
            "body[2].joint.prescribed.bounds",
            "expected two numbers",
        ),
        (
            "joint = { type = \"free\" }",
            "joint = { type = \"free\", prescribed = { times = [0], values = [[0, 0, 0, 0, 0, 0]], bounds = [-inf, 0] } }",
            "body[2].joint.prescribed.bounds[0]",
            "finite",
        ),
        (
            "stiffness = 0.5,",
            "stiffness = 0.5, prescribed = { times = [0, 1], values = [0, 1] },",
            "rod[0].joint.stiffness",
            "no stiffness, damping or rest",
        ),
    ];
    for (old, new, path, says) in cases {
        assert!(ROBOT.contains(old), "edit target {old:?}");
        let text = ROBOT.replacen(old, new, 1);
        let e = Scene::from_str(&text, "bad.toml").unwrap_err();
        assert_eq!(e.path(), Some(*path), "{new}: {e}");
        let msg = e.to_string();
        assert!(msg.contains(says), "{new}: {msg}");
        assert!(msg.contains("bad.toml"), "{msg}");
    }
}

/// `[initial] shape`: a rod on a revolute joint turned by `initial.q`
/// starts on a circle arc given in the world; the fitted curvature is the
/// arc's, seen in the rod's turned frame, and the arc is reproduced.
#[test]
fn initial_shape_is_fitted_in_the_rod_frame_after_its_parents() {
    let radius = 0.4_f64;
    let angle = 0.3_f64;
    // The rod's base turned by `angle` about y (revolute joint, q = angle):
    // an arc bending towards the rod's −z, expressed in the world.
    let pts: Vec<String> = (0..=8)
        .map(|i| {
            let s = 0.2 * i as f64 / 8.0;
            let a = s / radius;
            let (x, z) = (radius * a.sin(), -radius * (1.0 - a.cos()));
            let (c, sn) = (angle.cos(), angle.sin());
            // R_y(angle) (x, 0, z): (c x + s z, 0, −s x + c z).
            format!("[{}, 0, {}]", c * x + sn * z, -sn * x + c * z)
        })
        .collect();
    let text = format!(
        r#"
[[rod]]
name = "arm"
length = 0.2
pieces = 4
strains = ["ky", "kz"]
joint = {{ type = "revolute", axis = [0, 1, 0] }}
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}

[initial]
q = [{angle}, 0, 0, 0, 0, 0, 0, 0, 0]
shape = [{{ rod = "arm", centerline = [{}] }}]
"#,
        pts.join(", ")
    );
    let (scene, _) = Scene::from_str(&text, "shape.toml").unwrap();
    let built = scene.build().unwrap();
    assert_eq!(built.q0[0], angle, "the joint keeps initial.q");
    for p in 0..4 {
        assert!(
            (built.q0[1 + 2 * p] - 1.0 / radius).abs() < 1e-9,
            "{}",
            built.q0
        );
        assert!(built.q0[2 + 2 * p].abs() < 1e-9, "{}", built.q0);
    }
    let fit = &built.shape_fits[0];
    assert_eq!(fit.rod, "arm");
    assert!(fit.max < 1e-12, "{fit:?}");
}

/// A `[s, x, y, z]` shape ending at `s` = the scene's `length` is the
/// rod's tip, though the sum of ten pieces of 0.1 m rounds below 1.0 m:
/// the straight line through the two rows is fitted exactly.
#[test]
fn an_initial_shape_may_end_at_the_scene_length() {
    let text = r#"
[[rod]]
name = "arm"
length = 1.0
pieces = 10
strains = ["ky", "kz", "qx"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[initial]
shape = [{ rod = "arm", centerline = [[0, 0, 0, 0], [0.5, 0.5, 0, 0], [1.0, 1.0, 0, 0]] }]
"#;
    assert!(0.1_f64 * 10.0 <= 1.0 && (0..10).fold(0.0, |a, _| a + 0.1) < 1.0);
    let (scene, _) = Scene::from_str(text, "shape.toml").unwrap();
    let built = scene.build().unwrap();
    // Straight and unstretched: no curvature, no stretch (qx is the
    // stretch's deviation from 1) in every piece.
    assert_eq!(built.q0.len(), 30);
    assert!(built.q0.iter().all(|q| q.abs() < 1e-9), "{}", built.q0);
    assert!(built.shape_fits[0].max < 1e-12, "{:?}", built.shape_fits[0]);
}

#[test]
fn bad_initial_shapes_name_the_key() {
    let base = r#"
[[rod]]
name = "arm"
length = 0.2
pieces = 2
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[initial]
"#;
    let cases = [
        (
            r#"shape = [{ rod = "leg", centerline = [[0, 0, 0], [0.2, 0, 0]] }]"#,
            "initial.shape[0].rod",
            "leg",
        ),
        (
            r#"shape = [{ rod = "arm", centerline = [[0, 0], [0.2, 0]] }]"#,
            "initial.shape[0].centerline",
            "[s, x, y, z]",
        ),
        (
            r#"shape = [{ rod = "arm", centerline = [[0, 0, 0], [0.2, 0]] }]"#,
            "initial.shape[0].centerline[1]",
            "2 values",
        ),
        (
            r#"shape = [{ rod = "arm", centerline = [[0, 0, 0]] }]"#,
            "initial.shape[0].centerline",
            "at least two",
        ),
        (
            r#"shape = [{ rod = "arm", centerline = [[0, 0, 0, 0], [0.3, 0.2, 0, 0]] }]"#,
            "initial.shape[0].centerline[1][0]",
            "[0, 0.2]",
        ),
        (
            r#"shape = [{ rod = "arm", centerline = [[0.1, 0, 0, 0], [0.1, 0.2, 0, 0]] }]"#,
            "initial.shape[0].centerline[1][0]",
            "increase strictly",
        ),
        (
            r#"shape = [{ rod = "arm", centerline = [[0, 0, 0], [0.2, 0, 0]] }, { rod = "arm", centerline = [[0, 0, 0], [0.2, 0, 0]] }]"#,
            "initial.shape[1].rod",
            "already",
        ),
        (
            r#"shape = [{ rod = "arm", points = [[0, 0, 0], [0.2, 0, 0]] }]"#,
            "initial.shape[0].points",
            "unknown key",
        ),
    ];
    for (line, path, says) in cases {
        let text = format!("{base}{line}\n");
        let e = Scene::from_str(&text, "bad.toml").unwrap_err();
        assert_eq!(e.path(), Some(path), "{line}: {e}");
        assert!(e.to_string().contains(says), "{line}: {e}");
    }
}

#[test]
fn a_sampled_drive_that_stops_before_the_run_warns() {
    let text = |times: &str, values: &str| {
        format!(
            "[[rod]]\nname = \"arm\"\nlength = 0.2\npieces = 2\n\
             joint = {{ type = \"prismatic\", axis = [0, 0, 1], prescribed = {{ times = {times}, values = {values} }} }}\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n\
             [run]\nduration = 2.0\n"
        )
    };
    // A ramp still rising at t = 1 s: it stops abruptly, a warning.
    let (_, w) = Scene::from_str(&text("[0, 1]", "[0, 0.1]"), "w.toml").unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].path, "rod[0].joint.prescribed.times");
    assert!(w[0].message.contains("stops abruptly"), "{w:?}");
    // At rest at its end, or lasting the whole run: no warning.
    let (_, w) = Scene::from_str(&text("[0, 0.5, 1]", "[0.1, 0.1, 0.1]"), "w.toml").unwrap();
    assert!(w.is_empty(), "{w:?}");
    let (_, w) = Scene::from_str(&text("[0, 1, 2]", "[0, 0.1, 0.1]"), "w.toml").unwrap();
    assert!(w.is_empty(), "{w:?}");
}
