//! softrod simulates soft manipulators — slender soft arms, tentacles,
//! cable-driven continuum robots — with the Piecewise Constant Strain (PCS)
//! Cosserat-rod model. This crate is the one to depend on: it re-exports the
//! layers (`lie` → `kinematics` → `mechanics` → `dynamics` → `integrate`,
//! `scene`) and adds [`Simulation`]: a model with its initial state and run
//! settings, offering simulation, statics, modes, dynamics evaluations and
//! kinematics queries.
//!
//! ```
//! use softrod::prelude::*;
//!
//! let text = r#"
//! [world]
//! gravity = [0.0, 0.0, -9.81]
//! [[rod]]
//! name = "arm"
//! length = 0.5
//! pieces = 4
//! strains = ["ky", "qx", "qz"]
//! section = { shape = "circle", radius = 0.01 }
//! material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }
//! "#;
//! let (mut sim, _scene, _warnings) = Simulation::from_toml(text, "arm.toml")?;
//! let traj = sim.simulate(0.05)?;
//! let tip = traj.tip_position(traj.len() - 1, 0);
//! assert!(tip[2] < 0.0); // it sags under gravity
//! # Ok::<(), softrod::Error>(())
//! ```
//!
//! Units are SI; twists and wrenches are 6-vectors, angular part first;
//! velocities and forces are in the body frame of the section, poses in the
//! world frame. The equations are in `docs/theory.md` of the repository,
//! whose labels (D1)… the documentation cites.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod error;
mod settings;
mod simulation;

pub use error::{Error, Result};
pub use settings::{GENERALIZED_ALPHA_RHO_INF, Settings, output_times};
pub use simulation::{
    Equilibrium, Flow, ModalAnalysis, Observer, RunStatus, RunSummary, Sample, Simulation,
    Trajectory,
};

pub use softrod_dynamics as dynamics;
pub use softrod_integrate as integrate;
pub use softrod_kinematics as kinematics;
pub use softrod_lie as lie;
pub use softrod_mechanics as mechanics;
pub use softrod_scene as scene;

/// The names most programs need.
pub mod prelude {
    pub use crate::{Error, Settings, Simulation, Trajectory};
    pub use softrod_dynamics::{Model, RodSpec};
    pub use softrod_kinematics::{Basis, Frame, Rod as RodGeometry, Strain};
    pub use softrod_lie::{Pose, Vec3, Vec6};
    pub use softrod_mechanics::{Cable, Material, PointLoad, RodBody, Section, Tension};
    pub use softrod_scene::Integrator;
}
