//! Geometry figures: tip trajectory, rod shapes, mode shapes (equal aspect).

use plotters::prelude::*;

use super::common::{
    Area, LEGEND_W, LegendEntry, Marker, PanelSpec, Stroke, Swatch, TITLE_H, bounds, check_finite,
    check_len, color, draw_legend, draw_panel, equal_aspect_ranges, extent, finish_svg,
    length_unit, lighten, plot_err, plot_size, sequential, significant, titled,
};
use super::{Figure, PanelInfo};
use crate::error::VizError;

/// A named polyline in the world frame (m): a rod's centreline (sampled
/// within pieces, base to tip) or a tip's path over time.
#[derive(Debug, Clone, PartialEq)]
pub struct RodCurve {
    /// Rod name (legend).
    pub name: String,
    /// Points, world frame, m.
    pub points: Vec<[f64; 3]>,
}

/// A rigid body's frame origin at one time: where [`shapes`] marks it.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyMark {
    /// Body name (printed beside its mark).
    pub name: String,
    /// Origin of the body frame, world frame, m.
    pub position: [f64; 3],
}

/// The rods' shapes and the bodies' positions at one time (`t = None`: a
/// static shape).
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeSnapshot {
    /// Time, s, or `None` for an equilibrium.
    pub t: Option<f64>,
    /// One curve per rod.
    pub rods: Vec<RodCurve>,
    /// The rigid bodies of an articulated model (empty without bodies).
    pub bodies: Vec<BodyMark>,
}

/// One vibration mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// The rods displaced along the mode (equilibrium + a visible
    /// amplitude, e.g. a tenth of the rod length at the largest point); one
    /// curve per rod, with as many points as its equilibrium curve.
    pub displaced: Vec<RodCurve>,
}

/// Mode shapes about an equilibrium.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeShapes {
    /// The equilibrium shape, one curve per rod.
    pub equilibrium: Vec<RodCurve>,
    /// The modes, lowest first.
    pub modes: Vec<Mode>,
}

const AXES: [&str; 3] = ["x", "y", "z"];
/// The three projections: (horizontal axis, vertical axis).
const PROJECTIONS: [(usize, usize); 3] = [(0, 2), (1, 2), (0, 1)];
const PANEL_W: u32 = 430;
const PANEL_H: u32 = 450;
const PLOT: &str = "geometry";

struct Curve3 {
    points: Vec<[f64; 3]>,
    color: RGBColor,
    width: u32,
    dashed: bool,
}

type Planes = Vec<(usize, usize, String)>;
type PanelContents = Vec<(Vec<Curve3>, Vec<Marker3>)>;

#[derive(Clone)]
enum Marker3 {
    Circle([f64; 3], RGBColor),
    Square([f64; 3], RGBColor),
    Body([f64; 3], RGBColor, Option<String>),
}

impl Marker3 {
    fn point(&self) -> [f64; 3] {
        match self {
            Marker3::Circle(p, _) | Marker3::Square(p, _) | Marker3::Body(p, _, _) => *p,
        }
    }
}

/// Colour of the body marks with several rods (earlier snapshots lighter).
const BODY_COLOR: RGBColor = RGBColor(40, 40, 40);

fn check_curves(what: &str, curves: &[RodCurve]) -> Result<(), VizError> {
    for (i, c) in curves.iter().enumerate() {
        if c.points.is_empty() {
            return Err(VizError::Empty("a curve's points"));
        }
        for p in &c.points {
            check_finite(&format!("{what}[{i}] ('{}').points", c.name), p)?;
        }
    }
    Ok(())
}

/// Panels with equal aspect and one common scale, plus a legend column.
/// `planes[k]` = (horizontal, vertical) axes and title of panel `k`.
#[allow(clippy::too_many_arguments)]
fn geometry_figure(
    title: &str,
    planes: &[(usize, usize, String)],
    per_panel: &[(Vec<Curve3>, Vec<Marker3>)],
    cols: usize,
    legend: &[LegendEntry],
    plot: &'static str,
) -> Result<Figure, VizError> {
    let rows = planes.len().div_ceil(cols);
    let (w, h) = (
        cols as u32 * PANEL_W + LEGEND_W,
        TITLE_H + rows as u32 * PANEL_H,
    );
    let mut svg = String::new();
    let mut infos: Vec<PanelInfo> = Vec::new();
    {
        let root: Area = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let body = titled(&root, title, plot)?;
        let (panels_area, legend_area) = body.split_horizontally(cols as u32 * PANEL_W);
        let cells = panels_area.split_evenly((rows, cols));
        // Data boxes, then one scale for all panels.
        let all = per_panel
            .iter()
            .flat_map(|(c, m)| {
                c.iter()
                    .flat_map(|c| c.points.iter().copied())
                    .chain(m.iter().map(Marker3::point))
            })
            .collect::<Vec<_>>();
        let span = (0..3)
            .map(|j| extent(all.iter().map(|p| p[j])))
            .fold(0.0, f64::max);
        let (unit, factor) = length_unit(span);
        let mut boxes = Vec::new();
        let mut sizes = Vec::new();
        for (k, (a, b, ptitle)) in planes.iter().enumerate() {
            let pts = || {
                per_panel[k]
                    .0
                    .iter()
                    .flat_map(|c| c.points.iter())
                    .copied()
                    .chain(per_panel[k].1.iter().map(Marker3::point))
            };
            let ra = bounds(pts().map(|p| p[*a]));
            let rb = bounds(pts().map(|p| p[*b]));
            // A flat projection (a planar motion seen edge-on) gets a tenth
            // of the other axis' span, so its line sits mid-panel; both get
            // the same 6 % padding. A single point gets ±1 mm.
            let s = (ra.1 - ra.0).max(rb.1 - rb.0);
            let s = if s > 0.0 { s } else { 1e-3 };
            let widen = |r: (f64, f64)| {
                let c = 0.5 * (r.0 + r.1);
                let half = (0.5 * (r.1 - r.0)).max(0.05 * s) + 0.06 * s;
                (c - half, c + half)
            };
            boxes.push((widen(ra), widen(rb)));
            sizes.push(plot_size(&cells[k], ptitle, plot)?);
        }
        let ranges = equal_aspect_ranges(&boxes, &sizes);
        for (k, (a, b, ptitle)) in planes.iter().enumerate() {
            let (curves, markers) = &per_panel[k];
            let spec = PanelSpec {
                title: ptitle.clone(),
                x_label: format!("{} [{unit}]", AXES[*a]),
                y_label: format!("{} [{unit}]", AXES[*b]),
                x_scale: factor,
                y_scale: factor,
                strokes: curves
                    .iter()
                    .map(|c| Stroke {
                        points: c.points.iter().map(|p| (p[*a], p[*b])).collect(),
                        color: c.color,
                        width: c.width,
                        dashed: c.dashed,
                    })
                    .collect(),
                markers: markers
                    .iter()
                    .map(|m| match m {
                        Marker3::Circle(p, c) => Marker::Circle((p[*a], p[*b]), *c),
                        Marker3::Square(p, c) => Marker::Square((p[*a], p[*b]), *c),
                        Marker3::Body(p, c, l) => Marker::Body((p[*a], p[*b]), *c, l.clone()),
                    })
                    .collect(),
                zero_line: false,
            };
            infos.push(draw_panel(
                &cells[k],
                &spec,
                ranges[k].0,
                ranges[k].1,
                true,
                plot,
            )?);
        }
        draw_legend(&legend_area, 40, legend, plot)?;
        root.present().map_err(plot_err(plot))?;
    }
    finish_svg(&mut svg);
    Ok(Figure { svg, panels: infos })
}

/// A scene whose drawn points spread less than this fraction of their
/// largest extent along one world axis is planar: far below a pixel of any
/// panel, so the projection along that axis would show a line and the
/// other two the same picture twice.
const PLANAR_TOL: f64 = 1e-9;

/// The panels of a geometry figure (and their column count): the three
/// projections, or, when every point lies in a plane normal to a world axis,
/// the one projection onto that plane (its vertical axis z when it has one).
fn projections(curves: Vec<Curve3>, markers: Vec<Marker3>) -> (Planes, PanelContents, usize) {
    let all = || {
        curves
            .iter()
            .flat_map(|c| c.points.iter().copied())
            .chain(markers.iter().map(Marker3::point))
    };
    let spread: Vec<f64> = (0..3).map(|j| extent(all().map(|p| p[j]))).collect();
    let largest = spread.iter().copied().fold(0.0, f64::max);
    let flat = (0..3).find(|&j| largest > 0.0 && spread[j] <= PLANAR_TOL * largest);
    let chosen: Vec<(usize, usize)> = match flat {
        Some(j) => PROJECTIONS
            .iter()
            .copied()
            .filter(|&(a, b)| a != j && b != j)
            .collect(),
        None => PROJECTIONS.to_vec(),
    };
    let cols = chosen.len();
    let planes = chosen
        .iter()
        .map(|(a, b)| (*a, *b, format!("{}–{} projection", AXES[*a], AXES[*b])))
        .collect();
    let copy = |c: &Curve3| Curve3 {
        points: c.points.clone(),
        color: c.color,
        width: c.width,
        dashed: c.dashed,
    };
    let per = (0..cols)
        .map(|_| (curves.iter().map(copy).collect(), markers.to_vec()))
        .collect();
    (planes, per, cols)
}

/// The tip path of each rod over a run, in the x–z, y–z and x–y
/// projections (only the plane of a planar motion; equal aspect, one
/// scale), start ● and end ■ marked, rods in
/// the palette's colours. `tips[r].points` are the tip positions at the
/// output times.
pub fn tip_trajectory(title: &str, tips: &[RodCurve]) -> Result<Figure, VizError> {
    if tips.is_empty() {
        return Err(VizError::Empty("tips"));
    }
    check_curves("tips", tips)?;
    let mut curves = Vec::new();
    let mut markers = Vec::new();
    let mut legend = vec![LegendEntry::header(if tips.len() == 1 {
        "tip of"
    } else {
        "tips of"
    })];
    for (r, tip) in tips.iter().enumerate() {
        let c = color(r);
        curves.push(Curve3 {
            points: tip.points.clone(),
            color: c,
            width: 2,
            dashed: false,
        });
        markers.push(Marker3::Circle(tip.points[0], c));
        markers.push(Marker3::Square(tip.points[tip.points.len() - 1], c));
        legend.push(LegendEntry::line(tip.name.clone(), c, 3));
    }
    legend.push(LegendEntry {
        label: "start".into(),
        swatch: Swatch::Circle(RGBColor(90, 90, 90)),
    });
    legend.push(LegendEntry {
        label: "end".into(),
        swatch: Swatch::Square(RGBColor(90, 90, 90)),
    });
    let (planes, per, cols) = projections(curves, markers);
    geometry_figure(title, &planes, &per, cols, &legend, PLOT)
}

/// Rod shapes (centrelines, sampled within pieces) at one or more times, in
/// the three projections (only the plane of a planar scene; equal aspect,
/// one scale). Times are told apart by a perceptually uniform sequential
/// colormap (viridis, dark purple → green = early → late), each time
/// labelled in the legend; with several rods every rod of a snapshot takes
/// its time's colour (the rods are told apart by where they are), and one
/// snapshot of several rods is drawn a colour per rod. Rigid bodies are
/// outlined squares at their frame origins, in the same projections, named
/// at the last snapshot.
pub fn shapes(title: &str, snapshots: &[ShapeSnapshot]) -> Result<Figure, VizError> {
    shapes_with_obstacles(title, snapshots, &[])
}

/// [`shapes`] with obstacles drawn in every projection (their outlines,
/// `super::obstacles`): a carried obstacle's `poses` has one pose per
/// snapshot, and it is drawn at each (lighter when earlier).
pub fn shapes_with_obstacles(
    title: &str,
    snapshots: &[ShapeSnapshot],
    obstacles: &[crate::obstacles::ObstacleTrack],
) -> Result<Figure, VizError> {
    if snapshots.is_empty() {
        return Err(VizError::Empty("snapshots"));
    }
    let n_rods = snapshots[0].rods.len();
    for (k, s) in snapshots.iter().enumerate() {
        check_len(&format!("snapshots[{k}].rods"), s.rods.len(), n_rods)?;
        check_curves(&format!("snapshots[{k}].rods"), &s.rods)?;
        for b in &s.bodies {
            check_finite(
                &format!("snapshots[{k}].bodies ('{}').position", b.name),
                &b.position,
            )?;
        }
    }
    let m = snapshots.len();
    let time_text = |s: &ShapeSnapshot| match s.t {
        Some(t) => format!("t = {}", short_time(t)),
        None => "equilibrium".to_string(),
    };
    let mut curves = Vec::new();
    let mut markers = Vec::new();
    let mut legend = Vec::new();
    if n_rods == 1 {
        legend.push(LegendEntry::header(snapshots[0].rods[0].name.clone()));
        for (k, s) in snapshots.iter().enumerate() {
            let c = if m == 1 {
                color(0)
            } else {
                sequential(k as f64 / (m - 1) as f64)
            };
            curves.push(Curve3 {
                points: s.rods[0].points.clone(),
                color: c,
                width: 2,
                dashed: false,
            });
            markers.push(Marker3::Circle(s.rods[0].points[0], RGBColor(60, 60, 60)));
            body_marks(&mut markers, s, c, k + 1 == m);
            legend.push(LegendEntry::line(time_text(s), c, 3));
        }
    } else if m == 1 {
        legend.push(LegendEntry::header("rods"));
        for (r, rod) in snapshots[0].rods.iter().enumerate() {
            legend.push(LegendEntry::line(rod.name.clone(), color(r), 3));
            curves.push(Curve3 {
                points: rod.points.clone(),
                color: color(r),
                width: 2,
                dashed: false,
            });
        }
        body_marks(&mut markers, &snapshots[0], BODY_COLOR, true);
    } else {
        legend.push(LegendEntry::header(format!("{} rods at", n_rods)));
        for (k, s) in snapshots.iter().enumerate() {
            let c = sequential(k as f64 / (m - 1) as f64);
            for rod in &s.rods {
                curves.push(Curve3 {
                    points: rod.points.clone(),
                    color: c,
                    width: 2,
                    dashed: false,
                });
            }
            body_marks(&mut markers, s, c, k + 1 == m);
            legend.push(LegendEntry::line(time_text(s), c, 3));
        }
    }
    if snapshots.iter().any(|s| !s.bodies.is_empty()) {
        legend.push(LegendEntry {
            label: "body (frame origin)".into(),
            swatch: Swatch::HollowSquare(BODY_COLOR),
        });
    }
    for (k, o) in obstacles.iter().enumerate() {
        o.validate(&format!("obstacles[{k}]"), m)?;
    }
    let region = super::obstacles::region_of(curves.iter().flat_map(|c| c.points.iter().copied()));
    let (planes, mut per, cols) = projections(curves, markers);
    add_obstacles(&planes, &mut per, &mut legend, obstacles, &region);
    geometry_figure(title, &planes, &per, cols, &legend, PLOT)
}

/// Colour of obstacle outlines.
const OBSTACLE_COLOR: RGBColor = RGBColor(150, 110, 60);

/// The obstacles' outlines added to each panel (drawn before the rods, so
/// a rod resting on a table stays on top) and one legend line per obstacle.
fn add_obstacles(
    planes: &Planes,
    per: &mut PanelContents,
    legend: &mut Vec<LegendEntry>,
    obstacles: &[crate::obstacles::ObstacleTrack],
    region: &crate::obstacles::Region,
) {
    if obstacles.is_empty() {
        return;
    }
    for ((a, b, _), (curves, _)) in planes.iter().zip(per.iter_mut()) {
        let outlines = super::obstacles::outlines(obstacles, (*a, *b), region);
        let drawn = outlines.into_iter().map(|o| Curve3 {
            points: o.points,
            color: lighten(OBSTACLE_COLOR, o.fade),
            width: 2,
            dashed: false,
        });
        let rods = std::mem::take(curves);
        curves.extend(drawn);
        curves.extend(rods);
    }
    legend.push(LegendEntry::header("obstacles"));
    for o in obstacles {
        legend.push(LegendEntry::line(
            format!("{} ({})", o.name, crate::obstacles::kind(&o.shape)),
            OBSTACLE_COLOR,
            2,
        ));
    }
}

/// The marks of a snapshot's bodies, drawn after the rods; named on the
/// last snapshot only (earlier names would pile up on each other).
fn body_marks(markers: &mut Vec<Marker3>, s: &ShapeSnapshot, c: RGBColor, named: bool) {
    for b in &s.bodies {
        markers.push(Marker3::Body(b.position, c, named.then(|| b.name.clone())));
    }
}

/// A time printed with up to 4 significant digits: `0.125 s`, `1.5e-05 s`.
fn short_time(t: f64) -> String {
    if t == 0.0 {
        return "0 s".into();
    }
    let a = t.abs();
    if (1e-3..1e4).contains(&a) {
        let d = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{t:.d$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        format!("{s} s")
    } else {
        format!("{t:.3e} s")
    }
}

/// Mode shapes: one panel per mode (up to 3 per row), each in the
/// axis-aligned plane that shows it best (horizontal: the axis along which
/// the equilibrium extends most; vertical: of the other two, the one with
/// the largest modal displacement), equal aspect with one scale for all.
/// Equilibrium in grey, `+` mode solid, `−` mode (mirrored) dashed.
pub fn modes(title: &str, shapes: &ModeShapes) -> Result<Figure, VizError> {
    if shapes.modes.is_empty() {
        return Err(VizError::Empty("modes"));
    }
    check_curves("equilibrium", &shapes.equilibrium)?;
    let grey = RGBColor(150, 150, 150);
    let mut planes = Vec::new();
    let mut per = Vec::new();
    for (k, mode) in shapes.modes.iter().enumerate() {
        check_len(
            &format!("modes[{k}].displaced"),
            mode.displaced.len(),
            shapes.equilibrium.len(),
        )?;
        check_curves(&format!("modes[{k}].displaced"), &mode.displaced)?;
        check_finite(&format!("modes[{k}].frequency_hz"), &[mode.frequency_hz])?;
        let mut spread = [0.0f64; 3];
        let mut disp = [0.0f64; 3];
        for (e, d) in shapes.equilibrium.iter().zip(&mode.displaced) {
            check_len(
                &format!("modes[{k}].displaced ('{}').points", d.name),
                d.points.len(),
                e.points.len(),
            )?;
            for j in 0..3 {
                spread[j] = spread[j].max(extent(e.points.iter().map(|p| p[j])));
                disp[j] += e
                    .points
                    .iter()
                    .zip(&d.points)
                    .map(|(p, q)| (q[j] - p[j]).powi(2))
                    .sum::<f64>();
            }
        }
        let a = (0..3)
            .max_by(|i, j| spread[*i].total_cmp(&spread[*j]))
            .unwrap_or(0);
        let b = (0..3)
            .filter(|j| *j != a)
            .max_by(|i, j| disp[*i].total_cmp(&disp[*j]))
            .unwrap_or(2);
        planes.push((
            a,
            b,
            format!(
                "mode {}: {} Hz  ({}–{})",
                k + 1,
                significant(mode.frequency_hz, 4),
                AXES[a],
                AXES[b]
            ),
        ));
        let mut curves = Vec::new();
        for (r, (e, d)) in shapes.equilibrium.iter().zip(&mode.displaced).enumerate() {
            curves.push(Curve3 {
                points: e.points.clone(),
                color: grey,
                width: 2,
                dashed: false,
            });
            let mirrored = e
                .points
                .iter()
                .zip(&d.points)
                .map(|(p, q)| [2.0 * p[0] - q[0], 2.0 * p[1] - q[1], 2.0 * p[2] - q[2]])
                .collect();
            curves.push(Curve3 {
                points: mirrored,
                color: color(r),
                width: 2,
                dashed: true,
            });
            curves.push(Curve3 {
                points: d.points.clone(),
                color: color(r),
                width: 3,
                dashed: false,
            });
        }
        per.push((curves, Vec::new()));
    }
    let mut legend = vec![LegendEntry::line("equilibrium", grey, 2)];
    if shapes.equilibrium.len() > 1 {
        legend.push(LegendEntry::header("rods"));
    }
    for (r, e) in shapes.equilibrium.iter().enumerate() {
        legend.push(LegendEntry::line(
            format!("{}: + mode", e.name),
            color(r),
            3,
        ));
        legend.push(LegendEntry {
            label: format!("{}: − mode", e.name),
            swatch: Swatch::Line {
                color: color(r),
                width: 2,
                dashed: true,
            },
        });
    }
    let cols = shapes.modes.len().min(3);
    geometry_figure(title, &planes, &per, cols, &legend, PLOT)
}
