//! SVG plots with plotters: tip trajectory, energy, shape snapshots (the
//! work-precision chart of `softrod report` is in `report.rs`).

use std::path::Path;

use plotters::prelude::*;
use softrod_scene::Scene;

use crate::common::{CliError, failed};
use crate::run::Series;

type Res = Result<(), Box<dyn std::error::Error>>;

/// `[lo, hi]` padded by 5 % (and made non-degenerate).
fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = (hi - lo).max(1e-9 * lo.abs().max(hi.abs())).max(1e-12);
    (lo - 0.05 * span, hi + 0.05 * span)
}

/// Equal-aspect ranges for two coordinates.
fn square(a: (f64, f64), b: (f64, f64)) -> ((f64, f64), (f64, f64)) {
    let s = (a.1 - a.0).max(b.1 - b.0) / 2.0;
    let (ca, cb) = ((a.0 + a.1) / 2.0, (b.0 + b.1) / 2.0);
    ((ca - s, ca + s), (cb - s, cb + s))
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

pub fn all(dir: &Path, s: &Series, scene: &Scene) -> Result<(), CliError> {
    let wrap = |what: &str, r: Res| r.map_err(|e| failed(format!("plot {what}: {e}")));
    if s.t.is_empty() {
        return Ok(());
    }
    wrap(
        "tip_trajectory.svg",
        tip(&dir.join("tip_trajectory.svg"), s),
    )?;
    wrap("energy.svg", energy(&dir.join("energy.svg"), s))?;
    wrap("shapes.svg", shapes(&dir.join("shapes.svg"), s, scene))?;
    Ok(())
}

fn tip(path: &Path, s: &Series) -> Res {
    let root = SVGBackend::new(path, (1500, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled("tip trajectory (first rod) [m]", ("sans-serif", 22))?;
    let panels = root.split_evenly((1, 3));
    for (panel, (a, b, na, nb)) in panels.iter().zip([
        (0usize, 2usize, "x", "z"),
        (0, 1, "x", "y"),
        (1, 2, "y", "z"),
    ]) {
        let ra = range(s.tip.iter().map(|p| p[a]));
        let rb = range(s.tip.iter().map(|p| p[b]));
        let (ra, rb) = square(ra, rb);
        let mut c = ChartBuilder::on(panel)
            .caption(format!("{na}-{nb}"), ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(ra.0..ra.1, rb.0..rb.1)?;
        c.configure_mesh().x_desc(na).y_desc(nb).draw()?;
        c.draw_series(LineSeries::new(
            s.tip.iter().map(|p| (p[a], p[b])),
            &COLORS[0],
        ))?;
        if let (Some(f), Some(l)) = (s.tip.first(), s.tip.last()) {
            c.draw_series([Circle::new((f[a], f[b]), 4, COLORS[2].filled())])?
                .label("start")
                .legend(|(x, y)| Circle::new((x, y), 4, COLORS[2].filled()));
            c.draw_series([Circle::new((l[a], l[b]), 4, COLORS[3].filled())])?
                .label("end")
                .legend(|(x, y)| Circle::new((x, y), 4, COLORS[3].filled()));
            c.configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
    }
    root.present()?;
    Ok(())
}

fn energy(path: &Path, s: &Series) -> Res {
    let root = SVGBackend::new(path, (1000, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let tr = range(s.t.iter().copied());
    let er = range(s.energy.iter().flat_map(|e| e.iter().copied()));
    let mut c = ChartBuilder::on(&root)
        .caption(
            "energy (kinetic + elastic + gravitational) [J]",
            ("sans-serif", 22),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(90)
        .build_cartesian_2d(tr.0..tr.1, er.0..er.1)?;
    c.configure_mesh().x_desc("t [s]").y_desc("E [J]").draw()?;
    for (k, name) in ["total", "kinetic", "elastic", "gravitational"]
        .iter()
        .enumerate()
    {
        let color = COLORS[k];
        c.draw_series(LineSeries::new(
            s.t.iter().zip(&s.energy).map(|(t, e)| (*t, e[k])),
            color.stroke_width(if k == 0 { 3 } else { 1 }),
        ))?
        .label(*name)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

fn shapes(path: &Path, s: &Series, scene: &Scene) -> Res {
    let root = SVGBackend::new(path, (900, 800)).into_drawing_area();
    root.fill(&WHITE)?;
    let all = || s.shapes.iter().flat_map(|(_, rods)| rods.iter().flatten());
    let (rx, rz) = square(range(all().map(|p| p[0])), range(all().map(|p| p[2])));
    let mut c = ChartBuilder::on(&root)
        .caption("rod shapes, x-z projection [m]", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(rx.0..rx.1, rz.0..rz.1)?;
    c.configure_mesh().x_desc("x").y_desc("z").draw()?;
    for (k, (t, rods)) in s.shapes.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        for (r, pts) in rods.iter().enumerate() {
            c.draw_series(
                pts.iter()
                    .map(|p| Circle::new((p[0], p[2]), 3, color.filled())),
            )?;
            let series = c.draw_series(LineSeries::new(
                pts.iter().map(|p| (p[0], p[2])),
                color.stroke_width(2),
            ))?;
            if r == 0 {
                let label = if scene.rods.len() > 1 {
                    format!("t = {t:.3} s (all rods)")
                } else {
                    format!("t = {t:.3} s")
                };
                series
                    .label(label)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            }
        }
    }
    // Put the legend in the corner the rod visits least, so it hides no shape.
    let (cx, cz) = (0.5 * (rx.0 + rx.1), 0.5 * (rz.0 + rz.1));
    let mut counts = [0usize; 4];
    for p in all() {
        counts[usize::from(p[0] > cx) + 2 * usize::from(p[2] > cz)] += 1;
    }
    let corner = (0..4).min_by_key(|&i| counts[i]).unwrap_or(3);
    let position = match corner {
        0 => SeriesLabelPosition::LowerLeft,
        1 => SeriesLabelPosition::LowerRight,
        2 => SeriesLabelPosition::UpperLeft,
        _ => SeriesLabelPosition::UpperRight,
    };
    c.configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
