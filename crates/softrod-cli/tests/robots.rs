//! `check` and `statics --json` on a scene with bodies and joints
//! (scene-format.md, "Bodies, joints, bases and closures").

mod common;
use common::*;
use softrod_testkit::{svg_outlined_rect_centres, svg_texts};

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

/// The arm with its payload run for 0.05 s (outputs every 0.01 s) into
/// `DIR/out`, which it returns.
fn run_arm(dir: &std::path::Path) -> std::path::PathBuf {
    let scene = with_run(
        "arm_with_payload.toml",
        "[run]\nduration = 0.05\noutput_every = 0.01\n",
        dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    out
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
    let out = run_arm(&dir);
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

/// One panel of a geometry figure, read back from the SVG alone: its
/// data-to-pixel map comes from its printed tick labels (value and pixel of
/// the first and last tick on each axis, in the unit its axis label names),
/// not from the plotting code.
struct PanelAxes {
    /// World axes shown (horizontal, vertical): 0 = x, 1 = y, 2 = z.
    axes: (usize, usize),
    /// `pixel = a + b · metres`, horizontal then vertical.
    h: (f64, f64),
    v: (f64, f64),
    /// Figure pixels of the panel's cell, horizontally.
    cell: (f64, f64),
}

impl PanelAxes {
    fn to_px(&self, p: [f64; 3]) -> (f64, f64) {
        (
            self.h.0 + self.h.1 * p[self.axes.0],
            self.v.0 + self.v.1 * p[self.axes.1],
        )
    }
}

/// The projection panels of a shape figure (`x–z`, `y–z`, `x–y` titles in
/// that order, or the one plane of a planar scene; 430 px wide cells, the
/// legend to their right).
fn panels(svg: &str) -> Vec<PanelAxes> {
    const CELL_W: f64 = 430.0;
    let texts = svg_texts(svg);
    let axis = |c: &str| "xyz".find(c).unwrap();
    let mut out = Vec::new();
    let planes: Vec<&str> = ["x–z", "y–z", "x–y"]
        .into_iter()
        .filter(|p| texts.iter().any(|t| t.text == format!("{p} projection")))
        .collect();
    assert!(planes.len() == 1 || planes.len() == 3, "{planes:?}");
    for (k, plane) in planes.iter().enumerate() {
        let cell = (k as f64 * CELL_W, (k + 1) as f64 * CELL_W);
        let mine: Vec<_> = texts
            .iter()
            .filter(|t| t.x >= cell.0 && t.x < cell.1)
            .collect();
        assert!(
            mine.iter().any(|t| t.text == format!("{plane} projection")),
            "panel {k} is {plane}"
        );
        // Axis labels: "x [mm]" (horizontal), "z [mm]" (rotated).
        let label = |rotated: bool| {
            let t = mine
                .iter()
                .find(|t| t.rotated == rotated && t.text.len() > 2 && t.text.as_bytes()[1] == b' ')
                .expect("an axis label");
            let unit = t.text[3..t.text.len() - 1].to_string();
            let per_m = match unit.as_str() {
                "m" => 1.0,
                "mm" => 1e3,
                "µm" => 1e6,
                u => panic!("unit {u}"),
            };
            (axis(&t.text[..1]), per_m)
        };
        let ((ha, h_per_m), (va, v_per_m)) = (label(false), label(true));
        // Ticks: numbers centred under the horizontal axis, right-aligned
        // left of the vertical one.
        let fit = |anchor: &str, per_m: f64, horizontal: bool| {
            let mut ticks: Vec<(f64, f64)> = mine
                .iter()
                .filter(|t| t.anchor == anchor && !t.rotated)
                .filter_map(|t| {
                    let v: f64 = t.text.parse().ok()?;
                    Some((v / per_m, if horizontal { t.x } else { t.y }))
                })
                .collect();
            ticks.sort_by(|a, b| a.0.total_cmp(&b.0));
            assert!(ticks.len() >= 2, "ticks of panel {k}");
            let ((m0, p0), (m1, p1)) = (ticks[0], ticks[ticks.len() - 1]);
            let b = (p1 - p0) / (m1 - m0);
            (p0 - b * m0, b)
        };
        out.push(PanelAxes {
            axes: (ha, va),
            h: fit("middle", h_per_m, true),
            v: fit("end", v_per_m, false),
            cell,
        });
    }
    out
}

/// Every body has a mark, in every projection, where the panel's printed
/// axes put its position (a tick is placed to the pixel, so the map read
/// back is good to ~1 px over the figure), and its name is printed.
fn assert_bodies_drawn(svg: &str, bodies: &[(String, [f64; 3])]) {
    let marks = svg_outlined_rect_centres(svg);
    for p in panels(svg) {
        for (name, pos) in bodies {
            let (u, v) = p.to_px(*pos);
            assert!(u > p.cell.0 && u < p.cell.1, "{name} inside its panel");
            let d = marks
                .iter()
                .map(|(x, y)| ((x - u).powi(2) + (y - v).powi(2)).sqrt())
                .fold(f64::INFINITY, f64::min);
            assert!(
                d <= 2.0,
                "'{name}' at {pos:?}: no mark near ({u:.1}, {v:.1}) px in panel {:?} (nearest {d:.1} px)",
                p.axes
            );
        }
    }
    let texts = svg_texts(svg);
    for (name, _) in bodies {
        assert!(texts.iter().any(|t| &t.text == name), "'{name}' named");
    }
}

/// statics_shape.svg marks each body at the position `statics --json`
/// prints for it.
#[test]
fn the_statics_figure_draws_the_bodies_where_they_are() {
    let dir = tmp("statics-figure");
    let out = run(&["statics", SCENE, "--json", "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v = stdout_json(&out);
    let bodies: Vec<(String, [f64; 3])> = v["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let p = |k: usize| b["position"][k].as_f64().unwrap();
            (b["name"].as_str().unwrap().to_string(), [p(0), p(1), p(2)])
        })
        .collect();
    assert_eq!(bodies.len(), 2);
    let svg = std::fs::read_to_string(dir.join("statics_shape.svg")).unwrap();
    assert_bodies_drawn(&svg, &bodies);
}

/// shapes.svg of a run marks each body at its bodies.csv position at the
/// last output time (the last drawn snapshot).
#[test]
fn the_run_shapes_figure_draws_the_bodies_where_they_are() {
    let dir = tmp("run-figure");
    let out = run_arm(&dir);
    let rows = csv_cells(&out.join("bodies.csv"));
    let last = rows.last().unwrap()[0].clone();
    let bodies: Vec<(String, [f64; 3])> = rows
        .iter()
        .filter(|r| r[0] == last)
        .map(|r| {
            let p = |k: usize| r[2 + k].parse::<f64>().unwrap();
            (r[1].clone(), [p(0), p(1), p(2)])
        })
        .collect();
    assert_eq!(bodies.len(), 2);
    let svg = std::fs::read_to_string(out.join("shapes.svg")).unwrap();
    assert_bodies_drawn(&svg, &bodies);
}
