//! Strains along a rod at chosen times.

use plotters::prelude::*;

use super::common::{
    Area, LEGEND_W, LegendEntry, PanelSpec, Stroke, TITLE_H, check_finite, check_len, color,
    draw_legend, draw_panel, extent, finish_svg, length_unit, plot_err, range, sequential, titled,
};
use super::{Figure, PanelInfo};
use crate::error::VizError;

/// A strain component `ξ = (k, q)` (docs/theory.md §0.2: angular part
/// first; body frame, local x = tangent).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrainComponent {
    /// `k_x`: torsion, 1/m.
    Kx,
    /// `k_y`: bending about local y, 1/m.
    Ky,
    /// `k_z`: bending about local z, 1/m.
    Kz,
    /// `q_x`: stretch (1 at rest for a straight rod), dimensionless.
    Qx,
    /// `q_y`: shear along local y, dimensionless.
    Qy,
    /// `q_z`: shear along local z, dimensionless.
    Qz,
}

impl StrainComponent {
    /// All six, in the canonical order.
    pub const ALL: [StrainComponent; 6] =
        [Self::Kx, Self::Ky, Self::Kz, Self::Qx, Self::Qy, Self::Qz];

    /// Index in `ξ` (0…5).
    pub fn index(self) -> usize {
        self as usize
    }

    /// Axis label with unit.
    pub fn label(self) -> &'static str {
        match self {
            Self::Kx => "k_x [1/m]",
            Self::Ky => "k_y [1/m]",
            Self::Kz => "k_z [1/m]",
            Self::Qx => "q_x [–]",
            Self::Qy => "q_y [–]",
            Self::Qz => "q_z [–]",
        }
    }

    /// Its symbol (`k_y`).
    pub fn symbol(self) -> &'static str {
        ["k_x", "k_y", "k_z", "q_x", "q_y", "q_z"][self.index()]
    }

    /// What it measures.
    pub fn meaning(self) -> &'static str {
        match self {
            Self::Kx => "torsion",
            Self::Ky => "bending about y",
            Self::Kz => "bending about z",
            Self::Qx => "stretch",
            Self::Qy => "shear along y",
            Self::Qz => "shear along z",
        }
    }
}

/// Strain profiles of one rod: `values[k][i]` is `ξ` at abscissa `s[i]` at
/// time `times[k]`.
#[derive(Debug, Clone, PartialEq)]
pub struct StrainProfiles {
    /// Rod name (title).
    pub rod: String,
    /// Times of the profiles, s.
    pub times: Vec<f64>,
    /// Abscissae, m, non-decreasing (a repeated value makes a step).
    pub s: Vec<f64>,
    /// `ξ = (k_x, k_y, k_z, q_x, q_y, q_z)` per time and abscissa.
    pub values: Vec<Vec<[f64; 6]>>,
    /// The components to plot (e.g. those the scene's `strains` selects).
    pub components: Vec<StrainComponent>,
}

impl StrainProfiles {
    /// Profiles of a piecewise-constant strain (PCS): `bounds` are the N+1
    /// piece boundaries (m), `per_piece[k][n]` the strain of piece `n` at
    /// time `k`. Each piece becomes two samples (its ends), so the plot
    /// shows the steps.
    pub fn piecewise_constant(
        rod: impl Into<String>,
        times: Vec<f64>,
        bounds: &[f64],
        per_piece: &[Vec<[f64; 6]>],
        components: Vec<StrainComponent>,
    ) -> Self {
        let n = bounds.len().saturating_sub(1);
        let s = (0..n).flat_map(|p| [bounds[p], bounds[p + 1]]).collect();
        let values = per_piece
            .iter()
            .map(|pieces| pieces.iter().take(n).flat_map(|v| [*v, *v]).collect())
            .collect();
        Self {
            rod: rod.into(),
            times,
            s,
            values,
            components,
        }
    }
}

const PANEL_W: u32 = 560;
const PANEL_H: u32 = 330;

/// One panel per component (two per row), one line per time coloured
/// dark → light green = early → late, times in the legend; `k` in 1/m,
/// `q` dimensionless.
pub fn strains(title: &str, p: &StrainProfiles) -> Result<Figure, VizError> {
    let plot = "strains";
    if p.components.is_empty() {
        return Err(VizError::Empty("components"));
    }
    if p.times.is_empty() {
        return Err(VizError::Empty("times"));
    }
    check_finite("times", &p.times)?;
    check_finite("s", &p.s)?;
    check_len("values", p.values.len(), p.times.len())?;
    for (k, v) in p.values.iter().enumerate() {
        check_len(&format!("values[{k}]"), v.len(), p.s.len())?;
        for x in v {
            check_finite(&format!("values[{k}]"), x)?;
        }
    }
    if let Some(i) = p.s.windows(2).position(|w| w[1] < w[0]) {
        return Err(VizError::NotIncreasing {
            what: "s".into(),
            index: i + 1,
        });
    }
    let cols = if p.components.len() == 1 { 1 } else { 2 };
    let rows = p.components.len().div_ceil(cols);
    let (w, h) = (
        cols as u32 * PANEL_W + LEGEND_W,
        TITLE_H + rows as u32 * PANEL_H,
    );
    let m = p.times.len();
    let line_color = |k: usize| {
        if m == 1 {
            color(0)
        } else {
            sequential(k as f64 / (m - 1) as f64)
        }
    };
    let mut svg = String::new();
    let mut infos: Vec<PanelInfo> = Vec::new();
    {
        let root: Area = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let body = titled(&root, title, plot)?;
        let (left, legend_area) = body.split_horizontally(cols as u32 * PANEL_W);
        let cells = left.split_evenly((rows, cols));
        let sr = range(p.s.iter().copied(), 0.02);
        let (su, sf) = length_unit(extent(p.s.iter().copied()));
        for (c, comp) in p.components.iter().enumerate() {
            let j = comp.index();
            let yr = range(p.values.iter().flatten().map(|v| v[j]), 0.08);
            // Small (or huge) strains get a power of ten in the label, so
            // ticks read 1, 2, 3 instead of 0.00010, 0.00020, 0.00030.
            let (power, y_scale) = decade(yr.0.abs().max(yr.1.abs()));
            let y_label = match (power, comp.index() < 3) {
                (0, _) => comp.label().to_string(),
                (e, true) => format!("{} [10{} 1/m]", comp.symbol(), superscript(e)),
                (e, false) => format!("{} [10{}]", comp.symbol(), superscript(e)),
            };
            let spec = PanelSpec {
                title: format!("{} ({})", comp.meaning(), p.rod),
                x_label: format!("s [{su}]"),
                y_label,
                x_scale: sf,
                y_scale,
                strokes: p
                    .values
                    .iter()
                    .enumerate()
                    .map(|(k, v)| Stroke {
                        points: p.s.iter().copied().zip(v.iter().map(|x| x[j])).collect(),
                        color: line_color(k),
                        width: 2,
                        dashed: false,
                    })
                    .collect(),
                markers: Vec::new(),
                zero_line: true,
            };
            infos.push(draw_panel(&cells[c], &spec, sr, yr, false, plot)?);
        }
        let mut legend = vec![LegendEntry::header("time")];
        legend.extend(
            p.times
                .iter()
                .enumerate()
                .map(|(k, t)| LegendEntry::line(format!("t = {t} s"), line_color(k), 3)),
        );
        draw_legend(&legend_area, 40, &legend, plot)?;
        root.present().map_err(plot_err(plot))?;
    }
    finish_svg(&mut svg);
    Ok(Figure { svg, panels: infos })
}

/// The power of ten `e` to print in the label of values up to `max_abs`
/// (0 for 0.01 ≤ max_abs < 10⁴), and the display factor `10^−e`.
fn decade(max_abs: f64) -> (i32, f64) {
    if !(max_abs.is_finite() && max_abs > 0.0) || (1e-2..1e4).contains(&max_abs) {
        return (0, 1.0);
    }
    let e = max_abs.log10().floor() as i32;
    (e, 10f64.powi(-e))
}

/// `e` as superscript digits (`−4` → `⁻⁴`).
fn superscript(e: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut out = String::new();
    if e < 0 {
        out.push('⁻');
    }
    for c in e.unsigned_abs().to_string().chars() {
        out.push(DIGITS[c.to_digit(10).unwrap_or(0) as usize]);
    }
    out
}
