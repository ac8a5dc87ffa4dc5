//! `[[obstacle]]`, `[contact]` and `contact_radius` (scene-format.md,
//! "Contact: obstacles, rods touching rods, friction"): what a valid scene
//! gives the library, and the key path, line and problem of every kind of
//! bad input.

use softrod_lie::{Mat3, Vec3};
use softrod_mechanics::contact::{ContactSettings, Shape};
use softrod_scene::{Scene, SceneError};

const ROD: &str = r#"
[[rod]]
name = "arm"
length = 0.5
pieces = 4
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "ball"
parent = "world"
mass = 0.1
inertia = [1e-4, 1e-4, 1e-4]
joint = { type = "free" }
"#;

const OBSTACLES: &str = r#"
[[obstacle]]
name = "table"
shape = "plane"
position = [0, 0, -0.1]
normal = [0, 0, 2]
friction = 0.5

[[obstacle]]
name = "bump"
shape = "sphere"
position = [0.3, 0, -0.1]
radius = 0.05
restitution = 0.25

[[obstacle]]
name = "pole"
shape = "cylinder"
position = [0.6, 0, 0]
axis = [0, 3, 4]
radius = 0.02

[[obstacle]]
name = "pin"
shape = "capsule"
position = [0.2, 0.1, 0]
axis = [1, 0, 0]
length = 0.2
radius = 0.01
parent = "ball"

[[obstacle]]
name = "crate"
shape = "box"
position = [0.4, 0, -0.05]
rotation = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
half_extents = [0.05, 0.1, 0.05]
parent = "world"
"#;

fn scene(text: &str) -> Scene {
    match Scene::from_str(text, "c.toml") {
        Ok((s, _)) => s,
        Err(e) => panic!("{e}"),
    }
}

fn error(text: &str) -> SceneError {
    Scene::from_str(text, "c.toml").expect_err("must be refused")
}

#[test]
fn every_shape_enters_the_library_with_unit_directions() {
    let s = scene(&format!("{ROD}{OBSTACLES}"));
    assert_eq!(s.obstacles.len(), 5);
    assert!(s.has_contact());
    let names: Vec<&str> = s.obstacles.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["table", "bump", "pole", "pin", "crate"]);
    assert_eq!(
        s.obstacles[0].shape,
        Shape::Plane {
            point: Vec3::new(0.0, 0.0, -0.1),
            normal: Vec3::z()
        }
    );
    assert_eq!(s.obstacles[0].friction, 0.5);
    assert_eq!(s.obstacles[0].restitution, 0.0);
    assert_eq!(s.obstacles[1].restitution, 0.25);
    assert_eq!(s.obstacles[1].friction, 0.0);
    match &s.obstacles[2].shape {
        Shape::Cylinder { axis, radius, .. } => {
            // (0, 3, 4) / 5.
            assert!((axis - Vec3::new(0.0, 0.6, 0.8)).norm() < 1e-15);
            assert_eq!(*radius, 0.02);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(s.obstacles[3].parent.as_deref(), Some("ball"));
    assert_eq!(s.obstacles[4].parent, None);
    match &s.obstacles[4].shape {
        Shape::Box {
            rotation,
            half_extents,
            ..
        } => {
            // Row-major like a rod's base.rotation: the box's x axis is world y.
            assert!((rotation * Vec3::x() - Vec3::y()).norm() < 1e-15);
            assert_eq!(*half_extents, Vec3::new(0.05, 0.1, 0.05));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(s.contact, ContactSettings::default());
}

#[test]
fn position_defaults_to_the_parent_origin_and_rotation_to_identity() {
    let s = scene(&format!(
        "{ROD}[[obstacle]]\nname = \"b\"\nshape = \"box\"\nhalf_extents = [1, 2, 3]\n"
    ));
    assert_eq!(
        s.obstacles[0].shape,
        Shape::Box {
            center: Vec3::zeros(),
            rotation: Mat3::identity(),
            half_extents: Vec3::new(1.0, 2.0, 3.0)
        }
    );
}

#[test]
fn a_rotation_written_with_six_decimals_is_accepted_and_made_exact() {
    let s = scene(&format!(
        "{ROD}[[obstacle]]\nname = \"b\"\nshape = \"box\"\nhalf_extents = [1, 1, 1]\n\
         rotation = [[0.707107, -0.707107, 0], [0.707107, 0.707107, 0], [0, 0, 1]]\n"
    ));
    let Shape::Box { rotation, .. } = &s.obstacles[0].shape else {
        panic!()
    };
    assert!(
        (rotation.transpose() * rotation - Mat3::identity())
            .abs()
            .max()
            < 1e-14
    );
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!((rotation * Vec3::x() - Vec3::new(h, h, 0.0)).norm() < 1e-6);
}

#[test]
fn contact_settings_and_contact_radius() {
    let text = format!(
        "{ROD}[contact]\nrods = true\nself = true\nfriction = 0.3\nrestitution = 0.1\n\
         [[rod]]\nname = \"flat\"\nlength = 0.2\npieces = 1\n\
         section = {{ shape = \"rectangle\", width = 0.06, height = 0.08 }}\n\
         material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n\
         [[rod]]\nname = \"thin\"\nlength = 0.2\npieces = 1\ncontact_radius = 0.004\n\
         section = {{ shape = \"circle\", radius = 0.01 }}\n\
         material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n"
    );
    let s = scene(&text);
    assert_eq!(
        s.contact,
        ContactSettings {
            rods: true,
            self_contact: true,
            friction: 0.3,
            restitution: 0.1
        }
    );
    assert!(s.has_contact() && s.obstacles.is_empty());
    assert_eq!(s.contact_radius(0, 0.2), 0.01);
    // Half the diagonal of 6 cm × 8 cm: 5 cm.
    assert!((s.contact_radius(1, 0.1) - 0.05).abs() < 1e-15);
    assert_eq!(s.contact_radius(2, 0.1), 0.004);
}

#[test]
fn a_scene_without_contact_has_none() {
    let s = scene(ROD);
    assert!(!s.has_contact());
    assert!(s.obstacles.is_empty());
}

#[test]
fn friction_between_rods_without_rod_contact_is_warned_about() {
    let (_, warnings) =
        Scene::from_str(&format!("{ROD}[contact]\nfriction = 0.3\n"), "c.toml").unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.path == "contact" && w.message.contains("no effect")),
        "{warnings:?}"
    );
}

/// One bad input: the obstacle text appended to [`ROD`], the key path and
/// what the message says.
struct Case {
    name: &'static str,
    text: &'static str,
    path: &'static str,
    says: &'static [&'static str],
}

const PLANE: &str = "[[obstacle]]\nname = \"table\"\nshape = \"plane\"\n";

const CASES: &[Case] = &[
    Case {
        name: "zero radius",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = 0.0\n",
        path: "obstacle[0].radius",
        says: &["out of range: 0", "> 0"],
    },
    Case {
        name: "negative cylinder radius",
        text: "[[obstacle]]\nname = \"c\"\nshape = \"cylinder\"\naxis = [0, 1, 0]\nradius = -0.1\n",
        path: "obstacle[0].radius",
        says: &["out of range: -0.1"],
    },
    Case {
        name: "negative capsule length",
        text: "[[obstacle]]\nname = \"c\"\nshape = \"capsule\"\naxis = [0, 1, 0]\nradius = 0.1\nlength = -1\n",
        path: "obstacle[0].length",
        says: &["out of range: -1", ">= 0"],
    },
    Case {
        name: "zero half extent",
        text: "[[obstacle]]\nname = \"b\"\nshape = \"box\"\nhalf_extents = [0.1, 0.0, 0.1]\n",
        path: "obstacle[0].half_extents[1]",
        says: &["out of range: 0"],
    },
    Case {
        name: "zero normal",
        text: "[[obstacle]]\nname = \"table\"\nshape = \"plane\"\nnormal = [0, 0, 0]\n",
        path: "obstacle[0].normal",
        says: &["zero vector"],
    },
    Case {
        name: "zero axis",
        text: "[[obstacle]]\nname = \"c\"\nshape = \"cylinder\"\naxis = [0.0, 0.0, 0.0]\nradius = 0.1\n",
        path: "obstacle[0].axis",
        says: &["zero vector"],
    },
    Case {
        name: "non-orthonormal rotation",
        text: "[[obstacle]]\nname = \"b\"\nshape = \"box\"\nhalf_extents = [1, 1, 1]\n\
               rotation = [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]\n",
        path: "obstacle[0].rotation",
        says: &["not a rotation matrix"],
    },
    Case {
        name: "mirror rotation",
        text: "[[obstacle]]\nname = \"b\"\nshape = \"box\"\nhalf_extents = [1, 1, 1]\n\
               rotation = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]\n",
        path: "obstacle[0].rotation",
        says: &["det R = -1"],
    },
    Case {
        name: "unknown parent",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = 0.1\nparent = \"bal\"\n",
        path: "obstacle[0].parent",
        says: &["\"bal\"", "ball", "world"],
    },
    Case {
        name: "a rod as parent",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = 0.1\nparent = \"arm\"\n",
        path: "obstacle[0].parent",
        says: &["is a rod", "valid: ball, world"],
    },
    Case {
        name: "negative friction",
        text: "[[obstacle]]\nname = \"table\"\nshape = \"plane\"\nnormal = [0, 0, 1]\nfriction = -0.2\n",
        path: "obstacle[0].friction",
        says: &["out of range: -0.2", ">= 0"],
    },
    Case {
        name: "restitution above one",
        text: "[[obstacle]]\nname = \"table\"\nshape = \"plane\"\nnormal = [0, 0, 1]\nrestitution = 1.5\n",
        path: "obstacle[0].restitution",
        says: &["out of range: 1.5", "in [0, 1]"],
    },
    Case {
        name: "negative restitution between rods",
        text: "[contact]\nrods = true\nrestitution = -0.1\n",
        path: "contact.restitution",
        says: &["out of range: -0.1", "in [0, 1]"],
    },
    Case {
        name: "negative friction between rods",
        text: "[contact]\nrods = true\nfriction = -1\n",
        path: "contact.friction",
        says: &["out of range: -1"],
    },
    Case {
        name: "NaN radius",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = nan\n",
        path: "obstacle[0].radius",
        says: &["not a finite number: nan"],
    },
    Case {
        name: "infinite position",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = 1\nposition = [0, inf, 0]\n",
        path: "obstacle[0].position[1]",
        says: &["not a finite number: inf"],
    },
    Case {
        name: "unknown key",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = 1\ncolour = \"red\"\n",
        path: "obstacle[0].colour",
        says: &["unknown key", "half_extents"],
    },
    Case {
        name: "unknown key in [contact]",
        text: "[contact]\nselff = true\n",
        path: "contact.selff",
        says: &["unknown key", "self"],
    },
    Case {
        name: "a key of another shape",
        text: "[[obstacle]]\nname = \"table\"\nshape = \"plane\"\nnormal = [0, 0, 1]\nradius = 0.1\n",
        path: "obstacle[0].radius",
        says: &["does not apply to shape \"plane\"", "position, normal"],
    },
    Case {
        name: "a box with an axis",
        text: "[[obstacle]]\nname = \"b\"\nshape = \"box\"\nhalf_extents = [1, 1, 1]\naxis = [1, 0, 0]\n",
        path: "obstacle[0].axis",
        says: &["does not apply to shape \"box\""],
    },
    Case {
        name: "missing radius",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\n",
        path: "obstacle[0].radius",
        says: &["missing required key"],
    },
    Case {
        name: "missing normal",
        text: PLANE,
        path: "obstacle[0].normal",
        says: &["missing required key"],
    },
    Case {
        name: "missing name",
        text: "[[obstacle]]\nshape = \"sphere\"\nradius = 1\n",
        path: "obstacle[0].name",
        says: &["missing required key"],
    },
    Case {
        name: "unknown shape",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"cone\"\n",
        path: "obstacle[0].shape",
        says: &["\"cone\"", "plane, sphere, cylinder, capsule, box"],
    },
    Case {
        name: "duplicate obstacle names",
        text: "[[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = 1\n\
               [[obstacle]]\nname = \"s\"\nshape = \"sphere\"\nradius = 2\n",
        path: "obstacle[1].name",
        says: &["duplicate obstacle name \"s\"", "obstacle[0]"],
    },
    Case {
        name: "an obstacle named like a rod",
        text: "[[obstacle]]\nname = \"arm\"\nshape = \"sphere\"\nradius = 1\n",
        path: "obstacle[0].name",
        says: &["rod[0]"],
    },
    Case {
        name: "empty obstacle name",
        text: "[[obstacle]]\nname = \" \"\nshape = \"sphere\"\nradius = 1\n",
        path: "obstacle[0].name",
        says: &["must not be empty"],
    },
    Case {
        name: "wrong type of self",
        text: "[contact]\nself = 1\n",
        path: "contact.self",
        says: &["wrong type"],
    },
];

#[test]
fn bad_obstacles_and_settings_name_the_key_and_the_problem() {
    let mut failures = Vec::new();
    for case in CASES {
        let text = format!("{ROD}{}", case.text);
        let e = match Scene::from_str(&text, "c.toml") {
            Ok(_) => {
                failures.push(format!("{}: accepted", case.name));
                continue;
            }
            Err(e) => e,
        };
        let msg = e.to_string();
        if e.path() != Some(case.path) {
            failures.push(format!("{}: path {:?}: {msg}", case.name, e.path()));
        }
        if !msg.starts_with("c.toml:") {
            failures.push(format!("{}: no file:line:col: {msg}", case.name));
        }
        for s in case.says {
            if !msg.contains(s) {
                failures.push(format!("{}: {s:?} not in {msg}", case.name));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn errors_point_at_the_line_of_the_key() {
    let text = format!("{ROD}{OBSTACLES}",)
        .replace("radius = 0.05\nrestitution", "radius = -0.05\nrestitution");
    let e = error(&text);
    assert_eq!(e.path(), Some("obstacle[1].radius"));
    let line = text
        .lines()
        .position(|l| l == "radius = -0.05")
        .expect("edited line")
        + 1;
    let at = e.location().expect("located");
    assert_eq!(at.line, line, "{e}");
    assert!(e.to_string().starts_with(&format!("c.toml:{line}:")), "{e}");
    // The library's error is the source.
    let cause = std::error::Error::source(&e).expect("chained");
    assert!(cause.to_string().starts_with("radius must be positive"));
}

#[test]
fn contact_radius_must_be_positive() {
    let text = ROD.replace("pieces = 4\n", "pieces = 4\ncontact_radius = 0.0\n");
    let e = error(&text);
    assert_eq!(e.path(), Some("rod[0].contact_radius"), "{e}");
    assert!(e.to_string().contains("out of range: 0"), "{e}");
}

/// A rod that starts inside an obstacle is refused when the model is built
/// (what every command does before it writes anything), naming the rod, the
/// obstacle and the depth: a straight rod along x of radius 1 cm with a
/// table 5 mm above its centreline penetrates 1 cm + 5 mm = 1.5e-2 m.
#[test]
fn a_rod_starting_inside_an_obstacle_is_refused_naming_both_and_the_depth() {
    let text = format!(
        "{ROD}[[obstacle]]\nname = \"table\"\nshape = \"plane\"\nposition = [0, 0, 0.005]\n\
         normal = [0, 0, 1]\n"
    );
    let s = scene(&text);
    let e = s.build().expect_err("overlap");
    assert_eq!(e.path(), Some("obstacle[0]"), "{e}");
    let msg = e.to_string();
    for part in ["'arm'", "obstacle 'table'", "1.500e-2"] {
        assert!(msg.contains(part), "{part:?} not in {msg}");
    }
    // Touching within the allowed penetration (1 % of the radius) is fine:
    // the table 0.05 mm below the surface.
    let ok = text.replace("position = [0, 0, 0.005]", "position = [0, 0, -0.00995]");
    assert!(scene(&ok).build().is_ok());
    // And so is a table clear of the rod; the model then has the contact.
    let clear = text.replace("position = [0, 0, 0.005]", "position = [0, 0, -0.02]");
    let built = scene(&clear).build().unwrap();
    assert!(built.model.has_contact());
    assert_eq!(built.model.obstacles().len(), 1);
    // A scene without contact builds a model without.
    assert!(!scene(ROD).build().unwrap().model.has_contact());
}

#[test]
fn contact_radius_reaches_the_model() {
    let text = ROD.replace("pieces = 4\n", "pieces = 4\ncontact_radius = 0.004\n");
    let text = format!(
        "{text}[[obstacle]]\nname = \"table\"\nshape = \"plane\"\nposition = [0, 0, -0.0045]\n\
         normal = [0, 0, 1]\n"
    );
    // With the section's 1 cm radius the rod would start 5.5 mm deep; with
    // its 4 mm contact radius it clears the table by 0.5 mm.
    let built = scene(&text).build().unwrap();
    assert_eq!(built.model.rods()[0].spec.contact_radius, Some(0.004));
    let gap = built
        .model
        .max_penetration(0.0, built.q0.as_slice())
        .unwrap();
    assert_eq!(gap, 0.0);
}
