//! `--set KEY=VALUE` overrides: a setting given beside the file reads
//! exactly as the same setting written in the file (compared with the scene
//! read from the edited text), and is rejected with the file's key paths,
//! naming the `--set` it came from.

use softrod_scene::{Integrator, Override, Scene};

const BASE: &str = r#"
[[rod]]
name = "arm"
length = 0.5
pieces = 4
strains = ["ky", "qx", "qz"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[cable]]
rod = "arm"
offset = [0.0, 0.005]
tension = 1.5
"#;

fn set(list: &[&str]) -> Vec<Override> {
    list.iter().map(|s| s.parse().unwrap()).collect()
}

/// The scene with `overrides` equals the scene of the `edited` text, and
/// so do their warnings.
fn same(overrides: &[&str], edited: &str) {
    let (a, wa) = Scene::from_str_with(BASE, "t.toml", &set(overrides)).unwrap();
    let (b, wb) = Scene::from_str(edited, "t.toml").unwrap();
    assert_eq!(a, b);
    assert_eq!(wa, wb);
}

#[test]
fn a_set_value_reads_as_the_same_value_in_the_file() {
    same(
        &["cable[0].tension=2.0"],
        &BASE.replace("tension = 1.5", "tension = 2.0"),
    );
    same(
        &["rod[0].material.young=2.0e6"],
        &BASE.replace("young = 1.0e6", "young = 2.0e6"),
    );
    // A table the file does not have is created; a bare word is a string.
    let (scene, _) = Scene::from_str_with(
        BASE,
        "t.toml",
        &set(&["run.integrator=radau5", "run.duration=2"]),
    )
    .unwrap();
    assert_eq!(scene.run.integrator, Integrator::Radau5);
    assert_eq!(scene.run.duration, 2.0);
    // Later settings win.
    let (scene, _) = Scene::from_str_with(
        BASE,
        "t.toml",
        &set(&["run.integrator=radau5", "run.integrator=\"rk4\""]),
    )
    .unwrap();
    assert_eq!(scene.run.integrator, Integrator::Rk4);
}

fn error(overrides: &[&str]) -> String {
    Scene::from_str_with(BASE, "t.toml", &set(overrides))
        .unwrap_err()
        .to_string()
}

#[test]
fn bad_values_are_errors_with_the_key_path_naming_the_set() {
    let e = error(&["rod[0].material.young=-1.0"]);
    assert!(
        e.starts_with(
            "t.toml (--set rod[0].material.young=-1.0): rod[0].material.young: out of range"
        ),
        "{e}"
    );
    let e = error(&["run.integrator=radau6"]);
    assert!(
        e.starts_with("t.toml (--set run.integrator=radau6): run.integrator: "),
        "{e}"
    );
    assert!(e.contains("radau6") && e.contains("esdirk"), "{e}");
    let e = error(&["run.integratr=esdirk"]);
    assert!(
        e.contains("(--set run.integratr=esdirk): run.integratr: unknown key"),
        "{e}"
    );
    let e = error(&["cable[0].tension=\"strong\""]);
    assert!(
        e.contains("(--set cable[0].tension=\"strong\"): cable[0].tension: "),
        "{e}"
    );
    let e = error(&["cable[3].tension=1.0"]);
    assert!(
        e.contains("(--set cable[3].tension=1.0): cable[3]: the scene has 1"),
        "{e}"
    );
    let e = error(&["rod[0].length.x=1.0"]);
    assert!(e.contains("rod[0].length: not a table"), "{e}");
    let e = error(&["rod[0].section=[1, 2"]);
    assert!(e.contains("rod[0].section: the value is not TOML"), "{e}");
    // Errors elsewhere in the file keep their line.
    let bad = BASE.replace("length = 0.5", "length = -0.5");
    let e = Scene::from_str_with(&bad, "t.toml", &set(&["run.duration=2"]))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("t.toml:4:"), "{e}");
}

#[test]
fn warnings_about_a_set_value_name_it() {
    // A cable outside the section (radius 1 cm) is legal but suspicious.
    let (_, w) =
        Scene::from_str_with(BASE, "t.toml", &set(&["cable[0].offset=[0.0, 0.02]"])).unwrap();
    assert!(!w.is_empty());
    assert!(
        w[0].at.is_none()
            && w[0]
                .message
                .contains("(from --set cable[0].offset=[0.0, 0.02])"),
        "{w:?}"
    );
}

#[test]
fn malformed_settings_are_rejected_when_parsed() {
    for bad in [
        "run.integrator",
        "=2",
        "rod[x].length=1",
        "rod..length=1",
        "x=",
    ] {
        let e = bad.parse::<Override>().unwrap_err().to_string();
        assert!(e.starts_with(&format!("--set {bad}: ")), "{e}");
    }
}
