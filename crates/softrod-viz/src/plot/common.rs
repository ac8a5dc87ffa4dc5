//! Shared pieces of the figures: fonts, colours, units, legends, panels.

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::PanelInfo;
use crate::error::VizError;

pub(crate) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

pub(crate) const FONT: &str = "sans-serif";
// Nominal sizes: plotters writes `font-size = nominal / 1.24` into the SVG,
// so these give 24, 20, 18.5, 16 and 17 px text.
pub(crate) const TITLE_PX: u32 = 30;
pub(crate) const PANEL_TITLE_PX: u32 = 25;
pub(crate) const LABEL_PX: u32 = 23;
pub(crate) const TICK_PX: u32 = 20;
pub(crate) const LEGEND_PX: u32 = 21;
pub(crate) const LEGEND_W: u32 = 250;
pub(crate) const TITLE_H: u32 = 44;

/// Colours of rods (and of other named series), in order: the "tab10"
/// qualitative palette, distinguishable and print-safe.
pub(crate) const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
    RGBColor(188, 189, 34),
    RGBColor(127, 127, 127),
];

pub(crate) fn color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// A sequential colour for `u ∈ [0, 1]` (early → late): viridis, the
/// perceptually uniform colormap of matplotlib (its tabulated colours at
/// every tenth, interpolated), from dark purple through blue and green,
/// stopping at 0.9 before its pale yellow end, which vanishes on white.
/// Lightness rises monotonically, so the order of times reads in grey too.
pub(crate) fn sequential(u: f64) -> RGBColor {
    const VIRIDIS: [(f64, f64, f64); 11] = [
        (68.0, 1.0, 84.0),
        (72.0, 36.0, 117.0),
        (65.0, 68.0, 135.0),
        (53.0, 95.0, 141.0),
        (42.0, 120.0, 142.0),
        (33.0, 145.0, 140.0),
        (34.0, 168.0, 132.0),
        (68.0, 191.0, 112.0),
        (122.0, 209.0, 81.0),
        (189.0, 223.0, 38.0),
        (253.0, 231.0, 37.0),
    ];
    let x = u.clamp(0.0, 1.0) * 0.9 * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    let mix = |p: f64, q: f64| (p + f * (q - p)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// `c` mixed with white by `w ∈ [0, 1]`.
pub(crate) fn lighten(c: RGBColor, w: f64) -> RGBColor {
    let m = |v: u8| (f64::from(v) + w * (255.0 - f64::from(v))).round() as u8;
    RGBColor(m(c.0), m(c.1), m(c.2))
}

/// The display unit of lengths for a span (m): numbers between ~0.1 and
/// ~1000 on the ticks. Returns (unit, factor from metres).
pub(crate) fn length_unit(span: f64) -> (&'static str, f64) {
    if span >= 0.5 {
        ("m", 1.0)
    } else if span >= 5e-4 {
        ("mm", 1e3)
    } else {
        ("µm", 1e6)
    }
}

/// SI prefix for a quantity whose largest magnitude is `max_abs`:
/// (prefix, factor from the base unit).
pub(crate) fn si_prefix(max_abs: f64) -> (&'static str, f64) {
    let table = [
        (1e9, "G", 1e-9),
        (1e6, "M", 1e-6),
        (1e3, "k", 1e-3),
        (1.0, "", 1.0),
        (1e-3, "m", 1e3),
        (1e-6, "µ", 1e6),
        (1e-9, "n", 1e9),
        (1e-12, "p", 1e12),
    ];
    if !(max_abs.is_finite() && max_abs > 0.0) {
        return ("", 1.0);
    }
    for (lim, p, f) in table {
        if max_abs >= lim {
            return (p, f);
        }
    }
    ("f", 1e15)
}

/// Decimals for tick labels of a (displayed) span with ~`n` ticks.
pub(crate) fn decimals(span: f64, n: usize) -> usize {
    if !(span.is_finite() && span > 0.0) {
        return 2;
    }
    let step = span / n.max(1) as f64;
    let d = -(step.log10().floor());
    d.clamp(0.0, 9.0) as usize
}

/// `[lo, hi]` of finite values, widened by `pad` of the span on each side;
/// a degenerate range is widened around its value.
pub(crate) fn range(vals: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    let min_span = 1e-9 * lo.abs().max(hi.abs()).max(1e-12);
    if span < min_span {
        // Constant data: ±5 % around a non-zero value, ±1 around zero.
        let half = if lo.abs() > 0.0 { 0.05 * lo.abs() } else { 1.0 };
        return (lo - half, hi + half);
    }
    (lo - pad * span, hi + pad * span)
}

/// `(min, max)` of the finite values (`(0, 0)` for none).
pub(crate) fn bounds(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo.is_finite() { (lo, hi) } else { (0.0, 0.0) }
}

/// `max − min` of the finite values (0 for none or one).
pub(crate) fn extent(vals: impl Iterator<Item = f64>) -> f64 {
    let (lo, hi) = bounds(vals);
    hi - lo
}

pub(crate) fn plot_err<E: std::fmt::Display>(plot: &'static str) -> impl Fn(E) -> VizError {
    move |e| VizError::Plot {
        plot,
        message: e.to_string(),
    }
}

pub(crate) fn check_finite(what: &str, v: &[f64]) -> Result<(), VizError> {
    match v.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(VizError::NotFinite {
            what: what.into(),
            index: i,
            value: v[i],
        }),
    }
}

pub(crate) fn check_len(what: &str, got: usize, expected: usize) -> Result<(), VizError> {
    if got == expected {
        Ok(())
    } else {
        Err(VizError::Count {
            what: what.into(),
            got,
            expected,
        })
    }
}

/// How a legend entry is drawn.
#[derive(Clone, Copy)]
pub(crate) enum Swatch {
    Line {
        color: RGBColor,
        width: u32,
        dashed: bool,
    },
    Circle(RGBColor),
    Square(RGBColor),
    /// An outlined square: a rigid body's mark.
    HollowSquare(RGBColor),
    /// A header line (bold text, no swatch).
    Header,
    /// Plain text (a note).
    Note,
}

pub(crate) struct LegendEntry {
    pub label: String,
    pub swatch: Swatch,
}

impl LegendEntry {
    pub fn line(label: impl Into<String>, color: RGBColor, width: u32) -> Self {
        Self {
            label: label.into(),
            swatch: Swatch::Line {
                color,
                width,
                dashed: false,
            },
        }
    }
    pub fn header(label: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            swatch: Swatch::Header,
        }
    }
}

/// Draws a legend down the left of `area`, starting at `top` px.
pub(crate) fn draw_legend(
    area: &Area,
    top: i32,
    entries: &[LegendEntry],
    plot: &'static str,
) -> Result<(), VizError> {
    let err = plot_err(plot);
    let row = (LEGEND_PX as f64 * 1.4).round() as i32;
    let x0 = 14;
    let mut y = top;
    let text = TextStyle::from((FONT, LEGEND_PX).into_font())
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for e in entries {
        match e.swatch {
            Swatch::Line {
                color,
                width,
                dashed,
            } => {
                if dashed {
                    for k in 0..3 {
                        let a = x0 + 12 * k;
                        area.draw(&PathElement::new(
                            vec![(a, y), (a + 7, y)],
                            color.stroke_width(width),
                        ))
                        .map_err(&err)?;
                    }
                } else {
                    area.draw(&PathElement::new(
                        vec![(x0, y), (x0 + 32, y)],
                        color.stroke_width(width),
                    ))
                    .map_err(&err)?;
                }
            }
            Swatch::Circle(c) => area
                .draw(&Circle::new((x0 + 16, y), 6, c.filled()))
                .map_err(&err)?,
            Swatch::Square(c) => area
                .draw(&Rectangle::new(
                    [(x0 + 10, y - 6), (x0 + 22, y + 6)],
                    c.filled(),
                ))
                .map_err(&err)?,
            Swatch::HollowSquare(c) => area
                .draw(&Rectangle::new(
                    [(x0 + 9, y - 7), (x0 + 23, y + 7)],
                    c.stroke_width(BODY_STROKE),
                ))
                .map_err(&err)?,
            Swatch::Header | Swatch::Note => {}
        }
        let (dx, style) = match e.swatch {
            Swatch::Header => (
                0,
                TextStyle::from((FONT, LEGEND_PX, FontStyle::Bold).into_font())
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ),
            Swatch::Note => (
                0,
                TextStyle::from((FONT, LEGEND_PX - 2).into_font())
                    .color(&RGBColor(70, 70, 70))
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ),
            _ => (44, text.clone()),
        };
        area.draw(&Text::new(e.label.clone(), (x0 + dx, y), style))
            .map_err(&err)?;
        y += row;
    }
    Ok(())
}

/// Splits off a figure title of `TITLE_H` px; returns the rest.
pub(crate) fn titled<'a>(
    root: &Area<'a>,
    title: &str,
    plot: &'static str,
) -> Result<Area<'a>, VizError> {
    root.fill(&WHITE).map_err(plot_err(plot))?;
    let (head, rest) = root.split_vertically(TITLE_H);
    head.draw(&Text::new(
        title.to_string(),
        (16, (TITLE_H / 2) as i32 + 2),
        TextStyle::from((FONT, TITLE_PX, FontStyle::Bold).into_font())
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center)),
    ))
    .map_err(plot_err(plot))?;
    Ok(rest)
}

/// Margins and label areas of every panel, px.
pub(crate) const MARGIN: u32 = 14;
pub(crate) const X_LABEL_AREA: u32 = 58;
pub(crate) const Y_LABEL_AREA: u32 = 96;

fn builder<'a, 'b>(area: &'a Area<'b>) -> ChartBuilder<'a, 'b, SVGBackend<'b>> {
    let mut b = ChartBuilder::on(area);
    b.margin(MARGIN)
        .margin_right(MARGIN + 10)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA);
    b
}

/// Height of a panel's title strip, px.
pub(crate) const PANEL_TITLE_H: u32 = 30;

/// The part of a panel below its title strip (drawing the title when
/// `draw`).
fn panel_body<'a>(
    area: &Area<'a>,
    title: &str,
    draw: bool,
    plot: &'static str,
) -> Result<Area<'a>, VizError> {
    if title.is_empty() {
        return Ok(area.clone());
    }
    let (head, body) = area.split_vertically(PANEL_TITLE_H);
    if draw {
        let (w, _) = head.dim_in_pixel();
        head.draw(&Text::new(
            title.to_string(),
            (
                (Y_LABEL_AREA + MARGIN + (w - Y_LABEL_AREA - MARGIN) / 2) as i32,
                (PANEL_TITLE_H / 2 + 4) as i32,
            ),
            TextStyle::from((FONT, PANEL_TITLE_PX).into_font())
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))
        .map_err(plot_err(plot))?;
    }
    Ok(body)
}

/// Size of the plotting area a panel on `area` gets (title strip, label
/// areas and margins taken off), px. Draws nothing.
pub(crate) fn plot_size(
    area: &Area,
    title: &str,
    plot: &'static str,
) -> Result<(u32, u32), VizError> {
    let body = panel_body(area, title, false, plot)?;
    let chart = builder(&body)
        .build_cartesian_2d(0.0..1.0, 0.0..1.0)
        .map_err(plot_err(plot))?;
    Ok(chart.plotting_area().dim_in_pixel())
}

/// A curve or point set to draw in a panel.
pub(crate) struct Stroke {
    pub points: Vec<(f64, f64)>,
    pub color: RGBColor,
    pub width: u32,
    pub dashed: bool,
}

pub(crate) enum Marker {
    Circle((f64, f64), RGBColor),
    Square((f64, f64), RGBColor),
    /// A rigid body: an outlined square of ±`BODY_HALF_PX` centred on its
    /// frame origin, with its name beside it when given.
    Body((f64, f64), RGBColor, Option<String>),
}

/// Half the side of a body's mark, px.
pub(crate) const BODY_HALF_PX: f64 = 7.0;
/// Line width of a body's mark, px.
pub(crate) const BODY_STROKE: u32 = 2;

/// What to draw in one panel.
pub(crate) struct PanelSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Display factor and decimals of ticks.
    pub x_scale: f64,
    pub y_scale: f64,
    pub strokes: Vec<Stroke>,
    pub markers: Vec<Marker>,
    /// A horizontal reference line at this y (e.g. zero).
    pub zero_line: bool,
}

/// Draws a panel with the given ranges; returns its info.
pub(crate) fn draw_panel(
    area: &Area,
    spec: &PanelSpec,
    x_range: (f64, f64),
    y_range: (f64, f64),
    equal_aspect: bool,
    plot: &'static str,
) -> Result<PanelInfo, VizError> {
    let err = plot_err(plot);
    let body = panel_body(area, &spec.title, true, plot)?;
    let mut chart = builder(&body)
        .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)
        .map_err(&err)?;
    let plot_px = chart.plotting_area().dim_in_pixel();
    let (px_x, px_y) = chart.plotting_area().get_pixel_range();
    let (xs, ys) = (spec.x_scale, spec.y_scale);
    let nx = (plot_px.0 / 55).clamp(5, 12) as usize;
    let ny = (plot_px.1 / 45).clamp(4, 10) as usize;
    let dx = decimals((x_range.1 - x_range.0) * xs, nx);
    let dy = decimals((y_range.1 - y_range.0) * ys, ny);
    let fx = move |v: &f64| format_tick(v * xs, dx);
    let fy = move |v: &f64| format_tick(v * ys, dy);
    chart
        .configure_mesh()
        .x_labels(nx)
        .y_labels(ny)
        .x_desc(spec.x_label.as_str())
        .y_desc(spec.y_label.as_str())
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .label_style((FONT, TICK_PX).into_font())
        .axis_desc_style((FONT, LABEL_PX).into_font())
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .axis_style(RGBColor(60, 60, 60))
        .draw()
        .map_err(&err)?;
    if spec.zero_line && y_range.0 < 0.0 && y_range.1 > 0.0 {
        chart
            .draw_series(LineSeries::new(
                [(x_range.0, 0.0), (x_range.1, 0.0)],
                RGBColor(120, 120, 120).stroke_width(1),
            ))
            .map_err(&err)?;
    }
    // The curves keep sub-pixel precision: plotters places on whole pixels,
    // so they are written as polylines of their own (at plotters' map, to
    // the hundredth of a pixel, decimated to a tenth of one) where a
    // placeholder stands in the document's order until [`finish_svg`].
    let (x0, x1) = (f64::from(px_x.start), f64::from(px_x.end - 1));
    let (y0, y1) = (f64::from(px_y.start), f64::from(px_y.end - 1));
    let to_px = |(x, y): (f64, f64)| {
        (
            x0 + (x1 - x0) * (x - x_range.0) / (x_range.1 - x_range.0),
            y1 - (y1 - y0) * (y - y_range.0) / (y_range.1 - y_range.0),
        )
    };
    let mut polylines = String::new();
    for s in &spec.strokes {
        let px: Vec<(f64, f64)> = s.points.iter().map(|&p| to_px(p)).collect();
        polylines.push_str(&polyline(&px, s.color, s.width, s.dashed));
    }
    if !polylines.is_empty() {
        let k = PENDING.with(|p| {
            let mut p = p.borrow_mut();
            p.push(polylines);
            p.len() - 1
        });
        body.draw(&Text::new(
            format!("{PLACEHOLDER}{k}"),
            (0, 0),
            (FONT, TICK_PX).into_font(),
        ))
        .map_err(&err)?;
    }
    // Data units per pixel, to size marks in pixels whatever the ranges.
    let (ux, uy) = (
        (x_range.1 - x_range.0) / f64::from(plot_px.0.max(1)),
        (y_range.1 - y_range.0) / f64::from(plot_px.1.max(1)),
    );
    // Body names placed so far, as pixel boxes (left, bottom, right, top)
    // relative to the data origin: a name that would cover one moves up.
    let mut labels: Vec<(f64, f64, f64, f64)> = Vec::new();
    for m in &spec.markers {
        match m {
            Marker::Circle(p, c) => chart
                .draw_series([Circle::new(*p, 6, c.filled())])
                .map(|_| ())
                .map_err(&err)?,
            Marker::Square(p, c) => {
                // A square of ±6 px around p, in data units.
                chart
                    .draw_series([Rectangle::new(
                        [
                            (p.0 - 6.0 * ux, p.1 - 6.0 * uy),
                            (p.0 + 6.0 * ux, p.1 + 6.0 * uy),
                        ],
                        c.filled(),
                    )])
                    .map(|_| ())
                    .map_err(&err)?
            }
            Marker::Body(p, c, label) => {
                let (hx, hy) = (BODY_HALF_PX * ux, BODY_HALF_PX * uy);
                chart
                    .draw_series([Rectangle::new(
                        [(p.0 - hx, p.1 - hy), (p.0 + hx, p.1 + hy)],
                        c.stroke_width(BODY_STROKE),
                    )])
                    .map_err(&err)?;
                if let Some(name) = label {
                    // Beside the mark, clear of the rod it ends; the text
                    // box is estimated (≈ 0.52 em a character, sans-serif).
                    let (w, h) = (
                        0.52 * f64::from(TICK_PX) * name.chars().count() as f64,
                        1.2 * f64::from(TICK_PX),
                    );
                    let overlaps = |l: f64, b: f64, o: &(f64, f64, f64, f64)| {
                        l < o.2 && o.0 < l + w && b < o.3 && o.1 < b + h
                    };
                    // The first of up-right, up-left, down-right, down-left
                    // of the mark that stays in the plot and covers no
                    // earlier name; else up-right, stacked above those.
                    let gap = 1.6 * BODY_HALF_PX;
                    let (cx, cy) = (p.0 / ux, p.1 / uy);
                    let free = |l: f64, b: f64| {
                        l >= x_range.0 / ux
                            && l + w <= x_range.1 / ux
                            && b >= y_range.0 / uy
                            && b + h <= y_range.1 / uy
                            && !labels.iter().any(|o| overlaps(l, b, o))
                    };
                    let place = [
                        (cx + gap, cy + gap),
                        (cx - gap - w, cy + gap),
                        (cx + gap, cy - gap - h),
                        (cx - gap - w, cy - gap - h),
                    ]
                    .into_iter()
                    .find(|&(l, b)| free(l, b));
                    let (left, bottom) = place.unwrap_or_else(|| {
                        let (l, mut b) = (cx + gap, cy + gap);
                        for _ in 0..labels.len() {
                            match labels.iter().find(|o| overlaps(l, b, o)) {
                                Some(o) => b = o.3,
                                None => break,
                            }
                        }
                        (l, b)
                    });
                    labels.push((left, bottom, left + w, bottom + h));
                    let style = TextStyle::from((FONT, TICK_PX).into_font())
                        .color(&RGBColor(40, 40, 40))
                        .pos(Pos::new(HPos::Left, VPos::Bottom));
                    chart
                        .draw_series([Text::new(name.clone(), (left * ux, bottom * uy), style)])
                        .map_err(&err)?;
                }
            }
        }
    }
    Ok(PanelInfo {
        title: spec.title.clone(),
        x_label: spec.x_label.clone(),
        y_label: spec.y_label.clone(),
        x_range,
        y_range,
        plot_px,
        plot_rect: ((px_x.start, px_y.start), (px_x.end, px_y.end)),
        equal_aspect,
    })
}

thread_local! {
    /// The sub-pixel polylines of the panels drawn since the last
    /// [`finish_svg`] on this thread, each standing in its SVG as the text
    /// `PLACEHOLDER k` until then (plotters owns the document while it draws).
    static PENDING: std::cell::RefCell<Vec<String>> = const { std::cell::RefCell::new(Vec::new()) };
}

const PLACEHOLDER: &str = "softrod-subpixel-polylines-";

/// Pixels a decimated curve may stray from the drawn one: a tenth of a
/// pixel, invisible at any zoom that shows the figure's lines as lines.
pub(crate) const DECIMATION_PX: f64 = 0.1;

/// Replaces the placeholders [`draw_panel`] left in `svg` with their
/// polylines (call once the backend has presented the document).
pub(crate) fn finish_svg(svg: &mut String) {
    let pending = PENDING.with(|p| std::mem::take(&mut *p.borrow_mut()));
    for (k, lines) in pending.iter().enumerate() {
        // plotters writes `<text …>\nTOKEN\n</text>`: the token, then only
        // white space up to the closing tag (so `…-1` is not `…-12`).
        let token = format!("{PLACEHOLDER}{k}");
        let found = svg.match_indices(&token).find_map(|(at, _)| {
            let rest = &svg[at + token.len()..];
            let close = rest.len() - rest.trim_start().len();
            rest[close..]
                .starts_with("</text>")
                .then(|| (at, at + token.len() + close + "</text>".len()))
        });
        let Some((at, end)) = found else {
            continue; // from a figure that failed before presenting
        };
        let start = svg[..at].rfind("<text").unwrap_or(at);
        svg.replace_range(start..end, lines);
    }
}

/// An SVG polyline through pixel points, decimated (Ramer–Douglas–Peucker,
/// [`DECIMATION_PX`]) and written to a hundredth of a pixel; empty for no
/// points.
pub(crate) fn polyline(px: &[(f64, f64)], color: RGBColor, width: u32, dashed: bool) -> String {
    use std::fmt::Write;
    if px.is_empty() {
        return String::new();
    }
    let keep = decimate(px, DECIMATION_PX);
    let mut points = String::with_capacity(14 * keep.len());
    for (i, &(x, y)) in px.iter().enumerate() {
        if keep[i] {
            let _ = write!(points, "{x:.2},{y:.2} ");
        }
    }
    let dash = if dashed {
        " stroke-dasharray=\"7 5\""
    } else {
        ""
    };
    format!(
        "<polyline fill=\"none\" opacity=\"1\" stroke=\"#{:02X}{:02X}{:02X}\" stroke-width=\"{width}\"{dash} stroke-linejoin=\"round\" points=\"{}\"/>\n",
        color.0,
        color.1,
        color.2,
        points.trim_end()
    )
}

/// Which points of `p` to keep so that the polyline through them stays
/// within `tol` of every dropped one (Ramer–Douglas–Peucker; the ends
/// always kept). Iterative: long curves cannot overflow the stack.
pub(crate) fn decimate(p: &[(f64, f64)], tol: f64) -> Vec<bool> {
    let n = p.len();
    let mut keep = vec![false; n];
    if n == 0 {
        return keep;
    }
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0, n - 1)];
    while let Some((a, b)) = stack.pop() {
        if b <= a + 1 {
            continue;
        }
        let (ax, ay) = p[a];
        let (dx, dy) = (p[b].0 - ax, p[b].1 - ay);
        let len2 = dx * dx + dy * dy;
        let (mut worst, mut at) = (-1.0, a);
        for (i, &(x, y)) in p.iter().enumerate().take(b).skip(a + 1) {
            // Distance to the chord as a segment, not a line: a path that
            // turns back along itself keeps its turning points.
            let u = if len2 > 0.0 {
                (((x - ax) * dx + (y - ay) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d = (x - ax - u * dx).hypot(y - ay - u * dy);
            if d > worst {
                (worst, at) = (d, i);
            }
        }
        if worst > tol {
            keep[at] = true;
            stack.push((a, at));
            stack.push((at, b));
        }
    }
    keep
}

/// A tick number with `d` decimals, without "-0".
pub(crate) fn format_tick(v: f64, d: usize) -> String {
    let s = format!("{v:.d$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// Equal-aspect ranges for panels that share one scale (m per px): each
/// panel's data box `(x range, y range)` is centred and widened so that
/// `span_x / width = span_y / height = scale` with the largest scale any
/// panel needs.
/// A panel's (horizontal, vertical) data ranges.
pub(crate) type Box2 = ((f64, f64), (f64, f64));

pub(crate) fn equal_aspect_ranges(boxes: &[Box2], sizes: &[(u32, u32)]) -> Vec<Box2> {
    let scale = boxes
        .iter()
        .zip(sizes)
        .map(|((x, y), (w, h))| {
            ((x.1 - x.0) / f64::from((*w).max(1))).max((y.1 - y.0) / f64::from((*h).max(1)))
        })
        .fold(0.0, f64::max);
    boxes
        .iter()
        .zip(sizes)
        .map(|((x, y), (w, h))| {
            let (cx, cy) = (0.5 * (x.0 + x.1), 0.5 * (y.0 + y.1));
            let (hx, hy) = (0.5 * scale * f64::from(*w), 0.5 * scale * f64::from(*h));
            ((cx - hx, cx + hx), (cy - hy, cy + hy))
        })
        .collect()
}

/// `v` with `sig` significant digits, trailing zeros dropped (`1.12`,
/// `19.66`, `0.0123`).
pub(crate) fn significant(v: f64, sig: i32) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let d = (sig - 1 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.d$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod subpixel_tests {
    use super::*;

    /// Distance from `q` to the polyline through `line`.
    fn to_polyline(q: (f64, f64), line: &[(f64, f64)]) -> f64 {
        line.windows(2)
            .map(|w| {
                let ((ax, ay), (bx, by)) = (w[0], w[1]);
                let (dx, dy) = (bx - ax, by - ay);
                let l2 = dx * dx + dy * dy;
                let u = if l2 > 0.0 {
                    (((q.0 - ax) * dx + (q.1 - ay) * dy) / l2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (q.0 - ax - u * dx).hypot(q.1 - ay - u * dy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn decimation_keeps_every_point_within_tolerance() {
        let p: Vec<(f64, f64)> = (0..5000)
            .map(|i| {
                let x = i as f64 * 0.13;
                (x, 80.0 * (x / 37.0).sin() + 3.0 * (x / 3.1).cos())
            })
            .collect();
        let keep = decimate(&p, DECIMATION_PX);
        let kept: Vec<_> = p
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(q, _)| *q)
            .collect();
        assert!(kept.len() < p.len() / 3, "{} of {}", kept.len(), p.len());
        for q in &p {
            assert!(to_polyline(*q, &kept) <= DECIMATION_PX + 1e-12);
        }
        // Collinear points reduce to the ends; a path turning back along
        // itself keeps its turning points.
        let line: Vec<_> = (0..100).map(|i| (i as f64, 2.0 * i as f64)).collect();
        assert_eq!(decimate(&line, 0.1).iter().filter(|k| **k).count(), 2);
        let back = [(0.0, 0.0), (10.0, 0.0), (5.0, 0.0)];
        assert_eq!(decimate(&back, 0.1), vec![true, true, true]);
    }

    #[test]
    fn polylines_keep_hundredths_of_a_pixel() {
        let s = polyline(
            &[(1.234, 5.678), (9.999, 0.004)],
            RGBColor(1, 2, 255),
            2,
            true,
        );
        assert!(s.contains("points=\"1.23,5.68 10.00,0.00\""), "{s}");
        assert!(
            s.contains("stroke=\"#0102FF\"") && s.contains("stroke-dasharray"),
            "{s}"
        );
        assert!(polyline(&[], BLACK, 1, false).is_empty());
    }
}
