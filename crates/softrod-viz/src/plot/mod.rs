//! SVG figures for publication, with plotters (and the work–precision
//! chart of `softrod report`).
//!
//! Common to all: axis labels carry units (`x [mm]`, `E [mJ]`, `k_y [1/m]`),
//! the unit prefix chosen so tick numbers stay short; fonts of 15–22 px on
//! figures ~1000–1500 px wide (legible when the SVG is scaled to a column);
//! legends in their own column right of the panels, never over data;
//! rods told apart by colour. Geometry panels have **equal aspect** (one
//! metre is as many pixels across as up, the same in every panel of a
//! figure), reported per panel in [`PanelInfo`] so tests and callers can
//! check the numbers.
//!
//! Each function returns a [`Figure`] (the SVG text and its panels); write
//! it with [`Figure::write`].

mod common;
mod geometry;
mod obstacles;
mod series;
mod strains;
mod work_precision;

pub use geometry::{
    BodyMark, Mode, ModeShapes, RodCurve, ShapeSnapshot, modes, shapes, shapes_with_obstacles,
    tip_trajectory,
};
pub use series::{ActuatorSeries, EnergySeries, NamedSeries, actuators, energy};
pub use strains::{StrainComponent, StrainProfiles, strains};
pub use work_precision::{WorkPrecisionPoint, work_precision};

use std::path::Path;

use crate::error::VizError;

/// One drawn figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// The SVG document.
    pub svg: String,
    /// Its panels, left to right, top to bottom.
    pub panels: Vec<PanelInfo>,
}

impl Figure {
    /// Writes the SVG to `path`.
    pub fn write(&self, path: &Path) -> Result<(), VizError> {
        std::fs::write(path, &self.svg).map_err(|source| VizError::Io {
            path: path.to_path_buf(),
            source,
        })
    }
}

/// What a panel shows, in data units (m, s, J, …, before any display
/// prefix).
#[derive(Debug, Clone, PartialEq)]
pub struct PanelInfo {
    /// Panel title (e.g. `x–z`, `mode 2: 7.02 Hz`).
    pub title: String,
    /// Horizontal axis label with unit, as printed.
    pub x_label: String,
    /// Vertical axis label with unit, as printed.
    pub y_label: String,
    /// Horizontal range.
    pub x_range: (f64, f64),
    /// Vertical range.
    pub y_range: (f64, f64),
    /// Size of the plotting area, pixels (width, height).
    pub plot_px: (u32, u32),
    /// The plotting area in figure pixels: (left, top), (right, bottom).
    pub plot_rect: ((i32, i32), (i32, i32)),
    /// Drawn with equal aspect: `(x₁ − x₀) / width = (y₁ − y₀) / height`.
    pub equal_aspect: bool,
}
