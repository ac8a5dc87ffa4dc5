//! What `run` would refuse or fail at its start is refused or warned about
//! when the scene is read (issue 26): initial and rest strains through the
//! one validity rule (`softrod_mechanics::validity`), shape fits, closures
//! that hold nothing, impossible inertias, and messages that name what is
//! wrong. The reproducing scenes of the issue are the fixtures `D…`.

use softrod_scene::{Scene, Warning};

const D03A: &str = include_str!("fixtures/D03a_check_ok_shape_fit_inverted_piece.toml");
const D04: &str = include_str!("fixtures/D04_shape_fit_fails_representable_coil.toml");
const D10: &str = include_str!("fixtures/D10_closure_frame_with_itself_accepted.toml");
const D11: &str = include_str!("fixtures/D11_unknown_joint_type_wrong_message.toml");

fn warnings(text: &str) -> Vec<Warning> {
    Scene::from_str(text, "t.toml")
        .unwrap_or_else(|e| panic!("{e}"))
        .1
}

fn error(text: &str) -> softrod_scene::SceneError {
    Scene::from_str(text, "t.toml").unwrap_err()
}

const ROD: &str = r#"
[[rod]]
name = "a"
length = 0.3
pieces = 4
strains = ["ky", "kz", "qx"]
section = { shape = "circle", radius = 0.008 }
material = { density = 1100.0, young = 1.0e6, poisson = 0.5 }
"#;

/// D03a: three points that fold the rod back on itself. The fit gives an
/// inverted piece; `check` used to say "warnings: none" and `run` failed
/// at t = 0. Now the scene warns, in the run's words.
#[test]
fn a_shape_that_folds_the_rod_is_warned_about() {
    let w = warnings(D03A);
    let folded: Vec<_> = w
        .iter()
        .filter(|w| {
            w.message
                .starts_with("stretch not positive in the initial state")
        })
        .collect();
    assert_eq!(folded.len(), 1, "{w:?}");
    assert_eq!(folded[0].path, "initial.shape[0]");
    assert!(
        folded[0].message.contains("rod \"a\" piece ")
            && folded[0].message.contains("(the rod folded onto itself)")
            && folded[0].message.ends_with("`run` fails at its start"),
        "{}",
        folded[0].message
    );
    // The state it warns about is the one `build` starts from: a piece
    // of stretch ≤ 0 there, checked here without the validity module.
    let (scene, _) = Scene::from_str(D03A, "t.toml").unwrap();
    let b = scene.build().unwrap();
    let rod = &b.model.rods()[0].spec.geometry;
    assert!(
        (0..rod.n_pieces()).any(|n| rod.strain(n, b.q0.as_slice())[3] <= 0.0),
        "{:?}",
        b.q0
    );
}

/// The same q written as `initial.q` is warned about the same way.
#[test]
fn the_same_state_as_initial_q_is_warned_about_alike() {
    let (scene, _) = Scene::from_str(D03A, "t.toml").unwrap();
    let q = scene.build().unwrap().q0;
    let list: Vec<String> = q.iter().map(|v| format!("{v:e}")).collect();
    let text = D03A.replace(
        "shape = [ { rod = \"a\", centerline = [[0,0,0],[0.15,0,0],[0.0,0,0.0001]] } ]",
        &format!("q = [{}]", list.join(", ")),
    );
    let by_q = warnings(&text);
    let by_shape = warnings(D03A);
    let head = |w: &[Warning]| {
        w.iter()
            .find(|w| w.message.starts_with("stretch not positive"))
            .map(|w| w.message.clone())
    };
    assert_eq!(head(&by_q), head(&by_shape), "{by_q:?}\n{by_shape:?}");
    let w = by_q
        .iter()
        .find(|w| w.message.starts_with("stretch not positive"))
        .unwrap();
    assert!(w.path.starts_with("initial.q["), "{}", w.path);
}

/// A shape three times as long as the rod: a stretch of 3 everywhere,
/// beyond the model's validity.
#[test]
fn a_shape_stretched_three_times_is_warned_about() {
    let text = format!(
        "{ROD}[initial]\nshape = [{{ rod = \"a\", centerline = [[0,0,0],[0.45,0,0],[0.9,0,0]] }}]\n"
    );
    let w = warnings(&text);
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].path, "initial.shape[0]");
    assert!(
        w[0].message.starts_with(
            "strain beyond the model's validity in the initial state: rod \"a\" piece 0 has \
             stretch 3.000"
        ),
        "{}",
        w[0].message
    );
}

/// Repeated consecutive points would need a zero stretch: an input error
/// naming the key and the index.
#[test]
fn repeated_centreline_points_are_an_error() {
    let text = format!(
        "{ROD}[initial]\nshape = [{{ rod = \"a\", centerline = [[0,0,0],[0.1,0,0],[0.1,0,0],[0.3,0,0]] }}]\n"
    );
    let e = error(&text);
    assert_eq!(e.path(), Some("initial.shape[0].centerline[2]"), "{e}");
    assert!(e.to_string().contains("repeats point 1"), "{e}");
    // With [s, x, y, z] rows too.
    let text = format!(
        "{ROD}[initial]\nshape = [{{ rod = \"a\", centerline = [[0,0,0,0],[0.2,0.1,0,0],[0.3,0.1,0,0]] }}]\n"
    );
    assert_eq!(error(&text).path(), Some("initial.shape[0].centerline[2]"));
}

/// D04: a 20-turn coil that 40 pieces take exactly is fitted exactly (it
/// was fitted to a piece at stretch −3215): no warning about the fit or
/// the stretch, and every piece has stretch 1. The coil's radius, 2.4 mm,
/// is less than the rod's, 8 mm: that the scene says, in the words the
/// run's watch uses.
#[test]
fn the_representable_coil_is_fitted_exactly() {
    let (scene, w) = Scene::from_str(D04, "t.toml").unwrap();
    let paths: Vec<&str> = w.iter().map(|w| w.path.as_str()).collect();
    assert_eq!(paths, ["rod[0].pieces", "initial.shape[0]"], "{w:?}");
    assert!(
        w[1].message.starts_with(
            "curvature beyond the model's validity in the initial state: rod \"a\" piece 0 \
             bends with radius 2.387e-3 m"
        ),
        "{}",
        w[1].message
    );
    let b = scene.build().unwrap();
    assert!(b.shape_fits[0].max < 1e-12, "{:?}", b.shape_fits);
    let rod = &b.model.rods()[0].spec.geometry;
    for n in 0..rod.n_pieces() {
        let xi = rod.strain(n, b.q0.as_slice());
        assert!((xi[3] - 1.0).abs() < 1e-9, "piece {n}: {xi:?}");
        // A half turn per piece: |κ| ℓ = π.
        assert!(
            (xi[1].hypot(xi[2]) * 0.0075 - std::f64::consts::PI).abs() < 1e-9,
            "piece {n}: {xi:?}"
        );
    }
}

/// A shape the rod cannot take (a right angle with straight legs, two
/// pieces of bending only) is fitted as well as it can be, and the scene
/// says by how much it misses.
#[test]
fn a_shape_out_of_reach_is_warned_about_with_its_residual() {
    let text = format!(
        "{}[initial]\nshape = [{{ rod = \"a\", centerline = [[0,0,0],[0.05,0,0],[0.1,0,0],[0.15,0,0],[0.15,0,0.05],[0.15,0,0.1],[0.15,0,0.15]] }}]\n",
        ROD.replace("pieces = 4", "pieces = 2")
    );
    let w = warnings(&text);
    let fit: Vec<_> = w
        .iter()
        .filter(|w| w.path == "initial.shape[0].centerline")
        .collect();
    assert_eq!(fit.len(), 1, "{w:?}");
    assert!(
        fit[0].message.contains("more than 1% of its length"),
        "{}",
        fit[0].message
    );
}

/// D10: a weld of a rod's tip to itself holds nothing (0 independent
/// constraints): an error naming the closure.
#[test]
fn a_closure_of_a_frame_with_itself_is_an_error() {
    let e = error(D10);
    assert_eq!(e.path(), Some("closure[0]"), "{e}");
    let m = e.to_string();
    assert!(
        m.contains("closure \"closure[0]\" holds a frame to itself")
            && m.contains("0 independent constraints"),
        "{m}"
    );
}

/// Frames that cannot move apart although they are spelled differently:
/// a rod's base (s = 0) welded to the world where it is clamped. The
/// constraint Jacobian has rank 0 there.
#[test]
fn a_closure_whose_frames_cannot_move_apart_is_an_error() {
    let text = format!(
        "{ROD}[[closure]]\nname = \"stuck\"\ntype = \"weld\"\na = {{ element = \"a\", at = 0.0 }}\n\
         b = {{ element = \"world\" }}\n"
    );
    let e = error(&text);
    assert_eq!(e.path(), Some("closure[0]"), "{e}");
    assert!(
        e.to_string()
            .contains("closure \"stuck\" has 0 independent constraints"),
        "{e}"
    );
    // The same closure at the tip holds the tip: accepted.
    let ok = text.replace("at = 0.0", "at = 0.3").replace(
        "b = { element = \"world\" }",
        "b = { element = \"world\", base = { position = [0.3, 0, 0] } }",
    );
    warnings(&ok);
}

/// A rest curvature whose radius is below the section's radius puts the
/// centre of curvature inside the section: warned at the rest strain, in
/// the run watch's words.
#[test]
fn a_rest_curvature_inside_the_section_is_warned_about() {
    // κ_y = 200 1/m: radius 5 mm < 8 mm.
    let text = ROD.replace(
        "strains = [",
        "rest_strain = [0, 200, 0, 1, 0, 0]\nstrains = [",
    );
    let w = warnings(&text);
    assert_eq!(w.len(), 1, "{w:?}");
    assert_eq!(w[0].path, "rod[0].rest_strain");
    assert_eq!(
        w[0].message,
        "curvature beyond the model's validity at rest: rod \"a\" piece 0 bends with radius \
         5.000e-3 m, less than the section's half size 8.000e-3 m (the section would overlap \
         itself)"
    );
    // At 100 1/m (radius 10 mm): nothing to say.
    assert!(warnings(&text.replace("200", "100")).is_empty());
}

/// Principal moments that break the triangle inequality are no body.
#[test]
fn an_impossible_inertia_is_an_error() {
    let body = |inertia: &str| {
        format!("{ROD}[[body]]\nname = \"p\"\nparent = \"a\"\nmass = 0.1\ninertia = {inertia}\n")
    };
    let e = error(&body("[1e-5, 1e-5, 3e-5]"));
    assert_eq!(e.path(), Some("body[0].inertia"), "{e}");
    assert!(e.to_string().contains("triangle inequality"), "{e}");
    // As a rotated matrix too (eigenvalues 1, 1, 3 × 1e-5).
    let e = error(&body("[[2e-5, 1e-5, 0], [1e-5, 2e-5, 0], [0, 0, 1e-5]]"));
    assert_eq!(e.path(), Some("body[0].inertia"), "{e}");
    // A thin disk meets it with equality: a body.
    warnings(&body("[2.5e-6, 2.5e-6, 5e-6]"));
}

/// D11: an unknown joint type is named as such, with the valid ones — it
/// was reported as "a helical joint has no axis".
#[test]
fn an_unknown_joint_type_is_named() {
    let e = error(D11);
    assert_eq!(e.path(), Some("rod[0].joint.type"), "{e}");
    let m = e.to_string();
    assert!(
        m.contains("unknown value \"helical\" (valid: fixed, revolute, prismatic"),
        "{m}"
    );
}

/// A load naming a body in a scene without bodies says there are none
/// (it listed "(valid: )").
#[test]
fn a_missing_body_in_a_scene_without_bodies_says_so() {
    let e = error(&format!(
        "{ROD}[[load]]\nbody = \"plate\"\nforce = [0, 0, -1]\n"
    ));
    assert_eq!(e.path(), Some("load[0].body"), "{e}");
    let m = e.to_string();
    assert!(m.contains("there are no bodies"), "{m}");
    assert!(!m.contains("(valid: )"), "{m}");
}

/// `strains = "al"` names both spellings that are valid.
#[test]
fn an_unknown_strains_word_names_both_forms() {
    let e = error(&ROD.replace("strains = [\"ky\", \"kz\", \"qx\"]", "strains = \"al\""));
    assert!(
        e.to_string()
            .contains("(valid: \"all\", or a list of kx, ky, kz, qx, qy, qz)"),
        "{e}"
    );
}
