//! Scene files for softrod: parsing and validation of the TOML format
//! described in `docs/scene-format.md` (the contract) and
//! `docs/scene-format-extensions.md` (what this crate adds).
//!
//! [`Scene::from_path`] / [`Scene::from_str`] read a scene into raw serde
//! structs that deny unknown keys, then validate every value into a typed
//! [`Scene`] with SI units and all defaults filled in. Errors are one
//! [`SceneError`] naming the file, the key path (`rod[0].material.young`), the
//! line and column where known, and what is wrong; suspicious but legal input
//! comes back as [`Warning`]s next to the scene.
//!
//! [`Scene::build`] (module [`build`]) turns a scene into a
//! `softrod_dynamics::Model` holding only the terms the scene has, plus the
//! initial state.
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
//! assert_eq!(scene.rods[0].material.shear_modulus, 1.0e6 / 3.0);
//!
//! let err = Scene::from_str("[[rod]]\nname = \"arm\"\nlenght = 0.5\n", "bad.toml").unwrap_err();
//! assert!(err.to_string().starts_with("bad.toml:3:1: rod[0].lenght: unknown key"));
//! ```

#![warn(missing_docs)]

mod actuation;
pub mod build;
mod error;
mod locate;
mod raw;
mod rod;
mod scene;
mod validate;

pub use actuation::{Cable, Load, LoadFrame, Routing, Tension};
pub use build::Built;
pub use error::{Location, SceneError, Warning};
pub use rod::{Drag, Material, Pose, Rod, STRAIN_NAMES, Section, StrainSelection};
pub use scene::{Initial, Integrator, Mode, Reference, Run, Scene, UnknownIntegrator, World};
