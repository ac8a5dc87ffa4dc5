//! A branched robot through the command line (examples/three_arm_gripper.toml):
//! three cable-driven fingers on one hub. The scene is symmetric under a
//! rotation of 120° about the vertical axis, which nothing in the code
//! knows: every output time, finger k's shape rotated by 120° must be
//! finger k+1's.

mod common;

use common::{csv_cells, run, run_scene, stderr, stdout, tmp, with_run};

#[test]
fn three_fingers_move_with_the_scene_symmetry() {
    let dir = tmp("gripper");
    let scene = with_run(
        "three_arm_gripper.toml",
        "[run]\nduration = 0.6\noutput_every = 0.05\nrtol = 1e-6\natol = 1e-9",
        &dir,
    );
    let check = run(&["check", scene.to_str().unwrap()]);
    assert!(check.status.success(), "{}", stderr(&check));
    let text = stdout(&check);
    for k in 0..3 {
        assert!(
            text.contains(&format!("joint of rod 'finger{k}': fixed on 'hub'")),
            "{text}"
        );
    }
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    // shape.csv: t, rod, s, x, y, z, …; rows of one time, rods in order.
    let rows = csv_cells(&out.join("shape.csv"));
    let (c, s) = (
        (2.0 * std::f64::consts::PI / 3.0).cos(),
        (2.0 * std::f64::consts::PI / 3.0).sin(),
    );
    let point = |r: &Vec<String>| -> [f64; 3] { [3, 4, 5].map(|i| r[i].parse().unwrap()) };
    let mut opened = 0.0_f64;
    let mut compared = 0;
    for t in rows
        .iter()
        .map(|r| r[0].clone())
        .collect::<std::collections::BTreeSet<_>>()
    {
        let of = |k: usize| -> Vec<[f64; 3]> {
            rows.iter()
                .filter(|r| r[0] == t && r[1] == format!("finger{k}"))
                .map(point)
                .collect()
        };
        let fingers = [of(0), of(1), of(2)];
        for k in 0..3 {
            let (a, b) = (&fingers[k], &fingers[(k + 1) % 3]);
            assert_eq!(a.len(), b.len());
            for (p, q) in a.iter().zip(b) {
                let rotated = [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
                let d = (0..3)
                    .map(|i| (rotated[i] - q[i]).powi(2))
                    .sum::<f64>()
                    .sqrt();
                assert!(
                    d < 1e-6,
                    "t = {t}: finger{k} rotated is {d} m off finger{}",
                    (k + 1) % 3
                );
                compared += 1;
            }
        }
        // The cables open the claw: finger 0's tip moves outwards (+x).
        opened = opened.max(fingers[0].last().unwrap()[0] - 0.03);
    }
    assert!(compared > 100, "{compared}");
    assert!(opened > 0.005, "the cables open the fingers by {opened} m");
}
