//! A fuzz target over scenes (issue 26): proptest-generated TOML — legal,
//! extreme and malformed values, bodies, joints, closures, loads, cables,
//! initial states and shapes — through parse, validation, model building,
//! the run's admission check and the first steps of a run. For every
//! case:
//!
//! - nothing panics, and each case ends within a watchdog's bound (a
//!   generous 120 s for a case that takes milliseconds: a hang, not a
//!   slow machine);
//! - a scene that is accepted (parsed, built, admitted by `check_run`)
//!   without a warning that `run` fails at its start, does not fail at
//!   its start: the first steps of a run report no input error and no
//!   folded piece at t = 0. (Later failures — a blow-up, an energy
//!   violation — are physics, not admission.)
//!
//! Bounded in the normal suite: `FUZZ_CASES` cases (default 256, well under
//! a second; most scenes are small and the run is two rk4 steps). Longer
//! campaigns: `FUZZ_CASES=100000 cargo-lock test -p softrod --test
//! fuzz_scenes` (4000 cases take ~4 s); `FUZZ_VERBOSE=1` prints, per
//! case, what the scene check said (`refused: …` or `accepted, N
//! warnings`), to see that the generator reaches accepted scenes. A
//! failure prints the shrunk scene's TOML. Mutation-checked: with the
//! folded-piece warning silenced, the target fails within 300 cases on a
//! scene whose `initial.q` folds a piece.

use std::sync::mpsc;
use std::time::Duration;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use softrod::{Error, Flow, Observer, Sample, Simulation};
use softrod_scene::Integrator;

fn pick<T: Clone + std::fmt::Debug + 'static>(v: &[T]) -> impl Strategy<Value = T> + use<T> {
    proptest::sample::select(v.to_vec())
}

/// Mostly one of `good`, sometimes one of `bad` (each bad value refuses
/// the scene, so they are rare enough that most scenes get through).
fn mostly(good: &[&'static str], bad: &[&'static str]) -> BoxedStrategy<&'static str> {
    if bad.is_empty() {
        return pick(good).boxed();
    }
    prop_oneof![24 => pick(good), 1 => pick(bad)].boxed()
}

fn num() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-3.0f64..3.0).prop_map(|x| format!("{x:e}")),
        1 => pick(&["0.0", "-1.0", "1e9", "1e-12", "2.5", "0.3"]).prop_map(str::to_owned),
    ]
}

fn rod(i: usize) -> impl Strategy<Value = String> {
    (
        mostly(&["0.3", "0.1", "1.0", "0.02"], &["-0.1", "0"]),
        mostly(&["1", "2", "4", "6"], &["0", "-2"]),
        mostly(
            &[
                "\"all\"",
                "[\"ky\", \"kz\", \"qx\"]",
                "[\"qx\"]",
                "[\"kx\", \"ky\"]",
                "[\"qz\", \"ky\"]",
            ],
            &["\"al\"", "[]"],
        ),
        mostly(
            &[
                "{ shape = \"circle\", radius = 0.008 }",
                "{ shape = \"circle\", radius = 0.05 }",
                "{ shape = \"tube\", radius = 0.01, inner_radius = 0.006 }",
                "{ shape = \"rectangle\", width = 0.02, height = 0.01 }",
                "{ shape = \"circle\", radius_base = 0.01, radius_tip = 0.004 }",
            ],
            &[
                "{ shape = \"circle\", radius = -1 }",
                "{ shape = \"oval\", radius = 0.01 }",
            ],
        ),
        mostly(
            &[
                "{ density = 1100.0, young = 1.0e6, poisson = 0.5, viscosity = 500.0 }",
                "{ density = 1000.0, young = 1.0e7, poisson = 0.45 }",
                "{ density = 7800.0, young = 2.0e11, shear_modulus = 8.0e10 }",
            ],
            &["{ density = 1000.0, young = 0.0, poisson = 0.5 }"],
        ),
        mostly(
            &[
                "",
                "",
                "rest_strain = [0, 200, 0, 1, 0, 0]\n",
                "rest_strain = [0, 3, 0, 1, 0.7, 0]\n",
                "rest_strain = [0, 0, 0, 2, 0, 0]\n",
            ],
            &["rest_strain = [0, 0, 0, 0, 0, 0]\n"],
        ),
        mostly(
            &[
                "",
                "",
                "joint = { type = \"revolute\", axis = [0, 1, 0] }\n",
                "joint = { type = \"prismatic\", axis = [0, 0, 1], stiffness = 10.0 }\n",
                "joint = { type = \"spherical\" }\n",
                "joint = { type = \"free\" }\n",
                "joint = { type = \"universal\", axes = [[0,1,0],[0,0,1]] }\n",
                "joint = { type = \"revolute\", axis = [0, 1, 0], prescribed = { times = [0, 0.01], values = [0, 0.5] } }\n",
            ],
            &[
                "joint = { type = \"helical\", axis = [0, 0, 1] }\n",
                "joint = { type = \"fixed\", axis = [1, 0, 0] }\n",
            ],
        ),
        mostly(&["", "parent = \"r0\"\n", "parent = \"p\"\n"], &["parent = \"nobody\"\n"]),
    )
        .prop_map(move |(len, pieces, strains, section, material, rest, joint, parent)| {
            let parent = if i == 0 { "" } else { parent };
            format!(
                "[[rod]]\nname = \"r{i}\"\nlength = {len}\npieces = {pieces}\nstrains = {strains}\n\
                 section = {section}\nmaterial = {material}\n{rest}{joint}{parent}"
            )
        })
}

fn extras() -> impl Strategy<Value = String> {
    let body = mostly(
        &[
            "",
            "",
            "[[body]]\nname = \"p\"\nparent = \"r0\"\nmass = 0.05\ninertia = [2e-6, 2e-6, 2e-6]\n",
            "[[body]]\nname = \"p\"\nparent = \"r0\"\nmass = 0.05\ninertia = [1e-6, 1e-6, 2e-6]\njoint = { type = \"revolute\", axis = [1, 0, 0] }\n",
        ],
        &[
            "[[body]]\nname = \"p\"\nparent = \"r0\"\nmass = 0.05\ninertia = [1e-6, 1e-6, 3e-6]\n",
            "[[body]]\nname = \"p\"\nparent = \"world\"\nmass = 0.0\ninertia = [1e-6, 1e-6, 1e-6]\n",
        ],
    );
    let closure = mostly(
        &[
            "",
            "",
            "",
            "[[closure]]\ntype = \"ball\"\na = { element = \"r0\", at = 0.0 }\nb = { element = \"world\" }\n",
            "[[closure]]\ntype = \"slider\"\naxis = [1, 0, 0]\na = { element = \"r0\" }\nb = { element = \"world\" }\n",
        ],
        &[
            "[[closure]]\ntype = \"weld\"\na = { element = \"r0\" }\nb = { element = \"r0\" }\n",
            "[[closure]]\ntype = \"weld\"\na = { element = \"r0\", at = 0.0 }\nb = { element = \"world\" }\n",
            "[[closure]]\ntype = \"glue\"\na = { element = \"r0\" }\nb = { element = \"world\" }\n",
        ],
    );
    let load = mostly(
        &[
            "",
            "",
            "[[load]]\nrod = \"r0\"\ns = 0.01\nforce = [0, 0, -1]\n",
            "[[load]]\nrod = \"r0\"\ns = 0.01\nforce = [0, 0, -1e6]\nframe = \"body\"\n",
        ],
        &[
            "[[load]]\nbody = \"p\"\nforce = [0, 0, -1]\n",
            "[[load]]\nrod = \"r0\"\ns = 5.0\nforce = [0, 0, -1]\n",
            "[[load]]\nrod = \"r0\"\ns = 0.01\nforce = [0, 0, -1]\nframe = \"sideways\"\n",
        ],
    );
    let cable = mostly(
        &[
            "",
            "",
            "[[cable]]\nrod = \"r0\"\noffset = [0.0, 0.005]\ntension = 2.0\n",
        ],
        &["[[cable]]\nrod = \"r0\"\noffset = [0.0, 0.005]\ntension = -2.0\n"],
    );
    let gravity = pick(&[
        "",
        "[world]\ngravity = [0.0, 0.0, -9.81]\n",
        "[world]\ngravity = [1e4, 0, 0]\n",
    ]);
    (body, closure, load, cable, gravity).prop_map(|(a, b, c, d, e)| format!("{e}{a}{b}{c}{d}"))
}

fn initial() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => Just(String::new()),
        // Resized to the scene's n_dof in `one` (a wrong length is a
        // malformed-input test of its own).
        3 => proptest::collection::vec(num(), 1..30)
            .prop_map(|q| format!("[initial]\nq = [{}]\n", q.join(", "))),
        2 => proptest::collection::vec((num(), num(), num()), 1..7).prop_map(|pts| {
            let rows: Vec<String> = pts
                .iter()
                .map(|(x, y, z)| format!("[{x}, {y}, {z}]"))
                .collect();
            format!(
                "[initial]\nshape = [{{ rod = \"r0\", centerline = [[0,0,0], {}] }}]\n",
                rows.join(", ")
            )
        }),
        1 => Just("[initial]\nshape = [{ rod = \"r0\", centerline = [[0,0,0],[0.15,0,0],[0.15,0,0]] }]\n".to_owned()),
        1 => Just("[initial]\nshape = [{ rod = \"r0\", centerline = [[0,0,0],[0.15,0,0],[0.0,0,0.0001]] }]\n".to_owned()),
    ]
}

fn scene() -> impl Strategy<Value = String> {
    (rod(0), proptest::option::of(rod(1)), extras(), initial()).prop_map(|(a, b, x, i)| {
        format!(
            "{a}{}{x}{i}[run]\nduration = 0.01\noutput_every = 0.005\n",
            b.unwrap_or_default()
        )
    })
}

struct Discard;
impl Observer for Discard {
    fn sample(&mut self, _: Sample<'_>) -> Result<Flow, String> {
        Ok(Flow::Continue)
    }
}

/// `[initial] q = […]` cycled to the scene's `n_dof` (read from the scene
/// without it); other texts unchanged.
fn with_q_of_the_right_length(text: &str) -> String {
    let Some((base, q)) = text.split_once("[initial]\nq = [") else {
        return text.to_owned();
    };
    let (values, rest) = q.split_once("]\n").unwrap();
    let Ok((scene, _)) = softrod_scene::Scene::from_str(&format!("{base}{rest}"), "fuzz.toml")
    else {
        return text.to_owned();
    };
    let values: Vec<&str> = values.split(", ").collect();
    let q: Vec<&str> = (0..scene.n_dof())
        .map(|i| values[i % values.len()])
        .collect();
    format!("{base}[initial]\nq = [{}]\n{rest}", q.join(", "))
}

/// What happened to one scene; `Err` is a broken property.
fn one(text: &str) -> Result<(), String> {
    let (mut sim, _, warnings) = match Simulation::from_toml(text, "fuzz.toml") {
        Ok(x) => x,
        Err(e) => {
            if std::env::var("FUZZ_VERBOSE").is_ok() {
                eprintln!("refused: {e}");
            }
            return Ok(()); // Refused with a message, not a panic.
        }
    };
    if std::env::var("FUZZ_VERBOSE").is_ok() {
        eprintln!("accepted, {} warnings", warnings.len());
    }
    if sim.check_run(1e-4).is_err() {
        return Ok(());
    }
    let warned = warnings
        .iter()
        .any(|w| w.message.contains("`run` fails at its start"));
    // Two fixed steps of rk4: the start and a step, bounded work.
    let mut settings = sim.settings().clone();
    settings.integrator = Integrator::Rk4;
    settings.dt = 5e-5;
    settings.output_every = Some(5e-5);
    sim.set_settings(settings)
        .map_err(|e| format!("settings: {e}"))?;
    match sim.simulate_with(1e-4, &mut Discard) {
        Err(Error::Stretch { t, .. }) if t == 0.0 && !warned => {
            Err("accepted, then the run failed at t = 0 on a folded piece".into())
        }
        Err(e) if e.is_input() => Err(format!("accepted, then the run refused it: {e}")),
        _ => Ok(()),
    }
}

#[test]
fn scenes_never_panic_hang_or_pass_what_fails_at_the_start() {
    let cases = std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256);
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(&scene(), |text| {
            let text = with_q_of_the_right_length(&text);
            let (tx, rx) = mpsc::channel();
            let t = text.clone();
            let worker = std::thread::spawn(move || {
                let _ = tx.send(std::panic::catch_unwind(|| one(&t)));
            });
            match rx.recv_timeout(Duration::from_secs(120)) {
                Ok(Ok(Ok(()))) => {
                    worker.join().ok();
                    Ok(())
                }
                Ok(Ok(Err(m))) => Err(TestCaseError::fail(format!("{m}\n---\n{text}"))),
                Ok(Err(_)) => Err(TestCaseError::fail(format!("panicked on\n---\n{text}"))),
                Err(_) => Err(TestCaseError::fail(format!(
                    "no answer in 120 s\n---\n{text}"
                ))),
            }
        })
        .unwrap();
}
