//! Scene files for softrod: parsing and validation of the TOML format
//! described in `docs/scene-format.md` (the contract) and
//! `docs/scene-format-extensions.md` (what this crate adds).
//!
//! [`Scene::from_path`] / [`Scene::from_str`] read a scene into raw serde
//! structs that deny unknown keys, then validate it straight into the
//! library's own types: each rod is a `softrod_dynamics::Rod` (its
//! `Section`, `Material`, strain basis, cables, point loads and drag are
//! those of `softrod-mechanics` and `softrod-kinematics`), built by the
//! library's builders, which check every value once. This crate keeps only
//! what is a scene's: the [`World`], the [`Initial`] state, the [`Run`]
//! settings, the [`Reference`] answer, the source file and the [`Warning`]s.
//! The integrators `run.integrator` names are softrod-integrate's
//! [`Integrator`] list, re-exported here.
//!
//! Errors are one [`SceneError`] naming the file, the key path
//! (`rod[0].material.young`), the line and column where known, and what is
//! wrong; when a library constructor rejected the value, its structured
//! error (mapped to the key path by variant and quantity, never by its text)
//! is the [`SceneError`]'s `source()`.
//!
//! [`Scene::build`] turns a scene into a `softrod_dynamics::Model` holding
//! only the terms the scene has, plus the initial state ([`Built`]).
//!
//! ```
//! use softrod_scene::Scene;
//!
//! let text = r#"
//! [[rod]]
//! name = "arm"
//! length = 0.5
//! pieces = 4
//! strains = ["ky", "qx"]
//! section = { shape = "circle", radius = 0.01 }
//! material = { density = 1000.0, young = 1.0e6, poisson = 0.5 }
//! "#;
//! let (scene, warnings) = Scene::from_str(text, "arm.toml").unwrap();
//! assert!(warnings.is_empty());
//! assert_eq!(scene.n_dof(), 8);
//! assert_eq!(scene.rods[0].properties.material().shear_modulus(), 1.0e6 / 3.0);
//! assert_eq!(scene.build().unwrap().model.n_dof(), 8);
//!
//! let err = Scene::from_str("[[rod]]\nname = \"arm\"\nlenght = 0.5\n", "bad.toml").unwrap_err();
//! assert!(err.to_string().starts_with("bad.toml:3:1: rod[0].lenght: unknown key"));
//!
//! let bad = text.replace("young = 1.0e6", "young = -1.0");
//! let err = Scene::from_str(&bad, "arm.toml").unwrap_err();
//! assert_eq!(err.path(), Some("rod[0].material.young"));
//! // The library's own error is the source.
//! let cause = std::error::Error::source(&err).unwrap();
//! assert!(cause.to_string().starts_with("Young's modulus [Pa] must be positive"));
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]
// A SceneError carries the file, key path, location, value, allowed range and
// the library cause (~140 bytes): returned once per load, on a cold path,
// where boxing would only add an allocation and an indirection for callers.
#![allow(clippy::result_large_err)]

mod build;
mod error;
mod keys;
mod locate;
mod overrides;
mod raw;
mod reporter;
mod robot;
mod run;
mod scene;
mod validate;

pub use build::Built;
pub use build::ShapeFit;
pub use error::{Cause, Location, SceneError, Warning};
pub use locate::MAX_MAGNITUDE;
pub use overrides::{Override, OverrideSyntaxError};
pub use robot::Robot;
pub use run::{Integrator, Mode, Run, UnknownIntegrator};
pub use scene::{Initial, InitialShape, Reference, Scene, Target, UnknownLoad, World};
pub use validate::MAX_QUADRATURE;

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
