//! End-to-end tests of the `softrod` binary: physics checks, not snapshots.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use softrod_dynamics::{Data, StaticsOptions, statics};
use softrod_mechanics::Section;
use softrod_scene::Scene;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_softrod"))
}

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("softrod-cli-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("runs the binary")
}

/// `softrod run SCENE --out OUT --quiet`.
fn run_scene(scene: &Path, out: &Path) -> Output {
    run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ])
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The example with its `[run]` table replaced (written next to the outputs).
fn with_run(example: &str, run_table: &str, dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(examples().join(example)).unwrap();
    let cut = text.find("[run]").unwrap_or(text.len());
    let p = dir.join(example);
    std::fs::write(&p, format!("{}{run_table}\n", &text[..cut])).unwrap();
    p
}

fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
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

#[test]
fn statics_tip_matches_timoshenko() {
    let scene_path = examples().join("tip_load_statics.toml");
    let o = run(&["statics", scene_path.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["converged"], true);
    // Analytic small-load answer from the scene's own numbers.
    let (scene, _) = Scene::from_path(&scene_path).unwrap();
    let rod = &scene.rods[0];
    let Section::Circle { radius: r } = *rod.body.section() else {
        panic!("circle")
    };
    let m = rod.body.material();
    let (l, e, g) = (rod.body.length(), m.young(), m.shear_modulus());
    let p = -rod.point_loads[0].force[2];
    let i = std::f64::consts::PI * r.powi(4) / 4.0;
    let a = std::f64::consts::PI * r * r;
    let delta = p * l.powi(3) / (3.0 * e * i) + p * l / (g * a);
    let tip = &v["tip"]["position"];
    let z = tip[2].as_f64().unwrap();
    // PCS with 10 pieces: piecewise-constant curvature error ~ delta/(4 N^2).
    assert!(
        (-z - delta).abs() < 0.01 * delta,
        "tip z {z}, Timoshenko -{delta}"
    );
    assert!(tip[1].as_f64().unwrap().abs() < 1e-12);
    let x = tip[0].as_f64().unwrap();
    assert!(
        (x - (l - 0.6 * delta * delta / l)).abs() < 1e-6,
        "tip x {x}"
    );
    // Rotation rows: orthonormal, tip turned about +y (nose down).
    let rot: Vec<Vec<f64>> = serde_json::from_value(v["tip"]["rotation"].clone()).unwrap();
    assert_eq!(rot.len(), 3);
    assert!(rot[2][0] < 0.0, "local x points down at the tip: {rot:?}");
    assert_eq!(v["rods"][0]["name"], "beam");
}

#[test]
fn statics_json_matches_the_library() {
    let scene_path = examples().join("tip_load_statics.toml");
    let o = run(&["statics", scene_path.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let (scene, _) = Scene::from_path(&scene_path).unwrap();
    let b = scene.build().unwrap();
    let mut data = Data::new(&b.model);
    let res = statics(
        &b.model,
        &mut data,
        b.q0.as_slice(),
        &StaticsOptions::default(),
    )
    .unwrap();
    let q: Vec<f64> = serde_json::from_value(v["q"].clone()).unwrap();
    assert_eq!(q.len(), res.q.len());
    for (a, b) in q.iter().zip(res.q.iter()) {
        // serde_json's default float parser may be off by one ulp.
        assert!((a - b).abs() <= 1e-15 * b.abs(), "{a} vs {b}");
    }
    assert_eq!(v["iterations"].as_u64().unwrap() as usize, res.iterations);
    for key in ["converged", "iterations", "residual", "q", "tip", "rods"] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
}

#[test]
fn run_writes_valid_streams_and_conserves_energy() {
    let dir = tmp("energy");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.05\nintegrator = \"dopri5\"\nrtol = 1e-8\natol = 1e-11\noutput_every = 0.0025",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = csv(&out.join("trajectory.csv"));
    let n_dof = 24;
    let mut expect = "t,tip_x,tip_y,tip_z,tip_qw,tip_qx,tip_qy,tip_qz,energy".to_string();
    for i in 0..n_dof {
        expect.push_str(&format!(",q{i}"));
    }
    assert_eq!(header.join(","), expect);
    assert_eq!(rows.len(), 21, "0, 0.0025, ..., 0.05");
    assert!(rows.iter().flatten().all(|v| v.is_finite()));
    assert!(rows.iter().all(|r| r.len() == header.len()));
    assert_eq!(rows[0][0], 0.0);
    assert!((rows[20][0] - 0.05).abs() < 1e-15);
    // Undamped, unactuated: total energy conserved; the scale is the
    // gravitational energy exchanged (the tip drops).
    let e0 = rows[0][8];
    let drift = rows.iter().map(|r| (r[8] - e0).abs()).fold(0.0, f64::max);
    let (_, shape) = csv_shape(&out.join("shape.csv"));
    let scale = 1000.0 * 3.14159e-4 * 9.81 * 0.5 * (rows[20][3]).abs();
    assert!(rows[20][3] < -1e-4, "the tip falls: {}", rows[20][3]);
    assert!(
        drift < 1e-5 * scale.max(1e-12),
        "energy drift {drift:e}, scale {scale:e}"
    );
    // Shape: N+1 = 9 boundaries per output time, from the base at s = 0 to the tip.
    assert_eq!(shape, 21 * 9);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "ok");
    assert!((summary["final_time"].as_f64().unwrap() - 0.05).abs() < 1e-15);
    for k in ["steps", "rejected_steps", "rhs_evaluations", "wall_seconds"] {
        assert!(summary[k].is_number(), "{k}");
    }
    for svg in ["tip_trajectory.svg", "energy.svg", "shapes.svg"] {
        let t = std::fs::read_to_string(out.join(svg)).unwrap();
        assert!(t.starts_with("<svg") && t.contains("</svg>"), "{svg}");
    }
}

/// `[run] linearly_implicit` end to end: the IMEX generalized-alpha at a
/// fixed 1 ms step follows a tight Rosenbrock run of the same scene (an
/// independent, error-controlled method) to 2e-4 m over the whole run, in
/// one right-hand side per step.
#[test]
fn linearly_implicit_generalized_alpha_tracks_a_tight_rosenbrock_run() {
    let dir = tmp("linearly_implicit");
    let mut tips = Vec::new();
    for (name, table) in [
        (
            "li",
            "[run]\nduration = 0.3\nintegrator = \"generalized-alpha\"\nlinearly_implicit = true\ndt = 1e-3\noutput_every = 0.01",
        ),
        (
            "ros",
            "[run]\nduration = 0.3\nintegrator = \"rosenbrock\"\nrtol = 1e-5\natol = 1e-8\noutput_every = 0.01",
        ),
    ] {
        let sub = dir.join(name);
        std::fs::create_dir_all(&sub).unwrap();
        let scene = with_run("cantilever_gravity.toml", table, &sub);
        let out = sub.join("out");
        let o = run_scene(&scene, &out);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        if name == "li" {
            assert_eq!(summary["steps"], 300);
            assert_eq!(summary["rhs_evaluations"], 301);
        }
        tips.push(csv(&out.join("trajectory.csv")).1);
    }
    let (li, ros) = (&tips[0], &tips[1]);
    assert_eq!(li.len(), 31);
    assert_eq!(li.len(), ros.len());
    let max_diff = li
        .iter()
        .zip(ros)
        .map(|(a, b)| {
            ((a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2) + (a[3] - b[3]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    // The tip falls by centimetres in 0.3 s; the two methods agree far closer.
    assert!(ros[30][3] < -1e-2, "the tip falls: {}", ros[30][3]);
    assert!(max_diff < 2e-4, "max tip difference {max_diff:e} m");
}

/// Rows of shape.csv (header checked).
fn csv_shape(path: &Path) -> (String, usize) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    assert_eq!(header, "t,rod,s,x,y,z,qw,qx,qy,qz");
    let mut n = 0;
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.len(), 10);
        for (i, v) in f.iter().enumerate() {
            if i != 1 {
                assert!(v.parse::<f64>().unwrap().is_finite());
            }
        }
        n += 1;
    }
    (header, n)
}

#[test]
fn stiff_and_cable_examples_run_with_rosenbrock() {
    let dir = tmp("cable");
    let scene = with_run(
        "cable_planar_arm.toml",
        "[run]\nduration = 0.2\nintegrator = \"rosenbrock\"\nrtol = 1e-4\natol = 1e-7\noutput_every = 0.02",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, rows) = csv(&out.join("trajectory.csv"));
    assert_eq!(rows.len(), 11);
    // The right cable (local +z = world +x) pulls harder: the tip moves to +x.
    assert!(rows[10][1] > 1e-4, "tip x {}", rows[10][1]);
}

#[test]
fn modes_json_about_statics_and_rest() {
    // Rest: no gravity -> Euler-Bernoulli first bending frequency.
    let dir = tmp("modes");
    let p = dir.join("free.toml");
    std::fs::write(
        &p,
        "[[rod]]\nname = \"b\"\nlength = 0.5\npieces = 12\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }\n",
    )
    .unwrap();
    let o = run(&["modes", p.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["equilibrium"], "rest");
    let f: Vec<f64> = serde_json::from_value(v["frequencies_hz"].clone()).unwrap();
    assert_eq!(f.len(), 10);
    assert!(f.windows(2).all(|w| w[0] <= w[1]));
    let (r, l, e, rho): (f64, f64, f64, f64) = (0.01, 0.5, 1e7, 1000.0);
    let ei = e * std::f64::consts::PI * r.powi(4) / 4.0;
    let ma = rho * std::f64::consts::PI * r * r;
    let f1 = 1.875104f64.powi(2) / (2.0 * std::f64::consts::PI) * (ei / (ma * l.powi(4))).sqrt();
    assert!(
        (f[0] - f1).abs() < 0.02 * f1,
        "f1 {} vs Euler-Bernoulli {f1}",
        f[0]
    );
    // With gravity the equilibrium is the static one.
    let o = run(&[
        "modes",
        examples().join("cantilever_gravity.toml").to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["equilibrium"], "statics");
}

#[test]
fn check_prints_the_summary() {
    let o = run(&[
        "check",
        examples().join("cable_planar_arm.toml").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = stdout(&o);
    assert!(s.contains("degrees of freedom: 18"), "{s}");
    assert!(
        s.contains("cables") && s.contains("damping") && s.contains("gravity"),
        "{s}"
    );
}

#[test]
fn bad_input_exits_2_with_the_key_path() {
    let dir = tmp("bad");
    let good = std::fs::read_to_string(examples().join("cantilever_gravity.toml")).unwrap();
    let cases = [
        ("young = 1.0e7", "young = -5.0", "rod[0].material.young"),
        ("length = 0.5", "lenght = 0.5", "rod[0].lenght"),
        ("pieces = 8", "pieces = \"eight\"", "rod[0].pieces"),
        (
            "integrator = \"esdirk\"",
            "integrator = \"euler\"",
            "run.integrator",
        ),
    ];
    for (i, (from, to, expect)) in cases.iter().enumerate() {
        let p = dir.join(format!("bad{i}.toml"));
        assert!(good.contains(from));
        std::fs::write(&p, good.replacen(from, to, 1)).unwrap();
        for cmd in ["check", "run"] {
            let o = if cmd == "run" {
                run_scene(&p, &dir.join("o"))
            } else {
                run(&[cmd, p.to_str().unwrap()])
            };
            assert_eq!(o.status.code(), Some(2), "{cmd} {to}: {}", stderr(&o));
            let e = stderr(&o);
            assert!(e.contains(expect), "{cmd} {to}: {e}");
            assert!(!e.contains("panicked"), "{e}");
        }
    }
    let o = run(&["check", dir.join("missing.toml").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&["statics", dir.join("bad0.toml").to_str().unwrap(), "--json"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stdout(&o).is_empty(), "no partial JSON on stdout");
    assert!(
        stderr(&o).contains("bad0.toml:"),
        "file named: {}",
        stderr(&o)
    );
}

#[test]
fn unstable_explicit_run_fails_with_exit_1_and_a_summary() {
    let dir = tmp("unstable");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.1\nintegrator = \"rk4\"\ndt = 1e-3\noutput_every = 0.01",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(
        summary["status"].as_str().unwrap().starts_with("error: "),
        "{summary}"
    );
    let text = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(!text.to_lowercase().contains("nan") && !text.contains("inf"));
}

#[test]
fn help_teaches() {
    let o = run(&["--help"]);
    assert!(o.status.success());
    let s = stdout(&o);
    for w in ["check", "statics", "run", "modes", "report", "Example"] {
        assert!(s.contains(w), "{w} in {s}");
    }
}

#[test]
fn every_example_checks_and_the_3d_arm_leaves_the_plane() {
    for e in std::fs::read_dir(examples()).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "toml") {
            let o = run(&["check", p.to_str().unwrap()]);
            assert!(o.status.success(), "{}: {}", p.display(), stderr(&o));
        }
    }
    let dir = tmp("arm3d");
    let scene = with_run(
        "three_section_arm.toml",
        "[run]\nduration = 0.8\nintegrator = \"rosenbrock\"\nrtol = 1e-4\natol = 1e-7\noutput_every = 0.05",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, rows) = csv(&out.join("trajectory.csv"));
    let last = rows.last().unwrap();
    // By 0.8 s the cables at 0 and 120 degrees have pulled: the tip left the vertical axis
    // in both x and y.
    assert!(
        last[1].abs() > 1e-3 && last[2].abs() > 1e-4,
        "tip {:?}",
        &last[1..4]
    );
}

#[test]
fn report_writes_table_and_plot() {
    let dir = tmp("report");
    let p = dir.join("tiny.toml");
    std::fs::write(
        &p,
        "[world]\ngravity = [0, 0, -9.81]\n[[rod]]\nname = \"b\"\nlength = 0.3\npieces = 2\n\
         strains = [\"ky\"]\nsection = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n[run]\nduration = 0.05\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = run(&[
        "report",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--quick",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, n) = (
        0,
        std::fs::read_to_string(out.join("report.csv"))
            .unwrap()
            .lines()
            .count(),
    );
    assert_eq!(
        n,
        1 + 9 + 6 + 6 + 7 + 5,
        "header, 9 spatial (pieces x3, quadrature x3), 6 dopri5, 6 rosenbrock, 7 esdirk, 5 generalized-alpha"
    );
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("Temporal reference") && md.contains("Spatial reference"));
    assert!(md.contains("★"), "the Pareto front is marked");
    assert!(
        std::fs::read_to_string(out.join("report_spatial.svg"))
            .unwrap()
            .contains("</svg>")
    );
    assert!(
        std::fs::read_to_string(out.join("report.svg"))
            .unwrap()
            .contains("</svg>")
    );
}

#[test]
fn statics_flags_an_unstable_equilibrium() {
    // A rod standing upright under its own weight: the straight shape is
    // always an equilibrium (Newton finds it at once), stable only below
    // Greenhill's self-weight buckling length L_c = (7.837·EI/(ρAg))^{1/3}:
    // 0.13 m for E = 1e5 Pa (unstable at L = 0.5 m), 0.58 m for E = 1e7 Pa
    // (stable).
    let dir = tmp("unstable");
    let scene = |young: f64| {
        format!(
            "[world]\ngravity = [0.0, 0.0, -9.81]\n[[rod]]\nname = \"arm\"\nlength = 0.5\n\
             pieces = 6\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
             base = {{ position = [0, 0, 0], rotation = [[0,0,-1],[0,1,0],[1,0,0]] }}\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = {young:e}, poisson = 0.5 }}\n"
        )
    };
    for (young, stable) in [(1.0e5, false), (1.0e7, true)] {
        let p = dir.join(format!("upright_{young:e}.toml"));
        std::fs::write(&p, scene(young)).unwrap();
        let o = run(&["statics", p.to_str().unwrap(), "--json"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        assert_eq!(v["stable"], serde_json::Value::Bool(stable), "E = {young}");
        assert_eq!(stderr(&o).contains("unstable"), !stable);
    }
}

/// `linearize --json` about the sagged cantilever: the eigenvalues of `A`
/// are `±iω` with `ω` the frequencies `modes` finds by its symmetric
/// generalized eigenproblem (a second algorithm: gravity is conservative, so
/// the undamped linearization has a purely imaginary spectrum), and the
/// state ordering is `q` then `qdot`, named.
#[test]
fn linearize_agrees_with_modes() {
    let p = examples().join("cantilever_gravity.toml");
    let o = run(&["linearize", p.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["equilibrium"], "statics");
    let state = v["state"].as_array().unwrap();
    assert_eq!(state.len(), 48);
    assert_eq!(state[0], "q:cantilever.p0.ky");
    assert_eq!(state[24 + 2], "qdot:cantilever.p0.qz");
    assert!(v["inputs"].as_array().unwrap().is_empty());
    assert!(v["xdot_residual"].as_f64().unwrap() < 1e-6);
    let a_rows = v["A"].as_array().unwrap();
    let n = a_rows.len();
    let a = nalgebra::DMatrix::from_fn(n, n, |i, j| a_rows[i][j].as_f64().unwrap());
    let mut omega: Vec<f64> = a
        .complex_eigenvalues()
        .iter()
        .filter(|z| z.im > 0.0)
        .map(|z| {
            assert!(z.re.abs() < 1e-6 * z.im, "undamped: {z}");
            z.im
        })
        .collect();
    omega.sort_by(f64::total_cmp);
    let o = run(&["modes", p.to_str().unwrap(), "--json", "--count", "6"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let f = m["frequencies_hz"].as_array().unwrap();
    assert_eq!(f.len(), 6);
    for (k, fk) in f.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * fk.as_f64().unwrap();
        assert!(
            (omega[k] - w).abs() < 1e-6 * w,
            "mode {k}: {} vs {w}",
            omega[k]
        );
    }
}
