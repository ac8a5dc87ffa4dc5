//! Helpers shared by the CLI's integration tests (`tests/*.rs`): running the
//! binary, scratch directories, example scenes with their `[run]` table
//! replaced, and reading the CSV and JSON the binary writes.
//!
//! Each test file compiles this module on its own and uses only part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `softrod` binary under test.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_softrod"))
}

/// `softrod ARGS…`, waited for.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("runs the binary")
}

/// `softrod run SCENE --out OUT --quiet`.
pub fn run_scene(scene: &Path, out: &Path) -> Output {
    run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ])
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The repository's `examples/` directory.
pub fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// A fresh, empty scratch directory `NAME`, private to this test file (one
/// parent per test binary, so two files may use the same name).
pub fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(concat!("softrod-cli-", env!("CARGO_CRATE_NAME")))
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The text of `examples/EXAMPLE` with its `[run]` table (and everything
/// after it) replaced by `run_table`.
pub fn example_with_run(example: &str, run_table: &str) -> String {
    let text = std::fs::read_to_string(examples().join(example)).unwrap();
    let cut = text.find("[run]").unwrap_or(text.len());
    format!("{}{run_table}\n", &text[..cut])
}

/// [`example_with_run`] written to `DIR/<file name of EXAMPLE>`.
pub fn with_run(example: &str, run_table: &str, dir: &Path) -> PathBuf {
    let p = dir.join(Path::new(example).file_name().unwrap());
    std::fs::write(&p, example_with_run(example, run_table)).unwrap();
    p
}

/// A numeric CSV file: its header and its rows (every cell a number).
pub fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|v| v.parse::<f64>().expect("a number"))
                .collect()
        })
        .collect();
    (header, rows)
}

/// The rows of a CSV file as text cells, header skipped (for files with
/// name columns, such as bodies.csv).
pub fn csv_cells(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect()
}

/// A JSON file (summary.json, view.json, …), parsed.
pub fn json_file(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The JSON a command printed on stdout (`--json`), parsed.
pub fn stdout_json(o: &Output) -> serde_json::Value {
    serde_json::from_str(&stdout(o)).unwrap()
}
