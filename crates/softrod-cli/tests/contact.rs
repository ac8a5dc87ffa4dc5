//! Contact in the command line (scene-format.md, "Contact: obstacles, rods
//! touching rods, friction"): `check` lists obstacles and the contact
//! settings; bad obstacles exit 2 naming the key.

mod common;

use common::{json_file, run, stderr, stdout, tmp};

const SCENE: &str = r#"
[world]
gravity = [0, 0, -9.81]

[[rod]]
name = "arm"
length = 0.5
pieces = 4
strains = ["ky", "qx"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }

[[body]]
name = "ball"
parent = "world"
base = { position = [0.3, 0, -0.3] }
mass = 0.1
inertia = [1e-4, 1e-4, 1e-4]

[[obstacle]]
name = "table"
shape = "plane"
position = [0, 0, -0.2]
normal = [0, 0, 2]
friction = 0.5

[[obstacle]]
name = "knob"
shape = "sphere"
radius = 0.03
parent = "ball"

[contact]
rods = true
friction = 0.25
"#;

#[test]
fn check_lists_obstacles_and_contact_settings() {
    let dir = tmp("check");
    let scene = dir.join("c.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let o = run(&["check", scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    // The normal as the model has it: unit.
    assert!(
        out.contains(
            "obstacle 'table': plane through [0, 0, -0.2] m, normal [0, 0, 1], fixed in the \
             world, friction 0.5, restitution 0"
        ),
        "{out}"
    );
    assert!(
        out.contains(
            "obstacle 'knob': sphere at [0, 0, 0] m, radius 0.03 m, carried by body 'ball', \
             friction 0, restitution 0"
        ),
        "{out}"
    );
    assert!(
        out.contains(
            "contact between rods: different rods yes, a rod with itself no, friction 0.25, \
             restitution 0"
        ),
        "{out}"
    );
    assert!(out.contains("contact radius of rod 'arm': 0.01 m"), "{out}");
}

#[test]
fn a_scene_without_contact_says_nothing_of_it() {
    let dir = tmp("none");
    let scene = dir.join("n.toml");
    let text = SCENE.split("[[obstacle]]").next().unwrap();
    std::fs::write(&scene, text).unwrap();
    let o = run(&["check", scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stdout(&o).contains("contact between"), "{}", stdout(&o));
    assert!(!stdout(&o).contains("obstacle '"), "{}", stdout(&o));
}

#[test]
fn bad_obstacles_exit_2_naming_the_key() {
    let dir = tmp("bad");
    for (edit, path) in [
        ("radius = 0.03", "obstacle[1].radius"),
        ("normal = [0, 0, 2]", "obstacle[0].normal"),
        ("parent = \"ball\"", "obstacle[1].parent"),
        ("friction = 0.5", "obstacle[0].friction"),
    ] {
        let bad = match edit {
            "radius = 0.03" => SCENE.replace(edit, "radius = -0.03"),
            "normal = [0, 0, 2]" => SCENE.replace(edit, "normal = [0, 0, 0]"),
            "parent = \"ball\"" => SCENE.replace(edit, "parent = \"bal\""),
            _ => SCENE.replace(edit, "friction = -0.5"),
        };
        let scene = dir.join("b.toml");
        std::fs::write(&scene, bad).unwrap();
        for cmd in ["check", "statics", "run"] {
            let out = dir.join("out");
            let o = run(&[cmd, scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
            let o = if cmd == "check" {
                run(&[cmd, scene.to_str().unwrap()])
            } else {
                o
            };
            assert_eq!(o.status.code(), Some(2), "{cmd} {edit}: {}", stderr(&o));
            let err = stderr(&o);
            assert!(err.contains(path), "{cmd} {edit}: {err}");
            assert!(!out.exists(), "{cmd} {edit}: wrote {}", out.display());
        }
    }
}

/// A soft cantilever along x (radius 1 cm) under gravity droops onto a
/// frictionless table 2 cm below its centreline.
const DROOP: &str = r#"
[world]
gravity = [0, 0, -9.81]

[[rod]]
name = "arm"
length = 0.3
pieces = 6
strains = ["ky", "qx"]
section = { shape = "circle", radius = 0.01 }
material = { density = 1000.0, young = 1.0e6, poisson = 0.5, viscosity = 2000.0 }

[[obstacle]]
name = "table"
shape = "plane"
position = [0, 0, -0.02]
normal = [0, 0, 1]

[run]
duration = 0.1
output_every = 0.01
"#;

/// `statics --json` lists the contacts; each entry's gap is the distance
/// of its centreline point to the table less the radius (computed here
/// from the point), its normal the table's, its force along the normal
/// (frictionless) and pushing the rod up; `max_penetration` is the largest
/// `−gap`.
#[test]
fn statics_json_lists_contacts_consistent_with_the_geometry() {
    let dir = tmp("statics");
    let scene = dir.join("droop.toml");
    std::fs::write(&scene, DROOP).unwrap();
    let o = run(&["statics", scene.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let contacts = v["contacts"].as_array().expect("contacts");
    assert!(
        !contacts.is_empty(),
        "the rod should rest on the table: {v}"
    );
    let mut deepest = 0.0f64;
    for c in contacts {
        assert_eq!(c["a"], "arm");
        assert_eq!(c["b"], "table");
        assert!(c["b_s"].is_null());
        let s = c["s"].as_f64().unwrap();
        assert!((0.0..=0.3).contains(&s));
        let p: Vec<f64> = c["point"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let n: Vec<f64> = c["normal"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let f: Vec<f64> = c["force"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let gap = c["gap"].as_f64().unwrap();
        // `point` is where the rod's surface meets the normal (its
        // centreline point less r n): the centreline is r above it.
        let by_hand = ((p[2] + 0.01) - (-0.02)) - 0.01;
        assert!((gap - by_hand).abs() < 1e-12, "gap {gap} vs {by_hand}");
        assert!(n[0].abs() < 1e-12 && n[1].abs() < 1e-12 && (n[2] - 1.0).abs() < 1e-12);
        assert!(
            f[2] >= 0.0
                && f[0].abs() <= 1e-12 * f[2].abs().max(1.0)
                && f[1].abs() <= 1e-12 * f[2].abs().max(1.0),
            "{f:?}"
        );
        deepest = deepest.max(-gap);
    }
    assert_eq!(v["max_penetration"].as_f64().unwrap(), deepest);
}

/// `run` writes contacts.csv with the contract's header, one row per
/// contact and output time; summary.json's max_penetration and
/// max_contacts are those of the file's rows (recomputed here).
#[test]
fn run_writes_contacts_csv_and_the_summary_agrees_with_it() {
    let dir = tmp("run");
    let scene = dir.join("droop.toml");
    std::fs::write(&scene, DROOP).unwrap();
    let out = dir.join("out");
    let o = common::run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("contacts.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,a,s,b,b_s,x,y,z,nx,ny,nz,gap,fx,fy,fz,state"
    );
    let mut per_t: std::collections::BTreeMap<String, usize> = Default::default();
    let mut deepest = 0.0f64;
    for l in lines {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.len(), 16, "{l}");
        assert_eq!((f[1], f[3], f[4]), ("arm", "table", ""));
        assert!(f[15] == "stick" || f[15] == "slip", "{l}");
        let z: f64 = f[7].parse().unwrap();
        let gap: f64 = f[11].parse().unwrap();
        assert!((gap - ((z + 0.01 + 0.02) - 0.01)).abs() < 1e-12, "{l}");
        deepest = deepest.max(-gap);
        *per_t.entry(f[0].to_owned()).or_default() += 1;
    }
    assert!(!per_t.is_empty(), "the rod never touched the table");
    let summary = json_file(&out.join("summary.json"));
    assert_eq!(summary["max_penetration"].as_f64().unwrap(), deepest);
    assert_eq!(
        summary["max_contacts"].as_u64().unwrap() as usize,
        per_t.values().copied().max().unwrap()
    );
}

/// A scene without contact writes no contacts.csv and no contact keys.
#[test]
fn no_contact_no_contacts_file() {
    let dir = tmp("plain");
    let scene = dir.join("plain.toml");
    std::fs::write(&scene, DROOP.split("[[obstacle]]").next().unwrap()).unwrap();
    let out = dir.join("out");
    let o = common::run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("contacts.csv").exists());
    let summary = json_file(&out.join("summary.json"));
    assert!(summary.get("max_penetration").is_none());
}

/// A rod that starts inside an obstacle: exit 2 naming both and the depth,
/// nothing written.
#[test]
fn initial_overlap_exits_2_and_writes_nothing() {
    let dir = tmp("overlap");
    let scene = dir.join("o.toml");
    std::fs::write(
        &scene,
        DROOP.replace("position = [0, 0, -0.02]", "position = [0, 0, 0.0]"),
    )
    .unwrap();
    let out = dir.join("out");
    let o = common::run_scene(&scene, &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("obstacle[0]")
            && err.contains("'arm'")
            && err.contains("'table'")
            && err.contains("1.000e-2"),
        "{err}"
    );
    assert!(!out.exists());
}

/// examples/crossing_rods.toml: `run` writes the pair to contacts.csv
/// with the other rod's name and arc length (`b`, `b_s`), where the upper
/// rod passes over the lower (upper's s ≈ 0.3 m, lower's ≈ 0.1 m), its
/// force never pulling the upper rod down; `statics --json` lists the same
/// pair.
#[test]
fn crossing_rods_example_reports_the_pair() {
    let dir = tmp("crossing");
    let scene = common::examples().join("crossing_rods.toml");
    let out = dir.join("out");
    let o = common::run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(out.join("contacts.csv")).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert!(!rows.is_empty(), "the rods never touched");
    for f in &rows {
        assert_eq!((f[1], f[3]), ("upper", "lower"), "{f:?}");
        let (s, b_s): (f64, f64) = (f[2].parse().unwrap(), f[4].parse().unwrap());
        assert!((s - 0.3).abs() < 0.01 && (b_s - 0.1).abs() < 0.01, "{f:?}");
        // Never pulling (zero while an opening contact's damping would).
        let fz: f64 = f[14].parse().unwrap();
        assert!(fz >= 0.0, "{f:?}");
    }
    let o = run(&["statics", scene.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let contacts = v["contacts"].as_array().expect("contacts");
    assert_eq!(contacts.len(), 1, "{v}");
    assert_eq!(contacts[0]["b"], "lower");
    assert!((contacts[0]["b_s"].as_f64().unwrap() - 0.1).abs() < 0.01);
}

/// Two rods that start overlapping: exit 2 naming both rods, both arc
/// lengths and the depth; nothing written.
#[test]
fn overlapping_rods_exit_2_and_write_nothing() {
    let dir = tmp("rods_overlap");
    let text = std::fs::read_to_string(common::examples().join("crossing_rods.toml")).unwrap();
    let scene = dir.join("o.toml");
    std::fs::write(
        &scene,
        text.replace(
            "position = [0.0, 0.0, 0.0205]",
            "position = [0.0, 0.0, 0.015]",
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = common::run_scene(&scene, &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("'upper'")
            && err.contains("'lower'")
            && err.contains("s = 0.300000")
            && err.contains("s = 0.100000")
            && err.contains("5.000e-3"),
        "{err}"
    );
    assert!(!out.exists());
}

/// A concentrated load no longer sinks a contact beyond the bound: the
/// contact stiffness follows the force carried (CT15), so a 2 N load on the
/// dropped rod's tip (130 times the tip point's weight; it sank 43 % of the
/// radius with the stiffness of the points' own weight) stays within the
/// 10 % bound over the whole run, landing included, and the run says
/// nothing; the same drop without the load stays within it too. A load no
/// stiffness can follow within a step (2 kN, suddenly) stops the run with
/// an error naming the rod, `s`, the obstacle, the time and the depth, a
/// non-zero exit, and a summary that says so.
#[test]
fn penetration_stays_within_the_bound_or_stops_the_run() {
    let dir = tmp("penetration-bound");
    let run_table = "[run]\nduration = 0.2\nrtol = 1.0e-5\natol = 1.0e-8\noutput_every = 5.0e-3\n";
    let quiet = common::with_run("rod_dropped_on_table.toml", run_table, &dir);
    let o = common::run_scene(&quiet, &dir.join("quiet"));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let s = json_file(&dir.join("quiet/summary.json"));
    let pen = s["max_penetration"].as_f64().unwrap();
    assert!(pen > 0.0 && pen < 0.1 * 0.01, "{pen}");
    assert!(!stderr(&o).contains("sank"), "{}", stderr(&o));
    let pressed = |name: &str, force: f64| {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(
            &path,
            common::example_with_run("rod_dropped_on_table.toml", "")
                + &format!("[[load]]\nrod = \"rod\"\ns = 0.2\nforce = [0.0, 0.0, {force:?}]\n")
                + run_table,
        )
        .unwrap();
        let out = dir.join(name);
        let o = run(&[
            "run",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        (o, json_file(&out.join("summary.json")))
    };
    let (o, s) = pressed("pressed", -2.0);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let pen = s["max_penetration"].as_f64().unwrap();
    assert!(pen > 0.0 && pen < 0.1 * 0.01, "{pen}");
    assert!(!stderr(&o).contains("sank"), "{}", stderr(&o));
    let (o, s) = pressed("crushed", -2000.0);
    assert_ne!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("rod 0 ('rod') penetrates obstacle 'table' at s = 0.200000 m, t = ")
            && err.contains("> bound 1.500e-3 m"),
        "{err}"
    );
    let status = s["status"].as_str().unwrap();
    assert!(status.starts_with("error"), "{status}");
}
