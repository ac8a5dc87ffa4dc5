//! A prescribed joint through the command line (examples/oscillating_base.toml):
//! `check` says it is not a DoF, `run` moves the rod's base along the curve
//! (shape.csv's base rows against `x = A sin(2πft)` computed here), writes the
//! drive's coordinate and force, and the energy balance — which the drive's
//! force enters as the work it does — holds.

use std::path::Path;
use std::process::Command;

fn softrod(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(args)
        .output()
        .expect("runs")
}

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/oscillating_base.toml"
);

fn csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_owned).collect())
        .collect();
    (header, rows)
}

#[test]
fn check_says_the_drive_is_not_a_dof() {
    let out = softrod(&["check", SCENE]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("degrees of freedom: 18"), "{text}");
    assert!(
        text.contains(
            "joint of rod 'tentacle': prismatic on 'world', prescribed: 1 coordinates, not DoF"
        ),
        "{text}"
    );
}

#[test]
fn run_moves_the_base_along_the_curve_and_balances_energy() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("prescribed-run");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(SCENE).unwrap();
    let cut = text.find("[run]").unwrap();
    let scene = dir.join("osc.toml");
    std::fs::write(
        &scene,
        format!(
            "{}[run]\nduration = 0.4\noutput_every = 0.02\n",
            &text[..cut]
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = softrod(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let x = |t: f64| 0.01 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
    let (header, rows) = csv(&out.join("trajectory.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (cd, cf) = (col("prescribed0"), col("prescribed_force0"));
    assert_eq!(rows.len(), 21);
    let mut peak_force = 0.0_f64;
    for r in &rows {
        let t: f64 = r[0].parse().unwrap();
        let d: f64 = r[cd].parse().unwrap();
        assert!((d - x(t)).abs() < 1e-12, "t = {t}: {d} vs {}", x(t));
        peak_force = peak_force.max(r[cf].parse::<f64>().unwrap().abs());
    }
    // Shaking 66 g at (4π)²·1 cm ≈ 1.6 m/s² takes about 0.1 N.
    assert!(peak_force > 0.02 && peak_force < 1.0, "{peak_force}");
    // The rod's base (s = 0) is carried by the drive: world x = x(t).
    let (sh, shape) = csv(&out.join("shape.csv"));
    let (cs, cx) = (
        sh.iter().position(|h| h == "s").unwrap(),
        sh.iter().position(|h| h == "x").unwrap(),
    );
    let mut bases = 0;
    for r in shape
        .iter()
        .filter(|r| r[cs].parse::<f64>().unwrap() == 0.0)
    {
        let t: f64 = r[0].parse().unwrap();
        let bx: f64 = r[cx].parse().unwrap();
        assert!(
            (bx - x(t)).abs() < 1e-12,
            "t = {t}: base at x = {bx}, drive {}",
            x(t)
        );
        bases += 1;
    }
    assert_eq!(bases, 21);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(
        summary["prescribed_names"],
        serde_json::json!(["tentacle.joint.d"])
    );
    assert!(summary["energy_work"].as_f64().unwrap().abs() > 0.0);
    let rel = summary["energy_error_relative"].as_f64().unwrap();
    assert!(rel < 0.02, "energy balance with the drive's work: {rel}");
}

#[test]
fn statics_json_reports_the_drive_held_at_its_start() {
    let out = softrod(&["statics", SCENE, "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let j = &v["joints"][0];
    assert_eq!(j["prescribed"], true);
    assert_eq!(j["values"][0].as_f64().unwrap(), 0.0);
    // Hanging straight down under gravity: the tip right below the base.
    let tip = &v["rods"][0]["tip"]["position"];
    assert!(tip[0].as_f64().unwrap().abs() < 1e-9 && tip[2].as_f64().unwrap() < -0.29);
}
