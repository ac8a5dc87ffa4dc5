//! softrod-viz: what a person looks at after a softrod run.
//!
//! - [`html`]: an animated 3-D view in one self-contained HTML file (inline
//!   WebGL, no network), from [`ViewData`].
//! - [`plot`]: SVG figures for publication (tip trajectory, shapes, energy,
//!   strains, cable tensions and actuator power, mode shapes), from plain
//!   series.
//! - [`run_dir`]: reading and writing a run directory's `shape.csv`,
//!   `view.json` and `bodies.csv`, so a view can be rebuilt from files alone.
//! - [`collect`]: the same view built from a run's frames as it produces them.
//!
//! The crate depends on no physics crate: every input is plain data in SI
//! units and the world frame (see [`data`]).
//!
//! ```
//! use softrod_viz::demo::SwingingRods;
//! use softrod_viz::{ViewOptions, render_html};
//!
//! let view = SwingingRods { rods: 2, ..SwingingRods::default() }.build();
//! let (page, stats) = render_html(&view, &ViewOptions::default()).unwrap();
//! assert!(page.starts_with("<!DOCTYPE html>"));
//! assert_eq!(stats.frames.len(), 201); // all output times fit the budget
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod collect;
pub mod data;
pub mod decimate;
pub mod demo;
pub mod error;
pub mod html;
pub mod obstacles;
pub mod plot;
pub mod png;
pub mod run_dir;

pub use data::{BodyShape, BodyTrack, CableTrack, Pose, RodTrack, ViewData};
pub use error::VizError;
pub use html::{ViewOptions, ViewStats, render_html, write_html};
pub use obstacles::{ObstacleShape, ObstacleTrack};

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
