//! A prescribed joint through the command line (examples/oscillating_base.toml):
//! `check` says it is not a DoF, `run` moves the rod's base along the curve
//! (shape.csv's base rows against `x = A sin(2πft)` computed here), writes the
//! drive's coordinate and force, and the energy balance — which the drive's
//! force enters as the work it does — holds. And `[initial] shape`: `check`
//! reports the fit of a rod's strains to given centreline points.

mod common;

use common::{
    csv, csv_cells, json_file, run, run_scene, stderr, stdout, stdout_json, tmp, with_run,
};

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/oscillating_base.toml"
);

#[test]
fn check_says_the_drive_is_not_a_dof() {
    let out = run(&["check", SCENE]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
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
    let dir = tmp("run");
    let scene = with_run(
        "oscillating_base.toml",
        "[run]\nduration = 0.4\noutput_every = 0.02",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let x = |t: f64| 0.01 * (2.0 * std::f64::consts::PI * 2.0 * t).sin();
    let (header, rows) = csv(&out.join("trajectory.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (cd, cf) = (col("prescribed0"), col("prescribed_force0"));
    assert_eq!(rows.len(), 21);
    let mut peak_force = 0.0_f64;
    for r in &rows {
        let (t, d) = (r[0], r[cd]);
        assert!((d - x(t)).abs() < 1e-12, "t = {t}: {d} vs {}", x(t));
        peak_force = peak_force.max(r[cf].abs());
    }
    // Shaking 66 g at (4π)²·1 cm ≈ 1.6 m/s² takes about 0.1 N.
    assert!(peak_force > 0.02 && peak_force < 1.0, "{peak_force}");
    // The rod's base (s = 0) is carried by the drive: world x = x(t).
    // shape.csv: t, rod, s, x, y, z, …
    let mut bases = 0;
    for r in csv_cells(&out.join("shape.csv"))
        .iter()
        .filter(|r| r[2].parse::<f64>().unwrap() == 0.0)
    {
        let t: f64 = r[0].parse().unwrap();
        let bx: f64 = r[3].parse().unwrap();
        assert!(
            (bx - x(t)).abs() < 1e-12,
            "t = {t}: base at x = {bx}, drive {}",
            x(t)
        );
        bases += 1;
    }
    assert_eq!(bases, 21);
    let summary = json_file(&out.join("summary.json"));
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
    let out = run(&["statics", SCENE, "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v = stdout_json(&out);
    let j = &v["joints"][0];
    assert_eq!(j["prescribed"], true);
    assert_eq!(j["values"][0].as_f64().unwrap(), 0.0);
    // Hanging straight down under gravity: the tip right below the base.
    let tip = &v["rods"][0]["tip"]["position"];
    assert!(tip[0].as_f64().unwrap().abs() < 1e-9 && tip[2].as_f64().unwrap() < -0.29);
}

/// `check` reports the fit of an `[initial] shape`: a circle arc (exact)
/// and points the rod cannot reach without stretching (a residual and a
/// warning).
#[test]
fn check_reports_initial_shape_fits() {
    let dir = tmp("shape");
    let arc: Vec<String> = (0..=5)
        .map(|i| {
            let a = 0.5 * i as f64 / 5.0 / 0.4;
            format!("[{}, 0, {}]", 0.4 * a.sin(), -0.4 * (1.0 - a.cos()))
        })
        .collect();
    let rod = "[[rod]]\nname = \"arm\"\nlength = 0.5\npieces = 5\nstrains = [\"ky\", \"kz\"]\n\
               section = { shape = \"circle\", radius = 0.01 }\n\
               material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n";
    for (name, points, exact) in [
        ("arc", arc.join(", "), true),
        (
            "far",
            "[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0]".to_string(),
            false,
        ),
    ] {
        let scene = dir.join(format!("{name}.toml"));
        std::fs::write(
            &scene,
            format!("{rod}[initial]\nshape = [{{ rod = \"arm\", centerline = [{points}] }}]\n"),
        )
        .unwrap();
        let out = run(&["check", scene.to_str().unwrap()]);
        assert!(out.status.success(), "{}", stderr(&out));
        let text = stdout(&out);
        let line = text
            .lines()
            .find(|l| l.starts_with("initial shape of rod 'arm': strains fitted"))
            .unwrap_or_else(|| panic!("{text}"));
        let max: f64 = line
            .rsplit("max ")
            .next()
            .unwrap()
            .trim_end_matches(" m")
            .parse()
            .unwrap();
        if exact {
            assert!(max < 1e-12, "{line}");
            assert!(!text.contains("cannot pass"), "{text}");
        } else {
            // The tip point is 1 m out on a 0.5 m inextensible rod.
            assert!((max - 0.5).abs() < 1e-6, "{line}");
            assert!(text.contains("cannot pass within 1%"), "{text}");
        }
    }
}
