//! The figures' numbers: equal aspect (metres per pixel the same across and
//! up, and in every panel of a figure), data inside the ranges, labels with
//! units and legends present and off the data, and errors on bad input.

use softrod_testkit::svg_outlined_rect_centres;
use softrod_viz::VizError;
use softrod_viz::demo::SwingingRods;
use softrod_viz::plot::{
    self, ActuatorSeries, BodyMark, EnergySeries, Figure, Mode, ModeShapes, NamedSeries, PanelInfo,
    RodCurve, ShapeSnapshot, StrainComponent, StrainProfiles,
};

/// Relative agreement of the two scales of an equal-aspect panel: both are
/// computed from the same pixel sizes and one scale in f64.
const ASPECT_RTOL: f64 = 1e-12;

/// `(x, text)` of every `<text>` element.
fn texts(svg: &str) -> Vec<(f64, String)> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find("<text") {
        let tag_end = i + rest[i..].find('>').unwrap();
        let tag = &rest[i..tag_end];
        let x = tag
            .split("x=\"")
            .nth(1)
            .and_then(|v| v.split('"').next())
            .and_then(|v| v.parse().ok())
            .unwrap_or(f64::NAN);
        let close = tag_end + rest[tag_end..].find("</text>").unwrap();
        out.push((x, rest[tag_end + 1..close].trim().to_string()));
        rest = &rest[close..];
    }
    out
}

fn has_text(f: &Figure, t: &str) -> bool {
    texts(&f.svg).iter().any(|(_, s)| s == t)
}

fn scale(p: &PanelInfo) -> (f64, f64) {
    (
        (p.x_range.1 - p.x_range.0) / f64::from(p.plot_px.0),
        (p.y_range.1 - p.y_range.0) / f64::from(p.plot_px.1),
    )
}

fn assert_equal_aspect(f: &Figure) {
    let s0 = scale(&f.panels[0]).0;
    for p in &f.panels {
        assert!(p.equal_aspect);
        let (sx, sy) = scale(p);
        assert!(
            (sx - sy).abs() <= ASPECT_RTOL * sx,
            "{}: {sx} vs {sy} m/px",
            p.title
        );
        assert!(
            (sx - s0).abs() <= ASPECT_RTOL * s0,
            "{}: scale {sx} vs first panel {s0}",
            p.title
        );
        let w = (p.plot_rect.1.0 - p.plot_rect.0.0) as u32;
        let h = (p.plot_rect.1.1 - p.plot_rect.0.1) as u32;
        assert_eq!((w, h), p.plot_px);
    }
}

fn inside(p: &PanelInfo, a: f64, b: f64) -> bool {
    (p.x_range.0..=p.x_range.1).contains(&a) && (p.y_range.0..=p.y_range.1).contains(&b)
}

/// Legend texts lie right of every panel's plotting area.
fn assert_legend_off_data(f: &Figure, labels: &[&str]) {
    let right = f.panels.iter().map(|p| p.plot_rect.1.0).max().unwrap() as f64;
    let all = texts(&f.svg);
    for l in labels {
        let (x, _) = all
            .iter()
            .find(|(_, s)| s == l)
            .unwrap_or_else(|| panic!("legend entry {l:?} missing"));
        assert!(
            *x > right,
            "legend entry {l:?} at x = {x}, panels end at {right}"
        );
    }
}

fn tips(rods: usize, length: f64) -> Vec<RodCurve> {
    let view = SwingingRods {
        rods,
        length,
        radius: 0.02 * length,
        times: 41,
        ..SwingingRods::default()
    }
    .build();
    view.rods
        .iter()
        .map(|r| RodCurve {
            name: r.name.clone(),
            points: r.frames.iter().map(|f| f[f.len() - 1].position).collect(),
        })
        .collect()
}

#[test]
fn tip_trajectory_has_three_equal_aspect_projections() {
    let tips = tips(3, 0.5);
    let f = plot::tip_trajectory("tip", &tips).unwrap();
    assert_eq!(f.panels.len(), 3);
    assert_equal_aspect(&f);
    let planes = [(0, 2, "x–z"), (1, 2, "y–z"), (0, 1, "x–y")];
    for (p, (a, b, name)) in f.panels.iter().zip(planes) {
        assert_eq!(p.title, format!("{name} projection"));
        assert_eq!(p.x_label, format!("{} [m]", ["x", "y", "z"][a]));
        assert_eq!(p.y_label, format!("{} [m]", ["x", "y", "z"][b]));
        for t in &tips {
            assert!(
                t.points.iter().all(|q| inside(p, q[a], q[b])),
                "{name}: data outside"
            );
        }
    }
    for l in ["x [m]", "y [m]", "z [m]", "x–z projection", "tip"] {
        assert!(has_text(&f, l), "{l:?} missing");
    }
    assert_legend_off_data(&f, &["rod 0", "rod 1", "rod 2", "start", "end"]);
}

/// A 1 mm rod gets millimetre axes; the scale is the same in all panels.
#[test]
fn tiny_scene_uses_millimetres() {
    let f = plot::tip_trajectory("tip", &tips(1, 1e-3)).unwrap();
    assert_equal_aspect(&f);
    assert_eq!(f.panels[0].x_label, "x [mm]");
    assert!(has_text(&f, "z [mm]"));
    // Ticks are printed in mm: the motion spans about ±0.7 mm, so every
    // number is within ±2 and some are not zero (in metres they would
    // all be below 0.002).
    let ticks: Vec<f64> = texts(&f.svg)
        .iter()
        .filter_map(|(_, s)| s.parse().ok())
        .collect();
    // At least a few per axis of each panel (one panel: the motion is planar).
    assert!(ticks.len() > 5 * f.panels.len(), "{ticks:?}");
    assert!(ticks.iter().all(|v| v.abs() <= 2.0), "{ticks:?}");
    assert!(ticks.iter().any(|v| v.abs() >= 0.1), "{ticks:?}");
}

#[test]
fn shapes_colour_times_and_one_snapshot_of_several_rods_by_rod() {
    let view = SwingingRods {
        rods: 2,
        times: 11,
        ..SwingingRods::default()
    }
    .build();
    let snaps: Vec<ShapeSnapshot> = [0, 5, 10]
        .iter()
        .map(|&k| ShapeSnapshot {
            t: Some(view.times[k]),
            rods: view
                .rods
                .iter()
                .map(|r| RodCurve {
                    name: r.name.clone(),
                    points: r.frames[k].iter().map(|p| p.position).collect(),
                })
                .collect(),
            bodies: Vec::new(),
        })
        .collect();
    let both = plot::shapes("shapes", &snaps).unwrap();
    assert_equal_aspect(&both);
    // Several rods at several times: the times in viridis, each labelled.
    assert_legend_off_data(&both, &["2 rods at", "t = 0 s", "t = 1 s", "t = 2 s"]);
    let once = plot::shapes("shapes", &snaps[2..]).unwrap();
    assert_legend_off_data(&once, &["rod 0", "rod 1"]);
    let one: Vec<ShapeSnapshot> = snaps
        .iter()
        .map(|s| ShapeSnapshot {
            t: s.t,
            rods: vec![s.rods[0].clone()],
            bodies: Vec::new(),
        })
        .collect();
    let f = plot::shapes("shapes", &one).unwrap();
    assert_legend_off_data(&f, &["t = 0 s", "t = 1 s", "t = 2 s"]);
    // A static shape: one snapshot without a time.
    let stat = plot::shapes(
        "static",
        &[ShapeSnapshot {
            t: None,
            rods: vec![one[1].rods[0].clone()],
            bodies: Vec::new(),
        }],
    )
    .unwrap();
    assert_legend_off_data(&stat, &["equilibrium"]);
    for p in &stat.panels {
        assert!(p.equal_aspect);
    }
}

/// Kinetic + elastic = a e^{-t} (exchanging), gravity constant: the total's
/// drift is a (e^{-t} − 1), whose minimum a (e^{-T} − 1) the lower panel's
/// range must hold, within its 6 % padding.
/// Bodies are marked at their positions in every projection: the centre
/// of each outlined square is where the panel's own data-to-pixel map
/// (its ranges onto its plotting rectangle, y up) puts the body, to the
/// pixel rounding; each body is named once per panel (last snapshot only),
/// and the legend says what the squares are.
#[test]
fn shapes_mark_bodies_at_their_positions() {
    let rod = |z: f64| RodCurve {
        name: "arm".into(),
        points: (0..=10)
            .map(|k| [0.03 * k as f64, 0.01 * k as f64, z * (k * k) as f64])
            .collect(),
    };
    let bodies = |z: f64| {
        vec![
            BodyMark {
                name: "hub".into(),
                position: [0.15, 0.05, 25.0 * z],
            },
            BodyMark {
                name: "tool".into(),
                position: [0.3, 0.1, 100.0 * z],
            },
        ]
    };
    let snaps: Vec<ShapeSnapshot> = [(0.0, -1e-4), (1.0, -2e-3)]
        .iter()
        .map(|&(t, z)| ShapeSnapshot {
            t: Some(t),
            rods: vec![rod(z)],
            bodies: bodies(z),
        })
        .collect();
    let f = plot::shapes("bodies", &snaps).unwrap();
    assert_equal_aspect(&f);
    assert_legend_off_data(&f, &["body (frame origin)"]);
    let centres = svg_outlined_rect_centres(&f.svg);
    // 2 snapshots × 2 bodies × 3 panels, and the legend's swatch.
    assert_eq!(centres.len(), 13, "{centres:?}");
    let planes = [(0, 2), (1, 2), (0, 1)];
    for (p, (a, b)) in f.panels.iter().zip(planes) {
        let ((l, t), (r, btm)) = p.plot_rect;
        let to_px = |x: [f64; 3]| {
            (
                f64::from(l)
                    + (x[a] - p.x_range.0) / (p.x_range.1 - p.x_range.0) * f64::from(r - l),
                f64::from(btm)
                    - (x[b] - p.y_range.0) / (p.y_range.1 - p.y_range.0) * f64::from(btm - t),
            )
        };
        for s in &snaps {
            for body in &s.bodies {
                let (u, v) = to_px(body.position);
                let d = centres
                    .iter()
                    .map(|(x, y)| ((x - u).powi(2) + (y - v).powi(2)).sqrt())
                    .fold(f64::INFINITY, f64::min);
                assert!(d <= 1.5, "{}: '{}' mark {d:.2} px off", p.title, body.name);
            }
        }
    }
    for name in ["hub", "tool"] {
        let n = texts(&f.svg).iter().filter(|(_, s)| s == name).count();
        assert_eq!(n, 3, "'{name}' named once per panel");
    }
    let mut bad = snaps.clone();
    bad[1].bodies[1].position[2] = f64::NAN;
    match plot::shapes("s", &bad) {
        Err(VizError::NotFinite { what, index: 2, .. }) => {
            assert_eq!(what, "snapshots[1].bodies ('tool').position")
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn energy_components_total_and_drift() {
    let a = 2e-3;
    let t: Vec<f64> = (0..=200).map(|k| k as f64 * 0.01).collect();
    let e = EnergySeries {
        t: t.clone(),
        kinetic: t
            .iter()
            .map(|t| a * (-t).exp() * (5.0 * t).sin().powi(2))
            .collect(),
        elastic: t
            .iter()
            .map(|t| a * (-t).exp() * (5.0 * t).cos().powi(2))
            .collect(),
        gravitational: vec![-5e-4; t.len()],
        extra: vec![],
    };
    let f = plot::energy("energy", &e).unwrap();
    assert_eq!(f.panels.len(), 2);
    assert_eq!(f.panels[0].y_label, "E [mJ]");
    assert_eq!(f.panels[0].x_label, "t [s]");
    let top = &f.panels[0];
    assert!(top.y_range.0 <= -5e-4 && top.y_range.1 >= a - 5e-4);
    let drift_min = a * ((-2.0f64).exp() - 1.0);
    let lo = &f.panels[1];
    let span = -drift_min;
    assert!(
        lo.y_range.0 <= drift_min && lo.y_range.0 >= drift_min - 0.0601 * span,
        "{:?}",
        lo.y_range
    );
    assert!(
        lo.y_range.1 >= 0.0 && lo.y_range.1 <= 0.0601 * span * (1.0 + 1e-9),
        "{:?}",
        lo.y_range
    );
    assert!(!lo.equal_aspect);
    assert_legend_off_data(&f, &["total", "kinetic", "elastic", "gravitational"]);
    for l in ["E [mJ]", "E − E(t₀) [mJ]", "t [s]"] {
        assert!(has_text(&f, l), "{l:?} missing");
    }
}

#[test]
fn cable_tensions_and_power() {
    let t: Vec<f64> = (0..50).map(|k| k as f64 * 0.02).collect();
    let a = ActuatorSeries {
        t: t.clone(),
        tensions: vec![NamedSeries {
            name: "left, \"outer\"".into(),
            values: t.iter().map(|t| 2.0 * t).collect(),
        }],
        power: vec![NamedSeries {
            name: "left, \"outer\"".into(),
            values: t.iter().map(|t| 3e-3 * t).collect(),
        }],
    };
    let f = plot::actuators("cables", &a).unwrap();
    assert_eq!(f.panels[0].y_label, "T [N]");
    assert_eq!(f.panels[1].y_label, "P [mW]");
    assert!(f.panels[0].y_range.1 >= 2.0 * 0.98);
    // The SVG escapes the quotes of the name.
    assert!(f.svg.contains("left, &quot;outer&quot;") || f.svg.contains("left, \"outer\""));
}

#[test]
fn strains_per_component_with_units() {
    let bounds = [0.0, 0.1, 0.25, 0.5];
    let per = vec![
        vec![[0.0, 1.0, 0.0, 1.0, 0.0, 0.0]; 3],
        vec![
            [0.1, 2.0, -1.0, 1.01, 0.0, 1e-3],
            [0.1, 3.0, -1.0, 1.01, 0.0, 1e-3],
            [0.1, 4.0, -1.0, 1.01, 0.0, 1e-3],
        ],
    ];
    let p = StrainProfiles::piecewise_constant(
        "arm",
        vec![0.0, 0.5],
        &bounds,
        &per,
        vec![
            StrainComponent::Ky,
            StrainComponent::Qx,
            StrainComponent::Qz,
        ],
    );
    // Each piece is a step: its two ends carry its value.
    assert_eq!(p.s, vec![0.0, 0.1, 0.1, 0.25, 0.25, 0.5]);
    assert_eq!(p.values[1][2][1], 3.0);
    assert_eq!(p.values[1][3][1], 3.0);
    let f = plot::strains("strains", &p).unwrap();
    assert_eq!(f.panels.len(), 3);
    assert_eq!(f.panels[0].y_label, "k_y [1/m]");
    assert_eq!(f.panels[1].y_label, "q_x [–]");
    // q_z reaches 1e-3 (the range padded to ~1.08e-3): printed in 10⁻³.
    assert_eq!(f.panels[2].y_label, "q_z [10⁻³]");
    assert_eq!(f.panels[0].x_label, "s [m]");
    assert!(f.panels[0].y_range.0 <= 1.0 && f.panels[0].y_range.1 >= 4.0);
    assert_legend_off_data(&f, &["t = 0 s", "t = 0.5 s"]);
}

/// A mode that moves the x-aligned rod along y is shown in the x–y plane,
/// one along z in x–z; frequencies in the titles.
#[test]
fn mode_shapes_pick_the_plane_of_motion() {
    let xs: Vec<f64> = (0..=20).map(|i| 0.5 * i as f64 / 20.0).collect();
    let eq = RodCurve {
        name: "arm".into(),
        points: xs.iter().map(|x| [*x, 0.0, -0.01]).collect(),
    };
    let shape = |dir: usize, f: f64| Mode {
        frequency_hz: f,
        displaced: vec![RodCurve {
            name: "arm".into(),
            points: xs
                .iter()
                .map(|x| {
                    let mut p = [*x, 0.0, -0.01];
                    p[dir] += 0.05 * (x / 0.5).powi(2);
                    p
                })
                .collect(),
        }],
    };
    let f = plot::modes(
        "modes",
        &ModeShapes {
            equilibrium: vec![eq],
            modes: vec![shape(2, 1.123456), shape(1, 19.66)],
        },
    )
    .unwrap();
    assert_eq!(f.panels[0].title, "mode 1: 1.123 Hz  (x–z)");
    assert_eq!(f.panels[1].title, "mode 2: 19.66 Hz  (x–y)");
    assert_eq!(f.panels[1].y_label, "y [m]");
    assert_equal_aspect(&f);
    assert_legend_off_data(&f, &["equilibrium", "arm: + mode", "arm: − mode"]);
}

#[test]
fn bad_plot_input_is_a_structured_error() {
    let mut tips = tips(1, 0.5);
    tips[0].points[3][1] = f64::INFINITY;
    assert!(matches!(
        plot::tip_trajectory("t", &tips),
        Err(VizError::NotFinite { index: 1, .. })
    ));
    let e = EnergySeries {
        t: vec![0.0, 1.0],
        kinetic: vec![0.0],
        elastic: vec![0.0, 0.0],
        gravitational: vec![0.0, 0.0],
        extra: vec![],
    };
    assert!(matches!(
        plot::energy("e", &e),
        Err(VizError::Count {
            got: 1,
            expected: 2,
            ..
        })
    ));
    assert!(matches!(plot::shapes("s", &[]), Err(VizError::Empty(_))));
}
