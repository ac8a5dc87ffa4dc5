//! `[[closure]]` (scene-format.md, "Bodies, joints, bases and closures"):
//! a closed scene builds a model with its closures, and malformed closures
//! are errors naming the key path and the problem.

use softrod_dynamics::ClosureKind;
use softrod_scene::Scene;

const CLOSED: &str = r#"
[[rod]]
name = "beam"
length = 0.5
pieces = 4
strains = ["kx", "ky", "kz", "qx"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "plate"
parent = "beam"
at = 0.25
mass = 0.01
inertia = [1e-6, 1e-6, 1e-6]

[[closure]]
name = "far end"
type = "weld"
a = { element = "beam" }
b = { element = "world", base = { position = [0.5, 0, 0] } }

[[closure]]
type = "slider"
axis = [0, 0, 2]
a = { element = "beam", at = 0.125 }
b = { element = "plate", base = { position = [-0.125, 0, 0] } }
"#;

#[test]
fn closed_scene_builds_with_its_closures() {
    let (scene, warnings) = Scene::from_str(CLOSED, "c.toml").unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let c = &scene.robot.closures;
    assert_eq!(c.len(), 2);
    assert_eq!(c[0].name, "far end");
    assert_eq!(c[1].name, "closure[1]");
    assert_eq!(c[0].kind, ClosureKind::Weld);
    assert_eq!(c[1].a.at, Some(0.125));
    let built = scene.build().unwrap();
    assert!(built.model.has_closures());
    assert_eq!(built.model.n_constraints(), 8);
    let kinds: Vec<_> = built.model.closures().map(|c| c.kind.clone()).collect();
    // The axis is normalized by the model.
    assert_eq!(
        kinds[1],
        ClosureKind::Slider {
            axis: [0.0, 0.0, 1.0].into()
        }
    );
}

fn error_of(edits: &[(&str, &str)]) -> softrod_scene::SceneError {
    let mut text = CLOSED.to_owned();
    for (old, new) in edits {
        if old.is_empty() {
            text.push_str(new);
        } else {
            assert!(text.contains(old), "{old:?} not in the scene");
            text = text.replacen(old, new, 1);
        }
    }
    match Scene::from_str(&text, "c.toml") {
        Err(e) => e,
        Ok((scene, _)) => scene.build().expect_err("the scene should not build"),
    }
}

/// (case, edits `(old, new)`, key path, what the message says).
type Case<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str, &'a [&'a str]);

#[test]
fn malformed_closures_name_the_key() {
    let cases: &[Case] = &[
        (
            "unknown element",
            &[("a = { element = \"beam\" }", "a = { element = \"bean\" }")],
            "closure[0].a.element",
            &["bean", "beam", "plate", "world"],
        ),
        (
            "missing type",
            &[("type = \"weld\"\n", "")],
            "closure[0].type",
            &["missing"],
        ),
        (
            "unknown type",
            &[("type = \"weld\"", "type = \"glue\"")],
            "closure[0].type",
            &["glue", "weld", "ball", "slider"],
        ),
        (
            "zero axis",
            &[("axis = [0, 0, 2]", "axis = [0, 0, 0]")],
            "closure[1].axis",
            &["zero"],
        ),
        (
            "slider without axis",
            &[("axis = [0, 0, 2]\n", "")],
            "closure[1].axis",
            &["missing"],
        ),
        (
            "axis on a weld",
            &[("type = \"weld\"\n", "type = \"weld\"\naxis = [1, 0, 0]\n")],
            "closure[0].axis",
            &["only slider"],
        ),
        (
            "missing frame",
            &[("a = { element = \"beam\" }\n", "")],
            "closure[0].a",
            &["missing"],
        ),
        (
            "at off the rod",
            &[("at = 0.125", "at = 0.7")],
            "closure[1].a.at",
            &["0.7", "[0, 0.5]"],
        ),
        (
            "bad base rotation",
            &[(
                "base = { position = [0.5, 0, 0] }",
                "base = { position = [0.5, 0, 0], rotation = [[1, 0, 0], [0, 1, 0], [0, 0, -1]] }",
            )],
            "closure[0].b.base.rotation",
            &["rotation"],
        ),
        (
            "duplicate name",
            &[(
                "type = \"slider\"\n",
                "type = \"slider\"\nname = \"far end\"\n",
            )],
            "closure[1].name",
            &["duplicate", "far end"],
        ),
        (
            "both world",
            &[("a = { element = \"beam\" }", "a = { element = \"world\" }")],
            "closure[0].b.element",
            &["world"],
        ),
        (
            "unknown key",
            &[("type = \"weld\"\n", "type = \"weld\"\nstiffness = 3\n")],
            "closure[0].stiffness",
            &["stiffness"],
        ),
        (
            "does not hold at the start",
            &[("position = [0.5, 0, 0]", "position = [0.4, 0, 0]")],
            "closure[0]",
            &["far end", "does not hold", "residual 1.000e-1"],
        ),
    ];
    for (name, edits, path, says) in cases {
        let e = error_of(edits);
        let msg = e.to_string();
        assert_eq!(e.path(), Some(*path), "{name}: {msg}");
        assert!(msg.contains("c.toml"), "{name}: {msg}");
        for s in *says {
            assert!(msg.contains(s), "{name}: {msg:?} does not say {s:?}");
        }
    }
}
