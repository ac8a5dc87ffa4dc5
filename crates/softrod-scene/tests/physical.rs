//! Physical validation and resource bounds of scenes (issue 15): values a
//! parser accepts but physics or the machine cannot.

use softrod_scene::{MAX_QUADRATURE, Scene, SceneError};

const BASE: &str = include_str!("contract_example.toml");

fn edit(old: &str, new: &str) -> String {
    assert!(BASE.contains(old), "{old:?} not in the base scene");
    BASE.replacen(old, new, 1)
}

fn error_of(text: &str) -> SceneError {
    match Scene::from_str(text, "case.toml") {
        Ok(_) => panic!("scene accepted"),
        Err(e) => e,
    }
}

#[test]
fn non_positive_rest_stretch_is_an_error() {
    for s in ["0", "-1", "0.0"] {
        let e = error_of(&edit(
            "rest_strain = [0, 0, 0, 1, 0, 0]",
            &format!("rest_strain = [0, 0, 0, {s}, 0, 0]"),
        ));
        assert_eq!(e.path(), Some("rod[0].rest_strain[3]"), "{e}");
        assert!(e.to_string().contains("> 0"), "{e}");
        assert!(e.location().is_some(), "{e}");
    }
}

#[test]
fn far_from_unit_rest_stretch_is_a_warning() {
    for (s, warned) in [
        ("0.4", true),
        ("1.6", true),
        ("0.5", false),
        ("1.5", false),
        ("1", false),
    ] {
        let (_, w) = Scene::from_str(
            &edit(
                "rest_strain = [0, 0, 0, 1, 0, 0]",
                &format!("rest_strain = [0, 0, 0, {s}, 0, 0]"),
            ),
            "case.toml",
        )
        .unwrap();
        let hit = w.iter().any(|w| w.path == "rod[0].rest_strain[3]");
        assert_eq!(hit, warned, "stretch {s}: {w:?}");
    }
}

#[test]
fn absurd_magnitudes_are_errors_naming_the_key() {
    for (old, new, path) in [
        (
            "gravity = [0.0, 0.0, -9.81]",
            "gravity = [0.0, 0.0, -1e300]",
            "world.gravity[2]",
        ),
        ("length = 0.5", "length = 1e300", "rod[0].length"),
        ("young = 1.0e6", "young = 1e31", "rod[0].material.young"),
        ("tension = 2.0", "tension = -2e40", "cable[0].tension"),
    ] {
        let e = error_of(&edit(old, new));
        assert_eq!(e.path(), Some(path), "{new}: {e}");
        assert!(e.to_string().contains("magnitude"), "{e}");
    }
    // Large but physical values stay accepted.
    Scene::from_str(&edit("young = 1.0e6", "young = 1.2e12"), "case.toml").unwrap();
}

#[test]
fn non_finite_numbers_anywhere_are_errors() {
    for (old, new, path) in [
        (
            "gravity = [0.0, 0.0, -9.81]",
            "gravity = [0.0, nan, -9.81]",
            "world.gravity[1]",
        ),
        ("radius = 0.01", "radius = inf", "rod[0].section.radius"),
        ("s = 0.5", "s = -inf", "load[0].s"),
    ] {
        let e = error_of(&edit(old, new));
        assert_eq!(e.path(), Some(path), "{new}: {e}");
    }
}

#[test]
fn quadrature_is_bounded() {
    let e = error_of(&edit("quadrature = 4", "quadrature = 100000"));
    assert_eq!(e.path(), Some("run.quadrature"), "{e}");
    assert!(e.to_string().contains(&MAX_QUADRATURE.to_string()), "{e}");
    Scene::from_str(
        &edit("quadrature = 4", &format!("quadrature = {MAX_QUADRATURE}")),
        "case.toml",
    )
    .unwrap();
}

/// A long `initial.q` of the wrong length is rejected with the count, and
/// a NaN far inside it is still found (element spans are recorded only for
/// the first elements; the search for non-finite values covers all).
#[test]
fn long_initial_arrays_are_rejected_by_length_and_scanned_for_nan() {
    let n = 200_000;
    let mut values = vec!["0.0"; n];
    let text = format!("{BASE}\n[initial]\nq = [{}]\n", values.join(", "));
    let e = error_of(&text);
    assert_eq!(e.path(), Some("initial.q"), "{e}");
    assert!(e.to_string().contains(&n.to_string()), "{e}");
    values[150_000] = "nan";
    let e = error_of(&format!("{BASE}\n[initial]\nq = [{}]\n", values.join(", ")));
    assert_eq!(e.path(), Some("initial.q[150000]"), "{e}");
}
