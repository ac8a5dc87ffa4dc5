//! The log–log work–precision chart of a study (`softrod report`): error
//! against wall time, one curve per group, the Pareto front marked.

use plotters::prelude::*;

use super::common::{LEGEND_W, LegendEntry, Swatch, draw_legend, plot_err};
use super::{Figure, PanelInfo};
use crate::error::VizError;

/// One measured configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkPrecisionPoint {
    /// The curve it belongs to (an integrator, a quadrature order), as the
    /// legend names it.
    pub group: String,
    /// Wall time \[s\] (> 0).
    pub wall: f64,
    /// Error \[m\] (> 0).
    pub error: f64,
    /// Whether it is on the Pareto front (no other point is both faster
    /// and more accurate).
    pub pareto: bool,
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// The chart's size, px; the legend gets a column of [`LEGEND_W`] to its
/// right, so it never covers a curve.
const SIZE: (u32, u32) = (1000, 650);

/// Log–log error against wall time, one curve per group (in order of
/// first appearance), the Pareto front as a dashed black staircase with
/// ringed points. Points without a positive finite wall time and error are
/// left out; with none the axes span 1 ms–1 s and 1e-12–1 m.
pub fn work_precision(title: &str, points: &[WorkPrecisionPoint]) -> Result<Figure, VizError> {
    let pts: Vec<&WorkPrecisionPoint> = points
        .iter()
        .filter(|p| p.wall > 0.0 && p.error > 0.0 && p.error.is_finite() && p.wall.is_finite())
        .collect();
    let (mut wlo, mut whi, mut elo, mut ehi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in &pts {
        wlo = wlo.min(p.wall);
        whi = whi.max(p.wall);
        elo = elo.min(p.error);
        ehi = ehi.max(p.error);
    }
    if pts.is_empty() {
        (wlo, whi, elo, ehi) = (1e-3, 1.0, 1e-12, 1.0);
    }
    let (x_range, y_range) = ((wlo / 1.5, whi * 1.5), (elo / 3.0, ehi * 3.0));
    let x_label = "wall time [s] (median of repeats)";
    let y_label = "max tip error over the run [m]";
    let err = plot_err("work-precision");
    let mut svg = String::new();
    let (plot_px, plot_rect) = {
        let root =
            SVGBackend::with_string(&mut svg, (SIZE.0 + LEGEND_W, SIZE.1)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let (chart_area, legend_area) = root.split_horizontally(SIZE.0);
        let mut legend = Vec::new();
        let mut c = ChartBuilder::on(&chart_area)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(90)
            .build_cartesian_2d(
                (x_range.0..x_range.1).log_scale(),
                (y_range.0..y_range.1).log_scale(),
            )
            .map_err(&err)?;
        c.configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            // Powers of ten come out of the log axis as 9.999…e-5: round.
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| format!("{v:.2}"))
            .draw()
            .map_err(&err)?;
        let mut groups: Vec<&str> = Vec::new();
        for p in &pts {
            if !groups.contains(&p.group.as_str()) {
                groups.push(&p.group);
            }
        }
        for (k, g) in groups.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let mut line: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| p.group == *g)
                .map(|p| (p.wall, p.error))
                .collect();
            line.sort_by(|a, b| b.1.total_cmp(&a.1));
            c.draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))
                .map_err(&err)?;
            legend.push(LegendEntry::line(*g, color, 3));
            c.draw_series(line.iter().map(|&q| Circle::new(q, 4, color.filled())))
                .map_err(&err)?;
        }
        let mut front: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.pareto)
            .map(|p| (p.wall, p.error))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        if !front.is_empty() {
            // A staircase: below and left of it nothing was measured.
            let mut stair = Vec::new();
            for (i, &(w, e)) in front.iter().enumerate() {
                if i > 0 {
                    stair.push((w, front[i - 1].1));
                }
                stair.push((w, e));
            }
            c.draw_series(DashedLineSeries::new(stair, 6, 4, BLACK.stroke_width(1)))
                .map_err(&err)?;
            legend.push(LegendEntry {
                label: "Pareto front".into(),
                swatch: Swatch::Line {
                    color: BLACK,
                    width: 1,
                    dashed: true,
                },
            });
            c.draw_series(
                front
                    .iter()
                    .map(|&q| Circle::new(q, 8, BLACK.stroke_width(2))),
            )
            .map_err(&err)?;
        }
        draw_legend(&legend_area, 60, &legend, "work-precision")?;
        let area = c.plotting_area();
        let (xs, ys) = area.get_pixel_range();
        root.present().map_err(&err)?;
        (
            ((xs.end - xs.start) as u32, (ys.end - ys.start) as u32),
            ((xs.start, ys.start), (xs.end, ys.end)),
        )
    };
    Ok(Figure {
        svg,
        panels: vec![PanelInfo {
            title: title.to_owned(),
            x_label: x_label.to_owned(),
            y_label: y_label.to_owned(),
            x_range,
            y_range,
            plot_px,
            plot_rect,
            equal_aspect: false,
        }],
    })
}
