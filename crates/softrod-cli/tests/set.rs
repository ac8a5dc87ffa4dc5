//! `--set KEY=VALUE`: a setting given on the command line gives the same
//! answer as the same setting written in the scene file, for every command
//! that reads a scene, and a bad one is rejected (exit 2) with the file's
//! key path and the `--set` it came from.

mod common;

use common::*;

/// `softrod statics SCENE --json` with the given `--set`s, as JSON.
fn statics_json(scene: &std::path::Path, set: &[&str]) -> serde_json::Value {
    let mut args = vec!["statics", scene.to_str().unwrap(), "--json"];
    for s in set {
        args.extend(["--set", s]);
    }
    let o = run(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

#[test]
fn a_set_load_equals_the_edited_file() {
    let scene = examples().join("tip_load_statics.toml");
    let dir = tmp("edited");
    let edited = dir.join("edited.toml");
    let text = std::fs::read_to_string(&scene).unwrap();
    let new = text.replace("force = [0.0, 0.0, -0.01]", "force = [0.0, 0.02, -0.03]");
    assert_ne!(text, new);
    std::fs::write(&edited, new).unwrap();
    let set = statics_json(&scene, &["load[0].force=[0.0, 0.02, -0.03]"]);
    let file = statics_json(&edited, &[]);
    assert_eq!(set["q"], file["q"]);
    assert_eq!(set["tip"], file["tip"]);
    // And it is not the unedited answer.
    assert_ne!(statics_json(&scene, &[])["q"], set["q"]);
}

#[test]
fn run_takes_the_integrator_and_duration_from_set() {
    let out = tmp("run");
    let scene = examples().join("cable_planar_arm.toml");
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--set",
        "run.integrator=radau5",
        "--set",
        "run.duration=0.02",
        "--set",
        "cable[0].tension=2.0",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = csv(&out.join("trajectory.csv"));
    assert_eq!(rows.last().unwrap()[0], 0.02);
    let tension = header.iter().position(|h| h == "tension0").unwrap();
    assert!(rows.iter().all(|r| r[tension] == 2.0));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "ok");
}

#[test]
fn bad_settings_exit_2_naming_the_set_and_the_key_path() {
    let scene = examples().join("cantilever_gravity.toml");
    let scene = scene.to_str().unwrap();
    for (command, set, expected) in [
        (
            "check",
            "rod[0].material.young=-1.0",
            "(--set rod[0].material.young=-1.0): rod[0].material.young: out of range",
        ),
        (
            "run",
            "run.integrator=radau6",
            "(--set run.integrator=radau6): run.integrator: ",
        ),
        (
            "modes",
            "rod[0].lenght=1.0",
            "(--set rod[0].lenght=1.0): rod[0].lenght: unknown key",
        ),
        (
            "statics",
            "rod[2].length=1.0",
            "(--set rod[2].length=1.0): rod[2]: the scene has 1",
        ),
        (
            "linearize",
            "run.quadrature=\"x\"",
            "(--set run.quadrature=\"x\"): run.quadrature: ",
        ),
    ] {
        let o = run(&[command, scene, "--set", set]);
        assert_eq!(
            o.status.code(),
            Some(2),
            "{command} --set {set}: {}",
            stderr(&o)
        );
        assert!(
            stderr(&o).contains(expected),
            "{command} --set {set}: {}",
            stderr(&o)
        );
    }
    // Not KEY=VALUE: rejected by the argument parser.
    let o = run(&["check", scene, "--set", "run.integrator"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("expected KEY=VALUE"), "{}", stderr(&o));
    // `view` reads a directory, not a scene.
    let o = run(&["view", "out", "--set", "run.duration=1"]);
    assert_eq!(o.status.code(), Some(2));
}
