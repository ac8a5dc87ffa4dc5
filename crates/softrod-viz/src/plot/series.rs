//! Time-series figures: energy components, cable tensions and actuator power.

use plotters::prelude::*;

use super::common::{
    Area, LEGEND_W, LegendEntry, PanelSpec, Stroke, Swatch, TITLE_H, check_finite, check_len,
    color, draw_legend, draw_panel, finish_svg, plot_err, range, si_prefix, titled,
};
use super::{Figure, PanelInfo};
use crate::error::VizError;

/// A named series over the time axis of its figure.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedSeries {
    /// Legend name.
    pub name: String,
    /// One value per time.
    pub values: Vec<f64>,
}

/// Energy components over a run, J (docs/theory.md §7: energy = kinetic + elastic
/// + gravitational potential).
#[derive(Debug, Clone, PartialEq)]
pub struct EnergySeries {
    /// Output times, s.
    pub t: Vec<f64>,
    /// Kinetic energy, J.
    pub kinetic: Vec<f64>,
    /// Elastic (strain) energy, J.
    pub elastic: Vec<f64>,
    /// Gravitational potential energy, J.
    pub gravitational: Vec<f64>,
    /// Further terms added into the total (e.g. a load's potential), J.
    pub extra: Vec<NamedSeries>,
}

/// Cable tensions (N) and actuator powers (W) over a run.
#[derive(Debug, Clone, PartialEq)]
pub struct ActuatorSeries {
    /// Output times, s.
    pub t: Vec<f64>,
    /// Tension of each cable, N.
    pub tensions: Vec<NamedSeries>,
    /// Power each actuator puts into the rods, W (positive: work done on
    /// the rods).
    pub power: Vec<NamedSeries>,
}

const PLOT_W: u32 = 1000;
const PANEL_H: u32 = 330;

struct Line {
    label: String,
    color: RGBColor,
    width: u32,
    dashed: bool,
    values: Vec<f64>,
}

struct SeriesPanel {
    title: String,
    quantity: String,
    unit: String,
    lines: Vec<Line>,
}

fn series_figure(
    title: &str,
    t: &[f64],
    panels: Vec<SeriesPanel>,
    legend: Vec<LegendEntry>,
    plot: &'static str,
) -> Result<Figure, VizError> {
    let (w, h) = (PLOT_W + LEGEND_W, TITLE_H + PANEL_H * panels.len() as u32);
    let mut svg = String::new();
    let mut infos: Vec<PanelInfo> = Vec::new();
    {
        let root: Area = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let body = titled(&root, title, plot)?;
        let (left, legend_area) = body.split_horizontally(PLOT_W);
        let cells = left.split_evenly((panels.len(), 1));
        let tr = range(t.iter().copied(), 0.0);
        let (tu, tf) = if tr.1 - tr.0 < 0.1 {
            ("ms", 1e3)
        } else {
            ("s", 1.0)
        };
        for (k, p) in panels.iter().enumerate() {
            let yr = range(p.lines.iter().flat_map(|l| l.values.iter().copied()), 0.06);
            let max_abs = yr.0.abs().max(yr.1.abs());
            let (prefix, factor) = si_prefix(max_abs);
            let spec = PanelSpec {
                title: p.title.clone(),
                x_label: format!("t [{tu}]"),
                y_label: format!("{} [{prefix}{}]", p.quantity, p.unit),
                x_scale: tf,
                y_scale: factor,
                strokes: p
                    .lines
                    .iter()
                    .map(|l| Stroke {
                        points: t.iter().copied().zip(l.values.iter().copied()).collect(),
                        color: l.color,
                        width: l.width,
                        dashed: l.dashed,
                    })
                    .collect(),
                markers: Vec::new(),
                zero_line: true,
            };
            infos.push(draw_panel(&cells[k], &spec, tr, yr, false, plot)?);
        }
        draw_legend(&legend_area, 40, &legend, plot)?;
        root.present().map_err(plot_err(plot))?;
    }
    finish_svg(&mut svg);
    Ok(Figure { svg, panels: infos })
}

fn check_series(what: &str, t_len: usize, s: &[f64]) -> Result<(), VizError> {
    check_len(what, s.len(), t_len)?;
    check_finite(what, s)
}

/// Energy over time: kinetic, elastic, gravitational (and any extra terms)
/// and their total (thick), and below it the drift of the total, `E(t) −
/// E(t₀)`, on its own scale (for an undamped, unforced run it measures the
/// integrator's error; with damping it must fall).
pub fn energy(title: &str, e: &EnergySeries) -> Result<Figure, VizError> {
    let n = e.t.len();
    if n == 0 {
        return Err(VizError::Empty("t"));
    }
    check_finite("t", &e.t)?;
    check_series("kinetic", n, &e.kinetic)?;
    check_series("elastic", n, &e.elastic)?;
    check_series("gravitational", n, &e.gravitational)?;
    for x in &e.extra {
        check_series(&x.name, n, &x.values)?;
    }
    let total: Vec<f64> = (0..n)
        .map(|k| {
            e.kinetic[k]
                + e.elastic[k]
                + e.gravitational[k]
                + e.extra.iter().map(|x| x.values[k]).sum::<f64>()
        })
        .collect();
    let mut comps = vec![
        ("kinetic", e.kinetic.clone()),
        ("elastic", e.elastic.clone()),
        ("gravitational", e.gravitational.clone()),
    ];
    for x in &e.extra {
        comps.push((x.name.as_str(), x.values.clone()));
    }
    let mut lines = vec![Line {
        label: "total".into(),
        color: RGBColor(20, 20, 20),
        width: 3,
        dashed: false,
        values: total.clone(),
    }];
    for (i, (name, v)) in comps.into_iter().enumerate() {
        lines.push(Line {
            label: name.into(),
            color: color(i),
            width: 2,
            dashed: false,
            values: v,
        });
    }
    let drift: Vec<f64> = total.iter().map(|v| v - total[0]).collect();
    let legend = lines
        .iter()
        .map(|l| LegendEntry::line(l.label.clone(), l.color, l.width + 1))
        .chain([LegendEntry {
            label: "lower: total − total(t₀)".into(),
            swatch: Swatch::Note,
        }])
        .collect();
    let panels = vec![
        SeriesPanel {
            title: "energy components".into(),
            quantity: "E".into(),
            unit: "J".into(),
            lines,
        },
        SeriesPanel {
            title: "drift of the total".into(),
            quantity: "E − E(t₀)".into(),
            unit: "J".into(),
            lines: vec![Line {
                label: "drift".into(),
                color: RGBColor(20, 20, 20),
                width: 2,
                dashed: false,
                values: drift,
            }],
        },
    ];
    series_figure(title, &e.t, panels, legend, "energy")
}

/// Cable tensions (N) over time and, when given, the actuators' power (W)
/// in a second panel; cables in the palette's colours.
pub fn actuators(title: &str, a: &ActuatorSeries) -> Result<Figure, VizError> {
    let n = a.t.len();
    if n == 0 {
        return Err(VizError::Empty("t"));
    }
    if a.tensions.is_empty() && a.power.is_empty() {
        return Err(VizError::Empty("tensions and power"));
    }
    check_finite("t", &a.t)?;
    let mut legend = Vec::new();
    let mut panels = Vec::new();
    let lines_of = |what: &str, list: &[NamedSeries]| -> Result<Vec<Line>, VizError> {
        let mut out = Vec::new();
        for (i, s) in list.iter().enumerate() {
            check_series(&format!("{what}[{i}] ('{}')", s.name), n, &s.values)?;
            out.push(Line {
                label: s.name.clone(),
                color: color(i),
                width: 2,
                dashed: false,
                values: s.values.clone(),
            });
        }
        Ok(out)
    };
    if !a.tensions.is_empty() {
        let lines = lines_of("tensions", &a.tensions)?;
        legend.push(LegendEntry::header("cable tension"));
        legend.extend(
            lines
                .iter()
                .map(|l| LegendEntry::line(l.label.clone(), l.color, 3)),
        );
        panels.push(SeriesPanel {
            title: "cable tensions".into(),
            quantity: "T".into(),
            unit: "N".into(),
            lines,
        });
    }
    if !a.power.is_empty() {
        let lines = lines_of("power", &a.power)?;
        legend.push(LegendEntry::header("actuator power"));
        legend.extend(
            lines
                .iter()
                .map(|l| LegendEntry::line(l.label.clone(), l.color, 3)),
        );
        panels.push(SeriesPanel {
            title: "actuator power (into the rods)".into(),
            quantity: "P".into(),
            unit: "W".into(),
            lines,
        });
    }
    series_figure(title, &a.t, panels, legend, "actuators")
}
