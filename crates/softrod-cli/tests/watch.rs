//! `softrod run` and the physics watch (issue 15): the energy balance in
//! summary.json, exit 1 when it is violated, exit 2 when the task cannot
//! fit in memory.

use std::path::{Path, PathBuf};

mod common;
use common::*;

/// The example (`dir/NAME`) with its `[run]` table replaced, and
/// `pieces = 8` replaced by `pieces`.
fn scene(example: &str, run_table: &str, pieces: Option<&str>, dir: &Path) -> PathBuf {
    let mut text = example_with_run(example, run_table);
    if let Some(p) = pieces {
        text = text.replacen("pieces = 8", p, 1);
    }
    let p = dir.join(example.rsplit('/').next().unwrap());
    std::fs::write(&p, text).unwrap();
    p
}

fn summary(out: &Path) -> serde_json::Value {
    json_file(&out.join("summary.json"))
}

#[test]
fn a_violated_energy_balance_exits_1_and_says_so() {
    let dir = tmp("violated");
    let s = scene(
        "extreme/fast_whirl.toml",
        "[run]\nduration = 0.05\nintegrator = \"dopri5\"\nrtol = 0.1\natol = 0.1\noutput_every = 0.01",
        None,
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&s, &out);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = summary(&out);
    let status = v["status"].as_str().unwrap();
    assert!(
        status.starts_with("error: energy balance violated at t = "),
        "{v}"
    );
    assert!(v["energy_error_relative"].as_f64().unwrap() > 0.1, "{v}");
}

#[test]
fn a_tight_run_reports_its_balance() {
    let dir = tmp("tight");
    let s = scene(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.05\nintegrator = \"dopri5\"\nrtol = 1e-9\natol = 1e-12\noutput_every = 0.01",
        None,
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&s, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v = summary(&out);
    assert_eq!(v["status"], "ok");
    assert!(v["energy_error_relative"].as_f64().unwrap() < 1e-5, "{v}");
    assert!(v["energy_scale"].as_f64().unwrap() > 0.0, "{v}");
    assert_eq!(v["warnings"], serde_json::json!([]), "{v}");
}

#[test]
fn a_run_too_large_for_the_machine_exits_2_naming_the_key() {
    let dir = tmp("large");
    let s = scene(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.001\nintegrator = \"rosenbrock\"",
        Some("pieces = 100000"),
        &dir,
    );
    let o = run_scene(&s, &dir.join("out"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("rod[0].pieces") && err.contains("GB"), "{err}");
    // `check` refuses what `run` would, with the same message.
    let c = run(&["check", s.to_str().unwrap()]);
    assert_eq!(c.status.code(), Some(2));
    let first = |t: &str| {
        t.lines()
            .find(|l| l.contains("need about"))
            // The free memory moves between the two commands.
            .and_then(|l| l.split(" but ").next())
            .map(str::to_owned)
    };
    assert_eq!(first(&String::from_utf8_lossy(&c.stderr)), first(&err));
}

/// The issue's case: rk4 with dt = 1 s over 0.05 s was `ok` with a tip
/// 6.3 m from the clamp of a 0.5 m rod.
#[test]
fn one_unstable_rk4_step_is_not_ok() {
    let dir = tmp("rk4");
    let s = scene(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.05\nintegrator = \"rk4\"\ndt = 1.0\noutput_every = 0.01",
        None,
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&s, &out);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v = summary(&out);
    assert!(
        v["status"]
            .as_str()
            .unwrap()
            .starts_with("error: energy balance violated at t = "),
        "{v}"
    );
}

/// A fuzzed scene (a one-piece rod fitted to a point 100 lengths away: a
/// bend of radius 8e-8 m, warned about) on which rk4 at dt 5e-5 diverges
/// within its first step: the dynamics at the watch's midpoint state is NaN.
/// That is a failed run (exit 1, "error:"), not a refused input (exit 2,
/// "refused:"), which it used to be reported as.
#[test]
fn a_step_that_diverges_is_an_error_not_a_refusal() {
    let dir = tmp("diverge");
    let s = dir.join("scene.toml");
    std::fs::write(
        &s,
        r#"[[rod]]
name = "r0"
length = 0.02
pieces = 1
strains = ["ky", "qz"]
section = { shape = "circle", radius = 0.008 }
material = { density = 1100.0, young = 1.0e6, poisson = 0.5, viscosity = 500.0 }
rest_strain = [0, 3, 0, 1, 0.7, 0]
joint = { type = "revolute", axis = [0, 1, 0], prescribed = { times = [0, 0.01], values = [0, 0.5] } }
[world]
gravity = [0.0, 0.0, -9.81]
[initial]
shape = [{ rod = "r0", centerline = [[0,0,0], [-1.8910282922396568e0, 1.2229680187320713e0, 3.0524942036876673e-1]] }]
[run]
duration = 0.0001
output_every = 0.00005
integrator = "rk4"
dt = 5e-5
"#,
    )
    .unwrap();
    let out = dir.join("out");
    let o = run_scene(&s, &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    let status = summary(&out)["status"].as_str().unwrap().to_owned();
    assert!(status.starts_with("error: "), "{status}");
    assert!(
        status.contains("is not finite (NaN) at a finite state"),
        "{status}"
    );
}

/// Outputs that cannot fit on the disk are refused before anything is
/// written (exit 2, naming `run.output_every` and the sizes): 1e8 output
/// times of a 24-DoF rod and its 65 shape samples need almost a terabyte.
#[test]
fn outputs_larger_than_the_disk_are_refused_up_front() {
    let dir = tmp("disk-full-estimate");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 100.0\noutput_every = 1e-6\n",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run.output_every") && err.contains("on disk"),
        "{err}"
    );
    assert!(!out.join("trajectory.csv").exists(), "nothing written");
    // `check` warns of it in the same words (issue 26: what `run` refuses
    // at its start, `check` reports).
    let c = run(&["check", scene.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&c.stdout);
    assert!(
        said.contains("`run` would refuse this") && said.contains("on disk"),
        "{said}"
    );
}

/// The disk estimate counts every file a run writes, not only
/// trajectory.csv (D07: shape.csv is most of it): `check`'s "at least"
/// is a lower bound of what a run writes, and not a loose one.
#[test]
fn the_disk_estimate_bounds_every_output_from_below() {
    let dir = tmp("disk-estimate");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.5\noutput_every = 2.5e-4\n",
        &dir,
    );
    let c = run(&["check", scene.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&c.stdout).into_owned();
    let mb: f64 = said
        .lines()
        .find_map(|l| l.split("at least ").nth(1))
        .and_then(|r| r.strip_suffix(" MB on disk (CSV files)"))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("{said}"));
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let written: u64 = ["trajectory.csv", "shape.csv"]
        .iter()
        .map(|f| std::fs::metadata(out.join(f)).unwrap().len())
        .sum();
    let written = written as f64 / 1e6;
    assert!(
        mb <= written && written <= 2.0 * mb,
        "estimate {mb} MB, written {written} MB"
    );
}
