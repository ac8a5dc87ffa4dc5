//! The log-log work-precision chart (SVG).

use std::path::Path;

use plotters::prelude::*;

use super::table::{Row, wall};
use crate::common::{CliError, failed};

pub(super) const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Log-log error against wall time, one curve per group (`key`), the
/// Pareto front as a dashed black line with ringed points.
pub(super) fn work_precision_svg(
    path: &Path,
    title: &str,
    rows: &[Row],
    key: impl Fn(&Row) -> String,
) -> Result<(), CliError> {
    type Res = Result<(), Box<dyn std::error::Error>>;
    let pts: Vec<(String, f64, f64, bool)> = rows
        .iter()
        .filter_map(|r| {
            let w = wall(r);
            (r.result.is_ok() && w > 0.0 && r.err_max > 0.0 && r.err_max.is_finite())
                .then(|| (key(r), w, r.err_max, r.pareto))
        })
        .collect();
    let r: Res = (|| {
        let root = SVGBackend::new(path, (1000, 650)).into_drawing_area();
        root.fill(&WHITE)?;
        let (mut wlo, mut whi, mut elo, mut ehi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
        for (_, w, e, _) in &pts {
            wlo = wlo.min(*w);
            whi = whi.max(*w);
            elo = elo.min(*e);
            ehi = ehi.max(*e);
        }
        if pts.is_empty() {
            (wlo, whi, elo, ehi) = (1e-3, 1.0, 1e-12, 1.0);
        }
        let mut c = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(90)
            .build_cartesian_2d(
                (wlo / 1.5..whi * 1.5).log_scale(),
                (elo / 3.0..ehi * 3.0).log_scale(),
            )?;
        c.configure_mesh()
            .x_desc("wall time [s] (median of repeats)")
            .y_desc("max tip error over the run [m]")
            // Powers of ten come out of the log axis as 9.999…e-5: round.
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| format!("{v:.2}"))
            .draw()?;
        let mut groups: Vec<String> = Vec::new();
        for (g, ..) in &pts {
            if !groups.contains(g) {
                groups.push(g.clone());
            }
        }
        for (k, g) in groups.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            let mut p: Vec<(f64, f64)> = pts
                .iter()
                .filter(|(h, ..)| h == g)
                .map(|(_, w, e, _)| (*w, *e))
                .collect();
            p.sort_by(|a, b| b.1.total_cmp(&a.1));
            c.draw_series(LineSeries::new(p.clone(), color.stroke_width(2)))?
                .label(g.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            c.draw_series(p.iter().map(|&q| Circle::new(q, 4, color.filled())))?;
        }
        let mut front: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.3)
            .map(|(_, w, e, _)| (*w, *e))
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
            c.draw_series(DashedLineSeries::new(stair, 6, 4, BLACK.stroke_width(1)))?
                .label("Pareto front")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
            c.draw_series(
                front
                    .iter()
                    .map(|&q| Circle::new(q, 8, BLACK.stroke_width(2))),
            )?;
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
        Ok(())
    })();
    r.map_err(|e| failed(format!("plot {}: {e}", path.display())))
}
