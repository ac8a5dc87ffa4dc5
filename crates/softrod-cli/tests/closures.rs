//! `check`, `statics --json` and `run` on a closed scene: the parallel
//! robot of examples/parallel_robot.toml (scene-format.md, "Bodies, joints,
//! bases and closures"; docs/scene-format-extensions.md).

use std::process::Command;

fn softrod(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(args)
        .output()
        .expect("runs")
}

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/parallel_robot.toml"
);

fn ok(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout.clone()).unwrap()
}

#[test]
fn check_lists_closures_and_the_net_dof() {
    let text = ok(&softrod(&["check", SCENE]));
    assert!(
        text.contains("closure 'leg2 weld': weld, a = rod 'leg2' at its tip, b = body 'platform'"),
        "{text}"
    );
    assert!(text.contains("6 constraints"), "{text}");
    assert!(text.contains("closure 'leg3 ball': ball"), "{text}");
    // 3 legs × 4 pieces × 4 strains, 6 + 3 independent constraints.
    assert!(text.contains("degrees of freedom: 48"), "{text}");
    assert!(
        text.contains("closure constraints: 9, independent at the initial state: 9; net DoF: 39"),
        "{text}"
    );
    assert!(text.contains("closures"), "{text}");
}

fn vec3(v: &serde_json::Value) -> [f64; 3] {
    [0, 1, 2].map(|k| v[k].as_f64().unwrap())
}

fn mat3(v: &serde_json::Value) -> [[f64; 3]; 3] {
    [0, 1, 2].map(|i| vec3(&v[i]))
}

#[test]
fn statics_holds_the_loop_where_the_rods_say() {
    let v: serde_json::Value =
        serde_json::from_str(&ok(&softrod(&["statics", SCENE, "--json"]))).unwrap();
    let closures = v["closures"].as_array().unwrap();
    assert_eq!(closures.len(), 2);
    assert_eq!(closures[0]["name"], "leg2 weld");
    assert_eq!(closures[1]["type"], "ball");
    for c in closures {
        assert!(c["residual"].as_f64().unwrap() < 1e-12, "{c}");
    }
    // Independently of the closure code: the rod kinematics put leg 2's
    // and leg 3's tips on the platform's corners (platform pose from the
    // body frames), leg 2's tip turned like the corner frame.
    let plat = &v["bodies"][0];
    let (pp, pr) = (vec3(&plat["position"]), mat3(&plat["rotation"]));
    let corner = |y: f64| {
        let local = [-0.025, y, 0.0];
        [0, 1, 2].map(|i| pp[i] + (0..3).map(|j| pr[i][j] * local[j]).sum::<f64>())
    };
    let tip = |r: usize| vec3(&v["rods"][r]["tip"]["position"]);
    for (r, y) in [(1, 0.04330127018922193), (2, -0.04330127018922193)] {
        let (a, b) = (tip(r), corner(y));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-9, "rod {r}: {a:?} vs {b:?}");
        }
    }
    // Weld: R_tip = R_platform · R_corner, R_corner = the legs' base rotation.
    let rc = [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
    let rt = mat3(&v["rods"][1]["tip"]["rotation"]);
    for i in 0..3 {
        for j in 0..3 {
            let want: f64 = (0..3).map(|k| pr[i][k] * rc[k][j]).sum();
            assert!((rt[i][j] - want).abs() < 1e-9, "R[{i}][{j}]");
        }
    }
    // The sideways load moves the platform along it.
    assert!(pp[0] > 0.005 && pp[1] > 0.0, "{pp:?}");
}

#[test]
fn run_reports_a_bounded_closure_residual() {
    let dir = std::env::temp_dir().join(format!("softrod-closures-run-{}", std::process::id()));
    let d = dir.to_str().unwrap();
    ok(&softrod(&["run", SCENE, "--out", d, "--quiet"]));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["status"], "ok");
    let r = s["closure_residual_max"].as_f64().unwrap();
    // Below the warning level, 1e-6 of the longest rod (0.3 m).
    assert!(r < 3e-7, "closure residual {r:e}");
    assert!(dir.join("bodies.csv").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_closure_that_does_not_hold_is_an_input_error() {
    let text = std::fs::read_to_string(SCENE).unwrap().replacen(
        "position = [-0.025, -0.04330127018922193, 0.0] }",
        "position = [-0.02, -0.04330127018922193, 0.0] }",
        1,
    );
    let path =
        std::env::temp_dir().join(format!("softrod-closures-bad-{}.toml", std::process::id()));
    std::fs::write(&path, text).unwrap();
    let out = softrod(&["check", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("closure[1]") && err.contains("leg3 ball"),
        "{err}"
    );
    assert!(err.contains("does not hold"), "{err}");
    std::fs::remove_file(&path).ok();
}
