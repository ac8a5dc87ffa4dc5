//! Contact in the command line (scene-format.md, "Contact: obstacles, rods
//! touching rods, friction"): `check` lists obstacles and the contact
//! settings; bad obstacles exit 2 naming the key.

mod common;

use common::{run, stderr, stdout, tmp};

const SCENE: &str = r#"
[world]
gravity = [0, 0, -9.81]

[[rod]]
name = "arm"
length = 0.5
pieces = 4
strains = ["ky", "qx"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "ball"
parent = "world"
base = { position = [0.3, 0, -0.3] }
mass = 0.1
inertia = [1e-4, 1e-4, 1e-4]

[[obstacle]]
name = "table"
shape = "plane"
position = [0, 0, -0.2]
normal = [0, 0, 2]
friction = 0.5

[[obstacle]]
name = "knob"
shape = "sphere"
radius = 0.03
parent = "ball"

[contact]
rods = true
friction = 0.25
"#;

#[test]
fn check_lists_obstacles_and_contact_settings() {
    let dir = tmp("check");
    let scene = dir.join("c.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let o = run(&["check", scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    // The normal as the model has it: unit.
    assert!(
        out.contains(
            "obstacle 'table': plane through [0, 0, -0.2] m, normal [0, 0, 1], fixed in the \
             world, friction 0.5, restitution 0"
        ),
        "{out}"
    );
    assert!(
        out.contains(
            "obstacle 'knob': sphere at [0, 0, 0] m, radius 0.03 m, carried by body 'ball', \
             friction 0, restitution 0"
        ),
        "{out}"
    );
    assert!(
        out.contains(
            "contact between rods: different rods yes, a rod with itself no, friction 0.25, \
             restitution 0"
        ),
        "{out}"
    );
    assert!(out.contains("contact radius of rod 'arm': 0.01 m"), "{out}");
}

#[test]
fn a_scene_without_contact_says_nothing_of_it() {
    let dir = tmp("none");
    let scene = dir.join("n.toml");
    let text = SCENE.split("[[obstacle]]").next().unwrap();
    std::fs::write(&scene, text).unwrap();
    let o = run(&["check", scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stdout(&o).contains("contact"), "{}", stdout(&o));
    assert!(!stdout(&o).contains("obstacle"), "{}", stdout(&o));
}

#[test]
fn bad_obstacles_exit_2_naming_the_key() {
    let dir = tmp("bad");
    for (edit, path) in [
        ("radius = 0.03", "obstacle[1].radius"),
        ("normal = [0, 0, 2]", "obstacle[0].normal"),
        ("parent = \"ball\"", "obstacle[1].parent"),
        ("friction = 0.5", "obstacle[0].friction"),
    ] {
        let bad = match edit {
            "radius = 0.03" => SCENE.replace(edit, "radius = -0.03"),
            "normal = [0, 0, 2]" => SCENE.replace(edit, "normal = [0, 0, 0]"),
            "parent = \"ball\"" => SCENE.replace(edit, "parent = \"bal\""),
            _ => SCENE.replace(edit, "friction = -0.5"),
        };
        let scene = dir.join("b.toml");
        std::fs::write(&scene, bad).unwrap();
        for cmd in ["check", "statics", "run"] {
            let out = dir.join("out");
            let o = run(&[cmd, scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
            let o = if cmd == "check" {
                run(&[cmd, scene.to_str().unwrap()])
            } else {
                o
            };
            assert_eq!(o.status.code(), Some(2), "{cmd} {edit}: {}", stderr(&o));
            let err = stderr(&o);
            assert!(err.contains(path), "{cmd} {edit}: {err}");
            assert!(!out.exists(), "{cmd} {edit}: wrote {}", out.display());
        }
    }
}
