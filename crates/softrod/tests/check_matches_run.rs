//! What a run refuses or warns about at its start, reading the scene
//! already warns about, in the same words (issue 26): the scene check and
//! the run's watch apply one rule (`softrod_mechanics::validity`) and
//! format its findings the same way — only "in the initial state" and
//! "at t = 0e0 s" differ.

use softrod::{Error, Flow, Observer, Sample, Simulation};

const D03A: &str = include_str!("fixtures/D03a_check_ok_shape_fit_inverted_piece.toml");

struct Discard;
impl Observer for Discard {
    fn sample(&mut self, _: Sample<'_>) -> Result<Flow, String> {
        Ok(Flow::Continue)
    }
}

/// `(headline, details)` of a message `"{headline} {when}: rod {details}"`.
fn split<'a>(message: &'a str, when: &str) -> (&'a str, &'a str) {
    let (head, rest) = message
        .split_once(when)
        .unwrap_or_else(|| panic!("{message}"));
    let details = rest
        .strip_prefix(": ")
        .unwrap_or_else(|| panic!("{message}"));
    (head.trim_end(), details)
}

/// D03a: the run fails at t = 0 on a folded piece; the scene said so.
#[test]
fn a_folded_initial_shape_is_refused_by_run_as_the_scene_warned() {
    let (mut sim, _, warnings) = Simulation::from_toml(D03A, "d03a.toml").unwrap();
    let w = warnings
        .iter()
        .find(|w| w.message.starts_with("stretch not positive"))
        .expect("the scene warns");
    let e = sim.simulate_with(0.01, &mut Discard).unwrap_err();
    assert!(matches!(e, Error::Stretch { t: 0.0, .. }), "{e}");
    let run = e.to_string();
    let (head_w, details_w) = split(&w.message, "in the initial state");
    let (head_r, details_r) = split(&run, "at t = 0e0 s");
    assert_eq!(head_w, head_r);
    // The run adds a cause after ";", the scene a consequence after ":".
    let (finding_w, _) = details_w.split_once("):").unwrap();
    let (finding_r, _) = details_r.split_once(';').unwrap();
    assert_eq!(finding_w, finding_r);
}

const ROD: &str = r#"
[[rod]]
name = "a"
length = 0.3
pieces = 4
strains = ["ky", "kz", "qx"]
section = { shape = "circle", radius = 0.008 }
material = { density = 1100.0, young = 1.0e6, poisson = 0.5, viscosity = 500.0 }
[run]
output_every = 1e-4
"#;

/// Strains that the run warns about at t = 0 (a stretch of 3 from a shape,
/// a bend tighter than the section from `initial.q`): the scene's warning
/// and the run's say the same after their time.
#[test]
fn initial_strains_beyond_validity_are_warned_about_in_the_run_words() {
    let cases = [
        (
            "[initial]\nshape = [{ rod = \"a\", centerline = [[0,0,0],[0.45,0,0],[0.9,0,0]] }]\n",
            "strain beyond the model's validity",
        ),
        (
            "[initial]\nq = [150, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]\n",
            "curvature beyond the model's validity",
        ),
    ];
    for (initial, head) in cases {
        let text = format!("{ROD}{initial}");
        let (mut sim, _, warnings) = Simulation::from_toml(&text, "t.toml").unwrap();
        let w = warnings
            .iter()
            .find(|w| w.message.starts_with(head))
            .unwrap_or_else(|| panic!("{head}: {warnings:?}"));
        let sum = sim.simulate_with(1e-4, &mut Discard).unwrap();
        let r = sum
            .warnings
            .iter()
            .find(|w| w.starts_with(head))
            .unwrap_or_else(|| panic!("{head}: {:?}", sum.warnings));
        assert_eq!(
            split(&w.message, "in the initial state"),
            split(r, "at t = 0e0 s"),
            "{head}"
        );
    }
}
