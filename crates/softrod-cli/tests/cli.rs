//! End-to-end tests of the `softrod` binary: physics checks, not snapshots.

use std::path::Path;

use softrod_dynamics::{Data, StaticsOptions, statics};
use softrod_mechanics::Section;
use softrod_scene::Scene;

mod common;
use common::*;

#[test]
fn statics_tip_matches_timoshenko() {
    let scene_path = examples().join("tip_load_statics.toml");
    let o = run(&["statics", scene_path.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = stdout_json(&o);
    assert_eq!(v["converged"], true);
    // Analytic small-load answer from the scene's own numbers.
    let (scene, _) = Scene::from_path(&scene_path).unwrap();
    let rod = &scene.rods[0];
    let Section::Circle { radius: r } = *rod.properties.section() else {
        panic!("circle")
    };
    let m = rod.properties.material();
    let (l, e, g) = (rod.properties.length(), m.young(), m.shear_modulus());
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
    let v: serde_json::Value = stdout_json(&o);
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
    assert!(
        header.join(",").starts_with(&expect),
        "the contract's columns first"
    );
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
    // Shape: 8 pieces sampled at 8 points each (the default for 8 pieces)
    // plus the tip: 65 samples per output time, from the base at s = 0.
    assert_eq!(shape, 21 * 65);
    let summary: serde_json::Value = json_file(&out.join("summary.json"));
    assert_eq!(summary["status"], "ok");
    assert!((summary["final_time"].as_f64().unwrap() - 0.05).abs() < 1e-15);
    for k in ["steps", "rejected_steps", "rhs_evaluations", "wall_seconds"] {
        assert!(summary[k].is_number(), "{k}");
    }
    for svg in [
        "tip_trajectory.svg",
        "energy.svg",
        "shapes.svg",
        "strains.svg",
    ] {
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
        let summary: serde_json::Value = json_file(&out.join("summary.json"));
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

/// `softrod modes` of a 3 000-piece rod with all six strains (18 000
/// coordinates, whose dense modal matrices would need ~31 GB and were
/// refused as too large): the lowest frequencies by Lanczos, against
/// Euler–Bernoulli (L/r = 10⁴: shear and rotary inertia ~1e-8; the pieces,
/// 0.33 mm, stay longer than the radius, so no slenderness warning).
#[test]
fn modes_of_a_three_thousand_piece_rod() {
    let dir = tmp("modes_large");
    let p = dir.join("long.toml");
    std::fs::write(
        &p,
        "[[rod]]\nname = \"b\"\nlength = 1.0\npieces = 3000\n\
         section = { shape = \"circle\", radius = 0.0001 }\n\
         material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }\n",
    )
    .unwrap();
    let o = run(&["modes", p.to_str().unwrap(), "--json", "--count", "3"]);
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = stdout_json(&o);
    assert_eq!(v["equilibrium"], "rest");
    assert!(
        v["asymmetry"].as_f64().unwrap() < 1e-9,
        "{}",
        v["asymmetry"]
    );
    let f: Vec<f64> = serde_json::from_value(v["frequencies_hz"].clone()).unwrap();
    assert_eq!(f.len(), 3);
    let (r, e, rho): (f64, f64, f64) = (0.0001, 1e7, 1000.0);
    let ei = e * std::f64::consts::PI * r.powi(4) / 4.0;
    let ma = rho * std::f64::consts::PI * r * r;
    let f1 = 1.875104f64.powi(2) / (2.0 * std::f64::consts::PI) * (ei / ma).sqrt();
    // A round rod bends alike about y and z: the two lowest are f1 (to the
    // Lanczos tolerance, the Ritz error 0.19/N² and 1e-8 of shear and
    // rotary inertia).
    for (k, fk) in f[..2].iter().enumerate() {
        assert!((fk / f1 - 1.0).abs() < 1e-4, "f[{k}] {fk} vs {f1}");
    }
    assert!(
        f[2] > 6.0 * f1,
        "third mode {} (second bending ≈ 6.27 f1)",
        f[2]
    );
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
    let v: serde_json::Value = stdout_json(&o);
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
    let v: serde_json::Value = stdout_json(&o);
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
    let summary: serde_json::Value = json_file(&out.join("summary.json"));
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
        1 + 9 + 6 + 6 + 7 + 7 + 5,
        "header, 9 spatial (pieces x3, quadrature x3), 6 dopri5, 6 rosenbrock, 7 esdirk, \
         7 esdirk5, 5 generalized-alpha"
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
        let v: serde_json::Value = stdout_json(&o);
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
    let v = linearize_json(&p);
    let state = v["state"].as_array().unwrap();
    assert_eq!(state.len(), 48);
    assert_eq!(state[0], "q:cantilever.p0.ky");
    assert_eq!(state[24 + 2], "qdot:cantilever.p0.qz");
    assert!(v["inputs"].as_array().unwrap().is_empty());
    frequencies_agree(&p, &v, 6);
}

/// The same on a robot (the analytic derivatives on the tree,
/// docs/theory-derivatives.md §7): a rod with a body at its tip, a second
/// rod on a sprung revolute joint from that body, a payload with an offset
/// centre of mass, undamped, under gravity; its joint coordinate is named.
#[test]
fn linearize_agrees_with_modes_on_a_robot() {
    let dir = tmp("linearize_robot");
    let p = dir.join("robot.toml");
    std::fs::write(
        &p,
        "[world]\ngravity = [0.0, 0.0, -9.81]\n\
         [[rod]]\nname = \"upper\"\nlength = 0.25\npieces = 3\nstrains = [\"ky\", \"kz\", \"qx\"]\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1100.0, young = 2.0e6, poisson = 0.5 }\n\
         [[body]]\nname = \"connector\"\nparent = \"upper\"\nmass = 0.01\n\
         inertia = [1e-6, 1e-6, 1e-6]\ncenter_of_mass = [0.005, 0.0, 0.0]\n\
         [[rod]]\nname = \"lower\"\nparent = \"connector\"\nbase = { position = [0.01, 0.0, 0.0] }\n\
         joint = { type = \"revolute\", axis = [0, 1, 0], stiffness = 0.2 }\n\
         length = 0.2\npieces = 2\nstrains = \"all\"\n\
         section = { shape = \"circle\", radius = 0.008 }\n\
         material = { density = 1100.0, young = 2.0e6, poisson = 0.5 }\n\
         [[body]]\nname = \"gripper\"\nparent = \"lower\"\nmass = 0.02\n\
         inertia = [4e-6, 4e-6, 4e-6]\ncenter_of_mass = [0.01, 0.0, 0.002]\n",
    )
    .unwrap();
    let v = linearize_json(&p);
    let state = v["state"].as_array().unwrap();
    assert_eq!(state.len(), 2 * (9 + 1 + 12));
    assert!(
        state.iter().any(|s| s == "q:lower.joint.theta"),
        "{state:?}"
    );
    frequencies_agree(&p, &v, 6);
}

/// `softrod linearize SCENE --json`, checked to succeed, about the statics.
fn linearize_json(p: &std::path::Path) -> serde_json::Value {
    let o = run(&["linearize", p.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = stdout_json(&o);
    assert_eq!(v["equilibrium"], "statics");
    assert!(v["xdot_residual"].as_f64().unwrap() < 1e-6);
    v
}

/// The lowest `count` eigenfrequencies of the undamped `A` against `softrod
/// modes` to 1e-6.
fn frequencies_agree(p: &std::path::Path, v: &serde_json::Value, count: usize) {
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
    let count_arg = count.to_string();
    let o = run(&[
        "modes",
        p.to_str().unwrap(),
        "--json",
        "--count",
        &count_arg,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m: serde_json::Value = stdout_json(&o);
    let f = m["frequencies_hz"].as_array().unwrap();
    assert_eq!(f.len(), count);
    for (k, fk) in f.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * fk.as_f64().unwrap();
        assert!(
            (omega[k] - w).abs() < 1e-6 * w,
            "mode {k}: {} vs {w}",
            omega[k]
        );
    }
}

/// A rod's samples in shape.csv lie on the exact PCS arc, not on chords:
/// one piece bent at curvature κ about local y (base rotated so local x is
/// world x) is the circle x = sin(κs)/κ, z = −(1 − cos κs)/κ, here checked
/// at t = 0 for every sample, the piece's inside included; the number of
/// samples follows `[run] shape_points_per_piece`.
#[test]
fn shape_samples_lie_on_the_exact_arc() {
    let dir = tmp("arc");
    let kappa = 4.0;
    let p = dir.join("arc.toml");
    std::fs::write(
        &p,
        format!(
            "[[rod]]\nname = \"arc\"\nlength = 0.5\npieces = 1\nstrains = [\"ky\"]\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n\
             [initial]\nq = [{kappa}]\n\
             [run]\nduration = 0.001\noutput_every = 0.001\n"
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = run_scene(&p, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("shape.csv")).unwrap();
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| *i != 1)
                .map(|(_, v)| v.parse().unwrap())
                .collect()
        })
        .filter(|r: &Vec<f64>| r[0] == 0.0)
        .collect();
    // One piece: the default is 16 points per piece, plus the tip.
    assert_eq!(rows.len(), 17);
    for r in &rows {
        let (s, x, z) = (r[1], r[2], r[4]);
        // Bending about local y by +κ turns x toward −z.
        let (ex, ez) = (
            (kappa * s).sin() / kappa,
            -(1.0 - (kappa * s).cos()) / kappa,
        );
        assert!(
            (x - ex).abs() < 1e-12 && (z - ez).abs() < 1e-12 && r[3].abs() < 1e-15,
            "s = {s}: ({x}, {z}) vs the arc ({ex}, {ez})"
        );
    }
    assert_eq!(rows[16][1], 0.5, "the tip");
}

/// `softrod run` writes a self-contained 3-D view (no network reference),
/// its view.json (radius, cables), the strain and actuator figures;
/// `softrod view DIR` rebuilds the page from the files; a directory without
/// a run is bad input (exit 2).
#[test]
fn run_writes_the_view_and_view_rebuilds_it() {
    let dir = tmp("view");
    let scene = with_run(
        "cable_planar_arm.toml",
        "[run]\nduration = 0.1\nintegrator = \"rosenbrock\"\noutput_every = 0.01",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let page = std::fs::read_to_string(out.join("view.html")).unwrap();
    assert!(page.starts_with("<!DOCTYPE html>"));
    for net in ["src=\"http", "href=\"http", "import(", "fetch("] {
        assert!(!page.contains(net), "the page reaches out: {net}");
    }
    let spec: serde_json::Value = json_file(&out.join("view.json"));
    assert_eq!(spec["rods"][0]["radius"]["r"][0], 0.01);
    assert_eq!(spec["cables"].as_array().unwrap().len(), 2);
    assert_eq!(spec["cables"][1]["path"][0][2], -0.008);
    assert_eq!(spec["up"], serde_json::json!([0.0, 0.0, 1.0]));
    for svg in ["strains.svg", "actuators.svg", "shapes.svg"] {
        let t = std::fs::read_to_string(out.join(svg)).unwrap();
        assert!(t.starts_with("<svg") && t.contains("</svg>"), "{svg}");
    }
    std::fs::remove_file(out.join("view.html")).unwrap();
    let o = run(&["view", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o).trim(), out.join("view.html").to_str().unwrap());
    assert_eq!(
        std::fs::read_to_string(out.join("view.html")).unwrap(),
        page
    );
    let o = run(&["view", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a run directory"), "{}", stderr(&o));
}

/// The view `softrod run` builds from its frames is the page `softrod view`
/// rebuilds from the files, also with a body (its poses from bodies.csv).
#[test]
fn the_runs_view_with_a_body_equals_the_rebuilt_one() {
    let dir = tmp("view-body");
    let scene = with_run(
        "arm_with_payload.toml",
        "[run]\nduration = 0.05\noutput_every = 0.001",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let page = std::fs::read(out.join("view.html")).unwrap();
    let o = run(&["view", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        std::fs::read(out.join("view.html")).unwrap() == page,
        "the pages differ"
    );
    let d = softrod_viz::html::embedded_data(&String::from_utf8(page).unwrap()).unwrap();
    assert_eq!(
        d["bodies"].as_array().unwrap().len(),
        2,
        "the scene's two bodies"
    );
    assert_eq!(d["times"].as_array().unwrap().len(), 51);
}

/// `statics --out` writes the equilibrium's figure, `modes --out` the mode
/// shapes; the JSON on stdout is unchanged by it.
#[test]
fn statics_and_modes_write_their_figures() {
    let dir = tmp("figures");
    let scene = examples().join("tip_load_statics.toml");
    let o = run(&[
        "statics",
        scene.to_str().unwrap(),
        "--json",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let _: serde_json::Value = stdout_json(&o);
    let t = std::fs::read_to_string(dir.join("statics_shape.svg")).unwrap();
    assert!(t.contains("</svg>") && t.contains("equilibrium"));
    let o = run(&[
        "modes",
        examples().join("cantilever_gravity.toml").to_str().unwrap(),
        "--count",
        "3",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let t = std::fs::read_to_string(dir.join("modes.svg")).unwrap();
    assert!(
        t.contains("</svg>") && t.contains("mode 3"),
        "three modes drawn"
    );
}

/// The added trajectory.csv columns after the contract's: `qdot` is the
/// time derivative of `q` (central differences of the q columns agree),
/// the energy components sum to `energy`; summary.json names every q.
#[test]
fn trajectory_has_velocities_and_energy_components_and_summary_names_q() {
    let dir = tmp("columns");
    // Bending only: no shear/extension ringing at 1e5 rad/s, so a 0.1 ms
    // grid resolves the motion (highest mode ~300 Hz: central differences
    // off by (ωΔ)²/6 < 1 %).
    let text = std::fs::read_to_string(examples().join("cantilever_gravity.toml"))
        .unwrap()
        .replace("strains = [\"ky\", \"qx\", \"qz\"]", "strains = [\"ky\"]");
    let cut = text.find("[run]").unwrap();
    let scene = dir.join("bending.toml");
    std::fs::write(
        &scene,
        format!(
            "{}[run]\nduration = 0.02\nintegrator = \"dopri5\"\nrtol = 1e-9\natol = 1e-12\noutput_every = 0.0001",
            &text[..cut]
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = csv(&out.join("trajectory.csv"));
    let n = 8;
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    assert_eq!(col("q0"), 9, "the contract's columns first");
    assert_eq!(col("qdot0"), 9 + n);
    assert_eq!(col("kinetic"), 9 + 2 * n);
    assert_eq!(header.len(), 9 + 2 * n + 3);
    for r in &rows {
        let sum = r[col("kinetic")] + r[col("elastic")] + r[col("gravitational")];
        assert!(
            (sum - r[8]).abs() <= 1e-12 * r[8].abs().max(1e-9),
            "{sum} vs {}",
            r[8]
        );
    }
    // Central differences of q over 0.2 ms against qdot at the middle row,
    // on the bending coordinate of the first piece.
    let (q, qd) = (col("q0"), col("qdot0"));
    let scale = rows.iter().map(|r| r[qd].abs()).fold(0.0, f64::max);
    assert!(scale > 1e-2, "the rod moves: max |qdot0| = {scale}");
    for k in 1..rows.len() - 1 {
        let fd = (rows[k + 1][q] - rows[k - 1][q]) / (rows[k + 1][0] - rows[k - 1][0]);
        assert!(
            (fd - rows[k][qd]).abs() < 1e-2 * scale,
            "t = {}: dq/dt {fd} vs qdot {}",
            rows[k][0],
            rows[k][qd]
        );
    }
    let summary: serde_json::Value = json_file(&out.join("summary.json"));
    let names: Vec<String> = serde_json::from_value(summary["q_names"].clone()).unwrap();
    assert_eq!(names.len(), n);
    assert_eq!(names[..2], ["cantilever.p0.ky", "cantilever.p1.ky"]);
    assert_eq!(names[n - 1], "cantilever.p7.ky");
}

/// With cables, trajectory.csv has each cable's tension and power; without
/// damping and gravity the work they do is the change of energy
/// (work-energy theorem): ∫ Σ power dt (trapezoid) equals E(t) − E(0).
#[test]
fn cable_power_integrates_to_the_energy_change() {
    let dir = tmp("power");
    let p = dir.join("pull.toml");
    std::fs::write(
        &p,
        "[[rod]]\nname = \"arm\"\nlength = 0.3\npieces = 4\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1100.0, young = 1.0e6, poisson = 0.5 }\n\
         [[cable]]\nrod = \"arm\"\noffset = [0.0, 0.008]\n\
         tension = { times = [0.0, 0.02], values = [0.0, 1.0] }\n\
         [run]\nduration = 0.04\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-13\n\
         output_every = 0.0001\n",
    )
    .unwrap();
    let out = dir.join("out");
    let o = run_scene(&p, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let (header, rows) = csv(&out.join("trajectory.csv"));
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (tn, pw) = (col("tension0"), col("power0"));
    assert_eq!(header.len(), pw + 1);
    // The schedule, exactly.
    assert_eq!(rows[0][tn], 0.0);
    assert!((rows[100][tn] - 0.5).abs() < 1e-12, "{}", rows[100][tn]);
    assert_eq!(rows[400][tn], 1.0);
    let mut work = 0.0;
    let e0 = rows[0][8];
    let mut worst: f64 = 0.0;
    let mut scale: f64 = 0.0;
    for k in 1..rows.len() {
        work += 0.5 * (rows[k][pw] + rows[k - 1][pw]) * (rows[k][0] - rows[k - 1][0]);
        let de = rows[k][8] - e0;
        worst = worst.max((work - de).abs());
        scale = scale.max(de.abs());
    }
    assert!(scale > 1e-6, "the cable does work: {scale}");
    // Trapezoid error of a 0.1 ms grid on a motion of period ~10 ms.
    assert!(worst < 2e-3 * scale, "∫P dt vs ΔE: {worst:e} of {scale:e}");
}

/// `[initial] trajectory` starts from a row of a previous run: the first row
/// of the continuation is that row's state, and two runs of 0.01 s end where
/// one run of 0.02 s does. A row out of range, or a trajectory of another
/// scene, is bad input naming the key.
#[test]
fn a_run_restarts_from_a_row_of_a_previous_trajectory() {
    let dir = tmp("restart");
    let run_table = |d: f64| {
        format!(
            "[run]\nduration = {d}\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-13\noutput_every = 0.001"
        )
    };
    let whole = with_run("cantilever_gravity.toml", &run_table(0.02), &dir);
    let o = run_scene(&whole, &dir.join("whole"));
    assert!(o.status.success(), "{}", stderr(&o));
    let first = dir.join("first.toml");
    std::fs::copy(
        with_run("cantilever_gravity.toml", &run_table(0.01), &dir),
        &first,
    )
    .unwrap();
    let o = run_scene(&first, &dir.join("first"));
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&first).unwrap();
    let second = dir.join("second.toml");
    std::fs::write(
        &second,
        format!("{text}\n[initial]\ntrajectory = \"first/trajectory.csv\"\nrow = -1\n"),
    )
    .unwrap();
    let o = run_scene(&second, &dir.join("second"));
    assert!(o.status.success(), "{}", stderr(&o));
    let (h, a) = csv(&dir.join("first/trajectory.csv"));
    let (_, b) = csv(&dir.join("second/trajectory.csv"));
    let (_, w) = csv(&dir.join("whole/trajectory.csv"));
    let q0 = h.iter().position(|c| c == "q0").unwrap();
    let end = h.iter().position(|c| c == "kinetic").unwrap();
    assert_eq!(
        a.last().unwrap()[q0..end],
        b[0][q0..end],
        "q and qdot carried over exactly"
    );
    let (bt, wt) = (b.last().unwrap(), w.last().unwrap());
    for i in 1..4 {
        assert!(
            (bt[i] - wt[i]).abs() < 1e-8,
            "tip {i}: {} vs {}",
            bt[i],
            wt[i]
        );
    }
    // Bad rows and foreign trajectories: exit 2, the key named.
    std::fs::write(
        &second,
        format!("{text}\n[initial]\ntrajectory = \"first/trajectory.csv\"\nrow = 11\n"),
    )
    .unwrap();
    let o = run(&["check", second.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("initial.trajectory") && stderr(&o).contains("11 data rows"),
        "{}",
        stderr(&o)
    );
    let other = dir.join("other.toml");
    std::fs::write(
        &other,
        "[[rod]]\nname = \"b\"\nlength = 0.5\npieces = 2\nstrains = [\"ky\"]\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }\n\
         [initial]\ntrajectory = \"first/trajectory.csv\"\n",
    )
    .unwrap();
    let o = run(&["check", other.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("initial.trajectory") && stderr(&o).contains("n_dof = 2"),
        "{}",
        stderr(&o)
    );
}

/// `[run] shape_points_per_piece` sets the samples of shape.csv (m per
/// piece plus the tip); a bad value is bad input naming the key.
#[test]
fn shape_points_per_piece_sets_the_samples() {
    let dir = tmp("points");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.01\noutput_every = 0.005\nshape_points_per_piece = 3",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, n) = csv_shape(&out.join("shape.csv"));
    assert_eq!(n, 3 * (8 * 3 + 1));
    let bad = with_run(
        "cantilever_gravity.toml",
        "[run]\nshape_points_per_piece = 0",
        &dir,
    );
    let o = run_scene(&bad, &out);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("run.shape_points_per_piece"),
        "{}",
        stderr(&o)
    );
}

/// A scene whose rod name holds a comma, a quote and a line break.
const ODD_NAME: &str = "arm, \"left\"\nsecond line";

/// Rod names with commas, quotes and line breaks survive shape.csv (a real
/// CSV writer quotes them) and the view rebuilt from it.
#[test]
fn odd_rod_names_round_trip_through_shape_csv() {
    let dir = tmp("names");
    let p = dir.join("odd.toml");
    let toml_name = ODD_NAME.replace('"', "\\\"").replace('\n', "\\n");
    std::fs::write(
        &p,
        format!(
            "[world]\ngravity = [0.0, 0.0, -9.81]\n[[rod]]\nname = \"{toml_name}\"\nlength = 0.5\n\
             pieces = 4\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = 1.0e7, poisson = 0.5 }}\n\
             [run]\nduration = 0.01\noutput_every = 0.005\nshape_points_per_piece = 2\n"
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = run_scene(&p, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let shape = softrod_viz::run_dir::read_shape_csv(&out.join("shape.csv")).unwrap();
    assert_eq!(shape.rods.len(), 1);
    assert_eq!(shape.rods[0].name, ODD_NAME);
    assert_eq!(shape.times.len(), 3);
    assert_eq!(shape.rods[0].s.len(), 4 * 2 + 1);
    let o = run(&["view", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A rerun into the same directory removes the previous run's outputs
/// (here a cable figure and a second rod's strains this scene does not
/// make), and leaves the user's own files alone.
#[test]
fn a_rerun_removes_the_previous_runs_outputs() {
    let dir = tmp("stale");
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    for f in ["actuators.svg", "strains_3.svg", "view.html", "notes.txt"] {
        std::fs::write(out.join(f), "old").unwrap();
    }
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.01\noutput_every = 0.005",
        &dir,
    );
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("removed the previous run's outputs"),
        "{}",
        stderr(&o)
    );
    assert!(!out.join("actuators.svg").exists());
    assert!(!out.join("strains_3.svg").exists());
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "old"
    );
    assert!(
        std::fs::read_to_string(out.join("view.html"))
            .unwrap()
            .len()
            > 1000
    );
}

/// An output directory that is a file, or lies under one, is bad input.
#[test]
fn output_directory_problems_are_bad_input() {
    let dir = tmp("outdir");
    let file = dir.join("a_file");
    std::fs::write(&file, "x").unwrap();
    let scene = examples().join("cantilever_gravity.toml");
    for (out, says) in [
        (file.clone(), "exists and is not a directory"),
        (file.join("sub"), "cannot create it"),
    ] {
        let o = run_scene(&scene, &out);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains(says), "{}", stderr(&o));
        assert!(stderr(&o).contains(out.to_str().unwrap()), "{}", stderr(&o));
    }
    for cmd in ["statics", "modes", "report"] {
        let o = run(&[
            cmd,
            scene.to_str().unwrap(),
            "--out",
            file.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{cmd}: {}", stderr(&o));
        assert!(
            stderr(&o).contains("exists and is not a directory"),
            "{}",
            stderr(&o)
        );
    }
}

/// Scene warnings reach the user from every command, in the errors' layout
/// `FILE:LINE:COL: KEY: message`, on stderr (stdout keeps the JSON clean).
#[test]
fn every_command_prints_the_scene_warnings() {
    let dir = tmp("warnings");
    let text = std::fs::read_to_string(examples().join("tip_load_statics.toml")).unwrap();
    let p = dir.join("warn.toml");
    std::fs::write(
        &p,
        format!("{text}\n[[load]]\nrod = \"{}\"\ns = 0.2\n", rod_name(&text)),
    )
    .unwrap();
    let f = p.to_str().unwrap();
    let out = dir.join("out");
    for args in [
        vec!["statics", f, "--json"],
        vec!["modes", f, "--json"],
        vec!["run", f, "--out", out.to_str().unwrap(), "--quiet"],
    ] {
        let o = run(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let e = stderr(&o);
        let line = e
            .lines()
            .find(|l| l.contains("warning"))
            .unwrap_or_else(|| panic!("{args:?}: no warning in {e}"));
        assert!(
            line.contains(&format!("{f}:")) && line.contains("load["),
            "{line}"
        );
        if args.contains(&"--json") {
            let _: serde_json::Value = stdout_json(&o);
        }
    }
}

fn rod_name(scene: &str) -> String {
    let l = scene.lines().find(|l| l.starts_with("name")).unwrap();
    l.split('"').nth(1).unwrap().to_string()
}

/// `modes --json` marks an unstable equilibrium: the upright rod past its
/// self-weight buckling length (see statics_flags_an_unstable_equilibrium)
/// has ω² < 0, reported as an imaginary frequency; the short stiff one none.
#[test]
fn modes_json_marks_unstable_equilibria() {
    let dir = tmp("modes_unstable");
    let scene = |young: f64| {
        format!(
            "[world]\ngravity = [0.0, 0.0, -9.81]\n[[rod]]\nname = \"arm\"\nlength = 0.5\n\
             pieces = 6\nstrains = [\"ky\", \"qx\", \"qz\"]\n\
             base = {{ position = [0, 0, 0], rotation = [[0,0,-1],[0,1,0],[1,0,0]] }}\n\
             section = {{ shape = \"circle\", radius = 0.01 }}\n\
             material = {{ density = 1000.0, young = {young:e}, poisson = 0.5 }}\n"
        )
    };
    for (young, unstable) in [(1.0e5, true), (1.0e7, false)] {
        let p = dir.join(format!("upright_{young:e}.toml"));
        std::fs::write(&p, scene(young)).unwrap();
        let o = run(&["modes", p.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = stdout_json(&o);
        assert_eq!(v["unstable"], unstable, "E = {young}");
        let f: Vec<f64> = serde_json::from_value(v["frequencies_hz"].clone()).unwrap();
        let im: Vec<f64> = serde_json::from_value(v["imaginary_frequencies_hz"].clone()).unwrap();
        assert_eq!(!im.is_empty(), unstable);
        assert_eq!(f[0] < 0.0, unstable);
        if unstable {
            assert_eq!(im[0], -f[0]);
            assert!(stderr(&o).contains("unstable"), "{}", stderr(&o));
        }
    }
}

#[cfg(unix)]
fn summary_of(out: &Path) -> Option<serde_json::Value> {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).ok()?).ok()
}

/// Runs `scene` into `out`, waits until its summary says `running` with
/// more than `rows_before` rows (and its process id), sends `sig` (kill(1):
/// the workspace denies unsafe code, which libc::kill needs), and returns
/// the exit code, stderr and the final summary.
#[cfg(unix)]
fn signal_a_run(
    scene: &Path,
    out: &Path,
    rows_before: u64,
    sig: &str,
) -> (Option<i32>, String, serde_json::Value) {
    let mut child = bin()
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    loop {
        let s = summary_of(out);
        if let Some(s) = s.filter(|s| s["output_rows"].as_u64().unwrap_or(0) > rows_before) {
            assert_eq!(s["status"], "running");
            assert_eq!(s["pid"], child.id());
            break;
        }
        assert!(start.elapsed().as_secs() < 120, "no running summary");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let kill = std::process::Command::new("kill")
        .args(["-s", sig, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = child.wait().unwrap();
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    (status.code(), err, summary_of(out).unwrap())
}

/// A signal takes effect at the step it arrives in, not at the next output
/// time (issue 26, D09): a run whose only outputs are its start and its end
/// (10⁷ explicit steps between them) stops at once with a true summary.
#[cfg(unix)]
#[test]
fn a_signal_does_not_wait_for_the_next_output_time() {
    let dir = tmp("signal_between_outputs");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 100.0\nintegrator = \"rk4\"\ndt = 1e-5\noutput_every = 100.0",
        &dir,
    );
    let (code, err, s) = signal_a_run(&scene, &dir.join("out"), 0, "TERM");
    assert_eq!(code, Some(1), "{err}");
    let st = s["status"].as_str().unwrap();
    assert!(
        st.contains("interrupted by SIGTERM at t = 0 (1 of 2"),
        "{st}"
    );
    assert_eq!(s["output_rows"], 1);
}

/// A signal that arrives inside one long step — here the first Jacobian and
/// dense factorization of a 3 000-coordinate Rosenbrock step, minutes in
/// this build — still ends the run (issue 26, D09): the watchdog writes a
/// summary that matches the files (the row at t = 0) and says where the
/// run was, and the process exits 1 without waiting for the step.
#[cfg(unix)]
#[test]
fn a_signal_inside_a_long_step_ends_the_run() {
    let dir = tmp("signal_inside_a_step");
    let scene = dir.join("long_step.toml");
    std::fs::write(
        &scene,
        "[world]\ngravity = [0, 0, -9.81]\n[[rod]]\nname = \"a\"\nlength = 0.3\n\
         strains = [\"ky\", \"qx\", \"qz\"]\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 100.0 }\n\
         pieces = 1000\n[run]\nintegrator = \"rosenbrock\"\nduration = 0.01\n",
    )
    .unwrap();
    let out = dir.join("out");
    let (code, err, s) = signal_a_run(&scene, &out, 0, "TERM");
    assert_eq!(code, Some(1), "{err}");
    let st = s["status"].as_str().unwrap();
    assert!(
        st.contains("interrupted by SIGTERM at t = 0 (1 of 1001 output rows written) inside a long computation"),
        "{st}"
    );
    assert!(err.contains("inside a long computation"), "{err}");
    let (_, rows) = csv(&out.join("trajectory.csv"));
    assert_eq!(rows.len(), 1);
    assert_eq!(s["steps"], 0);
}

/// SIGTERM and SIGINT end a run cleanly: the summary is current while it
/// runs ("running", the process id), and after the signal it says so and
/// matches the files (rows written, last time), the figures of what exists
/// are drawn, exit 1.
#[cfg(unix)]
#[test]
fn a_signal_ends_the_run_with_a_true_summary() {
    for (sig, name) in [("TERM", "SIGTERM"), ("INT", "SIGINT")] {
        let dir = tmp(&format!("signal_{name}"));
        // A long run: explicit steps on a stiff rod (many seconds).
        let scene = with_run(
            "cantilever_gravity.toml",
            "[run]\nduration = 100.0\nintegrator = \"rk4\"\ndt = 1e-5\noutput_every = 0.001",
            &dir,
        );
        let out = dir.join("out");
        let (code, err, s) = signal_a_run(&scene, &out, 2, sig);
        assert_eq!(code, Some(1), "{name}: {err}");
        let st = s["status"].as_str().unwrap();
        assert!(st.contains(&format!("interrupted by {name}")), "{st}");
        let (_, rows) = csv(&out.join("trajectory.csv"));
        assert_eq!(s["output_rows"].as_u64().unwrap() as usize, rows.len());
        // Within an ulp or two: serde_json's default float parser does not
        // round-trip every shortest decimal exactly (0.10300000000000001).
        let (ft, last) = (s["final_time"].as_f64().unwrap(), rows.last().unwrap()[0]);
        assert!(
            (ft - last).abs() <= 4.0 * f64::EPSILON * last,
            "{ft} vs {last}"
        );
        let (_, shape) = csv_shape(&out.join("shape.csv"));
        assert_eq!(shape, rows.len() * 65);
        for svg in ["energy.svg", "shapes.svg", "tip_trajectory.svg"] {
            let t = std::fs::read_to_string(out.join(svg)).unwrap();
            assert!(t.contains("</svg>"), "{svg}");
        }
        assert!(out.join("view.html").exists());
    }
}

/// A write error (here the file-size limit, as a full disk would) stops the
/// run with a status that says so, the partial row removed: both CSVs end
/// with whole rows of the same times, no figure is left truncated.
#[cfg(unix)]
#[test]
fn a_write_error_drops_the_partial_row_and_says_so() {
    let dir = tmp("write_error");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 1.0\noutput_every = 0.001",
        &dir,
    );
    let out = dir.join("out");
    // The file-size limit through the shell (ulimit -f counts 512-byte
    // blocks: 586 ≈ 300 kB), SIGXFSZ ignored so the write fails with EFBIG
    // instead of killing the process; an ignored signal stays ignored
    // across exec. (The workspace denies unsafe code, which setrlimit in a
    // pre_exec hook would need.)
    let bin_path = bin().get_program().to_owned();
    let mut cmd = std::process::Command::new("sh");
    cmd.arg("-c")
        .arg("trap '' XFSZ; ulimit -f 586; exec \"$@\"")
        .arg("sh")
        .arg(bin_path)
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
    let o = cmd.output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let s = summary_of(&out).unwrap();
    let st = s["status"].as_str().unwrap();
    assert!(st.starts_with("error: writing shape.csv"), "{st}");
    assert!(st.contains("the partial row was removed"), "{st}");
    for f in ["trajectory.csv", "shape.csv"] {
        let t = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(t.ends_with('\n'), "{f} ends in a partial row");
    }
    let (header, rows) = csv(&out.join("trajectory.csv"));
    assert!(rows.iter().all(|r| r.len() == header.len()));
    let (_, shape) = csv_shape(&out.join("shape.csv"));
    assert_eq!(shape, rows.len() * 65, "the same times in both files");
    assert_eq!(s["output_rows"].as_u64().unwrap() as usize, rows.len());
    assert!(rows.len() > 5 && rows.len() < 1001);
    for e in std::fs::read_dir(&out).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with(".svg") || name.ends_with(".html") {
            let t = std::fs::read_to_string(e.path()).unwrap();
            assert!(
                t.contains("</svg>") || t.contains("</html>"),
                "{name} truncated"
            );
        }
    }
}

/// `run --snapshots` chooses the times of the shape and strain figures
/// (the nearest output times, in the legends); a time outside the run is
/// bad input, before anything is written.
#[test]
fn snapshots_choose_the_drawn_times() {
    let dir = tmp("snapshots");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.1\noutput_every = 0.01",
        &dir,
    );
    let out = dir.join("out");
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--snapshots",
        "0.031,0.1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let svg = std::fs::read_to_string(out.join("strains.svg")).unwrap();
    assert!(
        svg.contains("t = 0.03 s") && svg.contains("t = 0.1 s"),
        "legend times"
    );
    assert!(!svg.contains("t = 0.02 s") && !svg.contains("t = 0 s"));
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        dir.join("other").to_str().unwrap(),
        "--snapshots",
        "0.5",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--snapshots"), "{}", stderr(&o));
    assert!(!dir.join("other").exists());
}

/// A reader that stops early (`softrod check SCENE | head`) ends the command
/// quietly with 128 + SIGPIPE, as a shell reports, not with a panic: 2000
/// rods print 185 kB, more than a pipe holds, so the writer meets the
/// closed pipe.
#[cfg(unix)]
#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    let dir = tmp("broken_pipe");
    let rods: String = (0..2000)
        .map(|i| {
            format!(
                "[[rod]]\nname = \"r{i}\"\nlength = 0.1\npieces = 1\n\
                 base = {{ position = [{}, 0.0, 0.0] }}\n\
                 section = {{ shape = \"circle\", radius = 0.001 }}\n\
                 material = {{ density = 1000.0, young = 1.0e6, poisson = 0.5 }}\n",
                0.1 * i as f64
            )
        })
        .collect();
    let scene = dir.join("many.toml");
    std::fs::write(&scene, rods + "[run]\nintegrator = \"dopri5\"\n").unwrap();
    let mut child = bin()
        .args(["check", scene.to_str().unwrap()])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 10];
    std::io::Read::read_exact(child.stdout.as_mut().unwrap(), &mut first).unwrap();
    drop(child.stdout.take());
    let status = child.wait().unwrap();
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(141), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// The rows written on the writer thread, which receives them in batches
/// (issue 30), are every output time's, once each and in order, with the
/// numbers of the facade's own run of the same scene (`Simulation::simulate`:
/// a second path to the same deterministic integration, no files), read
/// back exactly: 101 output times are six whole batches and a partial one.
#[test]
fn trajectory_rows_from_the_writer_thread_match_the_facade_run() {
    let dir = tmp("rows_thread");
    let run_table = "[run]\nduration = 0.1\noutput_every = 0.001";
    let scene = with_run("cantilever_gravity.toml", run_table, &dir);
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&scene).unwrap();
    let (mut sim, _, _) = softrod::Simulation::from_toml(&text, "cantilever_gravity").unwrap();
    let traj = sim.simulate(0.1).unwrap();
    let (header, rows) = csv(&out.join("trajectory.csv"));
    assert_eq!(rows.len(), 101);
    assert_eq!(traj.t.len(), rows.len());
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let n = traj.q[0].len();
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row[col("t")], traj.t[k], "row {k}");
        for i in 0..n {
            assert_eq!(row[col(&format!("q{i}"))], traj.q[k][i], "row {k}, q{i}");
            assert_eq!(
                row[col(&format!("qdot{i}"))],
                traj.qdot[k][i],
                "row {k}, qdot{i}"
            );
        }
    }
    let (_, shape) = csv_shape(&out.join("shape.csv"));
    assert_eq!(shape, rows.len() * 65);
}

/// `shape.csv`'s leading fields, which the writer formats once per time
/// (`t`) or once per run (the rod's name, each sample's `s`), are at every
/// row what the facade's sampling and output times give, formatted here by
/// the standard library's shortest round-trip `Debug` (`0` for zero):
/// two rods with different pieces, three points per piece, and a body.
#[test]
fn shape_csv_leading_fields_match_the_sampling_at_every_row() {
    let dir = tmp("leading");
    let run_table = "[run]\nduration = 0.01\noutput_every = 0.0025\nshape_points_per_piece = 3";
    // The lower rod gets 3 pieces (the upper keeps 4): different samples.
    let scene = with_run("arm_with_payload.toml", run_table, &dir);
    let text = std::fs::read_to_string(&scene).unwrap().replacen(
        "length = 0.2\npieces = 4",
        "length = 0.2\npieces = 3",
        1,
    );
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let (sim, _, _) = softrod::Simulation::from_toml(&text, "arm_with_payload").unwrap();
    let sampling = softrod::record::RodSampling::of_model(sim.model(), Some(3));
    let names: Vec<String> = sim
        .model()
        .rods()
        .iter()
        .map(|r| r.spec.name.clone())
        .collect();
    assert_eq!(names.len(), 2);
    assert_ne!(sampling[0].s.len(), sampling[1].s.len());
    let fmt = |v: f64| {
        if v == 0.0 {
            "0".to_string()
        } else {
            format!("{v:?}")
        }
    };
    let times = softrod::output_times(0.01, 0.0025);
    let shape = std::fs::read_to_string(out.join("shape.csv")).unwrap();
    let mut lines = shape.lines().skip(1);
    for &t in &times {
        for (name, samp) in names.iter().zip(&sampling) {
            for &s in &samp.s {
                let line = lines.next().expect("a row per time, rod and sample");
                let want = format!("{},{},{},", fmt(t), name, fmt(s));
                assert!(line.starts_with(&want), "{line:?} vs {want:?}");
                assert_eq!(line.split(',').count(), 10, "{line}");
            }
        }
    }
    assert!(lines.next().is_none());
}
