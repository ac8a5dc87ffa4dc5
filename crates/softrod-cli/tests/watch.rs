//! `softrod run` and the physics watch (issue 15): the energy balance in
//! summary.json, exit 1 when it is violated, exit 2 when the task cannot
//! fit in memory.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("softrod-cli-watch")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The example (`dir/NAME`) with its `[run]` table replaced, and
/// `pieces = 8` replaced by `pieces`.
fn scene(example: &str, run_table: &str, pieces: Option<&str>, dir: &Path) -> PathBuf {
    let mut text = std::fs::read_to_string(examples().join(example)).unwrap();
    let cut = text.find("[run]").unwrap_or(text.len());
    text = format!("{}{run_table}\n", &text[..cut]);
    if let Some(p) = pieces {
        text = text.replacen("pieces = 8", p, 1);
    }
    let p = dir.join(example.rsplit('/').next().unwrap());
    std::fs::write(&p, text).unwrap();
    p
}

fn run(scene: &Path, out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap()
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
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
    let o = run(&s, &out);
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
    let o = run(&s, &out);
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
    let o = run(&s, &dir.join("out"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("rod[0].pieces") && err.contains("GB"), "{err}");
    // `check` refuses what `run` would, with the same message.
    let c = Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(["check", s.to_str().unwrap()])
        .output()
        .unwrap();
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

/// The case: rk4 with dt = 1 s over 0.05 s was `ok` with a tip
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
    let o = run(&s, &out);
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

/// Outputs that cannot fit on the disk are refused before anything is
/// written (exit 2, naming `run.output_every` and the sizes): 1e9 output
/// times of a 24-DoF rod need more than a terabyte.
#[test]
fn outputs_larger_than_the_disk_are_refused_up_front() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("disk-full-estimate");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/cantilever_gravity.toml"
    ))
    .unwrap();
    let cut = text.find("[run]").unwrap();
    let scene = dir.join("huge.toml");
    std::fs::write(
        &scene,
        format!(
            "{}[run]\nduration = 1000.0\noutput_every = 1e-6\n",
            &text[..cut]
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("run.output_every") && err.contains("on disk"),
        "{err}"
    );
    assert!(!out.join("trajectory.csv").exists(), "nothing written");
}
