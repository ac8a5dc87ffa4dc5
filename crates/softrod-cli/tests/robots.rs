//! `check` and `statics --json` on a scene with bodies and joints
//! (scene-format.md, "Bodies, joints, bases and closures").

use std::process::Command;

fn softrod(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(args)
        .output()
        .expect("runs")
}

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/arm_with_payload.toml"
);

#[test]
fn check_lists_joints_and_bodies() {
    let out = softrod(&["check", SCENE]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
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
    let out = softrod(&["statics", SCENE, "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
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
