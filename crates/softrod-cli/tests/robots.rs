//! `check` and `statics --json` on a scene with bodies and joints
//! (scene-format.md, "Bodies, joints, bases and closures").

mod common;
use common::*;

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/arm_with_payload.toml"
);

#[test]
fn check_lists_joints_and_bodies() {
    let out = run(&["check", SCENE]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("joint of rod 'lower': revolute on 'connector', 1 DoF (q[12..13])"),
        "{text}"
    );
    assert!(text.contains("body 'gripper': mass 0.02 kg"), "{text}");
    assert!(text.contains("degrees of freedom: 25"), "{text}");
}

#[test]
fn statics_json_has_bodies_and_joints_at_the_rod_tips() {
    let out = run(&["statics", SCENE, "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v = stdout_json(&out);
    let bodies = v["bodies"].as_array().unwrap();
    assert_eq!(bodies.len(), 2);
    assert_eq!(bodies[1]["name"], "gripper");
    // The gripper hangs at the lower rod's tip (fixed joint, identity base):
    // same position and rotation as that tip.
    let tip = &v["rods"][1]["tip"];
    for k in 0..3 {
        let a = bodies[1]["position"][k].as_f64().unwrap();
        let b = tip["position"][k].as_f64().unwrap();
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
    let joints = v["joints"].as_array().unwrap();
    let lower = joints.iter().find(|j| j["element"] == "lower").unwrap();
    assert_eq!(lower["type"], "revolute");
    let angle = lower["values"][0].as_f64().unwrap();
    assert_eq!(angle, v["q"][12].as_f64().unwrap());
    // The payload sags the arm: the lower rod's tip is below the upper's.
    assert!(
        tip["position"][2].as_f64().unwrap() < v["rods"][0]["tip"]["position"][2].as_f64().unwrap()
    );
}

/// `run` writes `bodies.csv` (t, body, pose) beside `shape.csv`: the
/// connector and the gripper sit at the tips of the rods they hang from
/// (their base poses are the identity), so each body row equals the last
/// `shape.csv` sample of its parent rod at the same time — two paths (the
/// dynamics' frames for bodies, the rod kinematics carried into the world
/// for shapes) that must agree. The view is drawn with them.
#[test]
fn run_writes_bodies_at_their_parents_tips() {
    let dir = tmp("robots-run");
    let scene = with_run(
        "arm_with_payload.toml",
        "[run]\nduration = 0.05\noutput_every = 0.01\n",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let bodies = csv_cells(&out.join("bodies.csv"));
    let shape = csv_cells(&out.join("shape.csv"));
    assert_eq!(bodies.len(), 6 * 2, "two bodies at six output times");
    let mut moved = 0.0_f64;
    for b in &bodies {
        let parent = if b[1] == "connector" {
            "upper"
        } else {
            "lower"
        };
        let tip = shape
            .iter()
            .rfind(|r| r[0] == b[0] && r[1] == parent)
            .expect("the parent's samples at this time");
        for k in 0..7 {
            let (x, y): (f64, f64) = (b[2 + k].parse().unwrap(), tip[3 + k].parse().unwrap());
            assert!((x - y).abs() < 1e-9, "{} at t = {}: {x} vs {y}", b[1], b[0]);
        }
        if b[1] == "gripper" {
            moved = moved.max((b[4].parse::<f64>().unwrap()).abs());
        }
    }
    assert!(moved > 1e-4, "the gripper falls under gravity");
    assert!(out.join("view.html").exists());
    // view.json names the bodies as boxes of their mass and inertia: the
    // gripper, 20 g with I = 4e-6 kg m² about every axis, is a cube of
    // edge sqrt(6 I / m) = 0.0346 m.
    let view = json_file(&out.join("view.json"));
    let bodies = view["bodies"].as_array().unwrap();
    assert_eq!(bodies.len(), 2);
    let g = bodies.iter().find(|b| b["name"] == "gripper").unwrap();
    let edge = (6.0_f64 * 4e-6 / 0.02).sqrt();
    for k in 0..3 {
        assert!((g["size"][k].as_f64().unwrap() - edge).abs() < 1e-12, "{g}");
    }
}
