//! What a journal asks of the figures: curves placed to a fraction of a
//! pixel (checked against the panel's own map of the data), a planar scene
//! drawn in its one plane, snapshot times in a perceptually ordered
//! colormap with every time labelled, and legends off the data (the
//! work–precision chart of `softrod report` included).

use softrod_testkit::svg_texts;
use softrod_viz::plot::{self, Figure, PanelInfo, RodCurve, ShapeSnapshot, WorkPrecisionPoint};

/// A rod bent into a quarter circle of radius 0.3 m in the x–z plane, its
/// curvature growing with `k`, sampled at 60 points.
fn arc(k: usize, y: f64) -> Vec<[f64; 3]> {
    let angle = 0.25 * (k as f64 + 1.0);
    (0..60)
        .map(|i| {
            let a = angle * i as f64 / 59.0;
            [
                0.3 * a.sin() / angle * 1.3,
                y,
                -0.3 * (1.0 - a.cos()) / angle,
            ]
        })
        .collect()
}

fn snapshots(n: usize, y_of: impl Fn(usize) -> f64) -> Vec<ShapeSnapshot> {
    (0..n)
        .map(|k| ShapeSnapshot {
            t: Some(0.2 * k as f64),
            rods: vec![RodCurve {
                name: "arm".into(),
                points: arc(k, y_of(k)),
            }],
            bodies: Vec::new(),
        })
        .collect()
}

/// `(stroke colour, points)` of every data curve: the polylines drawn
/// with round joins (the legend's swatches and the grid are plotters' own).
fn polylines(svg: &str) -> Vec<(String, Vec<(f64, f64)>)> {
    svg.split("<polyline")
        .skip(1)
        .filter(|e| e[..e.find("/>").unwrap()].contains("stroke-linejoin=\"round\""))
        .map(|e| {
            let tag = &e[..e.find("/>").unwrap()];
            let attr = |k: &str| {
                let at = tag.find(&format!(" {k}=\"")).unwrap() + k.len() + 3;
                tag[at..at + tag[at..].find('"').unwrap()].to_string()
            };
            let points = attr("points")
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            (attr("stroke"), points)
        })
        .collect()
}

/// The panel's map from data to figure pixels, from its ranges and
/// plotting rectangle alone (the last pixel column and row are the ranges'
/// ends, as plotters places its ticks).
fn to_px(p: &PanelInfo, x: f64, y: f64) -> (f64, f64) {
    let ((l, t), (r, b)) = p.plot_rect;
    let (l, t, r, b) = (
        f64::from(l),
        f64::from(t),
        f64::from(r - 1),
        f64::from(b - 1),
    );
    (
        l + (r - l) * (x - p.x_range.0) / (p.x_range.1 - p.x_range.0),
        b - (b - t) * (y - p.y_range.0) / (p.y_range.1 - p.y_range.0),
    )
}

fn distance_to(q: (f64, f64), line: &[(f64, f64)]) -> f64 {
    line.windows(2)
        .map(|w| {
            let ((ax, ay), (bx, by)) = (w[0], w[1]);
            let (dx, dy) = (bx - ax, by - ay);
            let u = (((q.0 - ax) * dx + (q.1 - ay) * dy) / (dx * dx + dy * dy).max(1e-300))
                .clamp(0.0, 1.0);
            (q.0 - ax - u * dx).hypot(q.1 - ay - u * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

fn legend_off_data(f: &Figure, labels: &[String]) {
    let right = f.panels.iter().map(|p| p.plot_rect.1.0).max().unwrap() as f64;
    let texts = svg_texts(&f.svg);
    for l in labels {
        let t = texts
            .iter()
            .find(|t| &t.text == l)
            .unwrap_or_else(|| panic!("legend entry {l:?} missing"));
        assert!(
            t.x > right,
            "legend entry {l:?} at x = {}, panels end at {right}",
            t.x
        );
    }
}

#[test]
fn a_planar_scene_is_drawn_in_its_plane_and_a_3d_one_in_three() {
    let f = plot::shapes("planar", &snapshots(6, |_| 0.0)).unwrap();
    assert_eq!(f.panels.len(), 1);
    assert_eq!(f.panels[0].title, "x–z projection");
    assert!(f.panels[0].x_label.starts_with("x [") && f.panels[0].y_label.starts_with("z ["));
    let f = plot::shapes("3-D", &snapshots(6, |k| 0.01 * k as f64)).unwrap();
    assert_eq!(f.panels.len(), 3);
    // The tip path of the planar motion too.
    let tips = vec![RodCurve {
        name: "arm".into(),
        points: (0..6).map(|k| *arc(k, 0.0).last().unwrap()).collect(),
    }];
    assert_eq!(plot::tip_trajectory("tip", &tips).unwrap().panels.len(), 1);
}

#[test]
fn curves_are_placed_to_a_tenth_of_a_pixel() {
    let snaps = snapshots(6, |_| 0.0);
    let f = plot::shapes("planar", &snaps).unwrap();
    let panel = &f.panels[0];
    let lines = polylines(&f.svg);
    assert_eq!(lines.len(), snaps.len());
    let mut fractional = 0;
    for (s, (_, line)) in snaps.iter().zip(&lines) {
        for p in &s.rods[0].points {
            let q = to_px(panel, p[0], p[2]);
            // Decimation (0.1 px) plus the printed hundredths (0.005 √2).
            let d = distance_to(q, line);
            assert!(d <= 0.1 + 0.0075, "{q:?} is {d} px off its curve");
        }
        fractional += line
            .iter()
            .filter(|(x, y)| x.fract() != 0.0 || y.fract() != 0.0)
            .count();
    }
    assert!(fractional > 0, "every vertex on a whole pixel");
}

#[test]
fn snapshot_times_are_ordered_in_lightness_and_labelled() {
    for rods in [1, 3] {
        let snaps: Vec<ShapeSnapshot> = snapshots(7, |k| 0.01 * k as f64)
            .into_iter()
            .map(|mut s| {
                let r = s.rods[0].clone();
                s.rods = (0..rods)
                    .map(|i| RodCurve {
                        name: format!("rod {i}"),
                        points: r
                            .points
                            .iter()
                            .map(|p| [p[0], p[1] + 0.1 * i as f64, p[2]])
                            .collect(),
                    })
                    .collect();
                s
            })
            .collect();
        let f = plot::shapes("times", &snaps).unwrap();
        // One colour per time, in the first panel's drawing order.
        let lines = polylines(&f.svg);
        let colours: Vec<String> = lines
            .iter()
            .step_by(rods)
            .take(snaps.len())
            .map(|l| l.0.clone())
            .collect();
        let luminance = |hex: &str| {
            let c =
                |i: usize| f64::from(u8::from_str_radix(&hex[1 + 2 * i..3 + 2 * i], 16).unwrap());
            0.2126 * c(0) + 0.7152 * c(1) + 0.0722 * c(2)
        };
        assert_eq!(colours.len(), snaps.len(), "{rods} rods");
        let l: Vec<f64> = colours.iter().map(|c| luminance(c)).collect();
        assert!(
            l.windows(2).all(|w| w[1] > w[0] + 5.0),
            "{rods} rods: {colours:?} {l:?}"
        );
        let labels: Vec<String> = ["0 s", "0.2 s", "0.4 s", "0.6 s", "0.8 s", "1 s", "1.2 s"]
            .iter()
            .map(|t| format!("t = {t}"))
            .collect();
        legend_off_data(&f, &labels);
    }
}

#[test]
fn the_work_precision_legend_is_beside_the_chart() {
    let points: Vec<WorkPrecisionPoint> = ["esdirk", "dopri5"]
        .iter()
        .enumerate()
        .flat_map(|(g, name)| {
            (0..5).map(move |k| WorkPrecisionPoint {
                group: name.to_string(),
                wall: 1e-3 * 2f64.powi(k + g as i32),
                error: 1e-3 / 10f64.powi(k),
                pareto: g == 0,
            })
        })
        .collect();
    let f = plot::work_precision("report", &points).unwrap();
    legend_off_data(
        &f,
        &["esdirk".into(), "dopri5".into(), "Pareto front".into()],
    );
}
