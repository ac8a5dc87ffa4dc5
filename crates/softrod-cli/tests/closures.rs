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

/// `softrod linearize` on a closed scene (docs/theory-derivatives.md CD9):
/// a rope pinned at both ends (spherical joint at its base, ball closure
/// at its tip) sagging under gravity, undamped. The eigenvalues of `A`
/// are the constrained motion's `±iω`, with `ω` what `softrod modes`
/// finds on the null space of the closure rows (a second algorithm), and
/// the Baumgarte stabilization's `−α`, a double per independent row
/// (here 3: 6 eigenvalues).
#[test]
fn linearize_of_a_closed_scene_agrees_with_modes() {
    let dir = std::env::temp_dir().join(format!("softrod_closed_linearize_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("rope.toml");
    std::fs::write(
        &p,
        "[world]\ngravity = [0.0, 0.0, -9.81]\n\
         [[rod]]\nname = \"rope\"\nlength = 0.5\npieces = 4\n\
         joint = { type = \"spherical\" }\n\
         section = { shape = \"circle\", radius = 0.01 }\n\
         material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }\n\
         [[closure]]\nname = \"pin\"\ntype = \"ball\"\na = { element = \"rope\" }\n\
         b = { element = \"world\", base = { position = [0.5, 0, 0] } }\n",
    )
    .unwrap();
    let path = p.to_str().unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&ok(&softrod(&["linearize", path, "--json"]))).unwrap();
    assert_eq!(v["equilibrium"], "statics");
    assert!(v["xdot_residual"].as_f64().unwrap() < 1e-6);
    assert_eq!(v["closure_rows"], 3);
    let alpha = v["baumgarte_rate"].as_f64().unwrap();
    let a_rows = v["A"].as_array().unwrap();
    let n = a_rows.len();
    let a = nalgebra::DMatrix::from_fn(n, n, |i, j| a_rows[i][j].as_f64().unwrap());
    let ev = a.complex_eigenvalues();
    let stab = ev
        .iter()
        .filter(|z| (z.re + alpha).hypot(z.im) < 1e-3 * alpha)
        .count();
    assert_eq!(stab, 6, "{ev}");
    let mut omega: Vec<f64> = ev
        .iter()
        .filter(|z| z.im > 1e-3 && z.re.abs() < 1e-6 * z.im)
        .map(|z| z.im)
        .collect();
    omega.sort_by(f64::total_cmp);
    let m: serde_json::Value =
        serde_json::from_str(&ok(&softrod(&["modes", path, "--json", "--count", "6"]))).unwrap();
    let f: Vec<f64> = m["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .filter(|x| *x > 0.0)
        .collect();
    assert!(f.len() >= 4, "{m}");
    for (k, fk) in f.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * fk;
        assert!(
            (omega[k] - w).abs() < 1e-6 * w,
            "mode {k}: {} vs {w}",
            omega[k]
        );
    }
    let text = ok(&softrod(&["linearize", path]));
    assert!(text.contains("constrained"), "{text}");
}
