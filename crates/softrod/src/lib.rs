//! softrod simulates soft manipulators — slender soft arms, tentacles,
//! cable-driven continuum robots — with the Piecewise Constant Strain (PCS)
//! Cosserat-rod model. This crate is the one to depend on: it re-exports the
//! layers (`lie` → `kinematics` → `mechanics` → `dynamics` → `integrate`,
//! `scene`) and adds [`Simulation`]: a model with its initial state and run
//! settings, offering simulation, statics, modes, dynamics evaluations and
//! kinematics queries.
//!
//! A soft rod clamped horizontal and released under gravity (the scene of
//! `docs/theory.md` §8(h), whose tip is known from a DOP853 run at
//! rtol 1e-12):
//!
//! ```
//! use softrod::prelude::*;
//!
//! let material = Material::builder().density(1000.0).young(1e7).poisson(0.5).build()?;
//! let arm = Rod::builder(0.5).name("arm").pieces(8).circle(0.01).material(material)
//!     .strains([Strain::Ky, Strain::Qx, Strain::Qz]);
//! let model = Model::builder().rod(arm).gravity([0.0, 0.0, -9.81]).quadrature(5).build()?;
//! let mut sim = Simulation::new(model);
//! let traj = sim.simulate(0.25)?;
//! let tip = traj.tip_position(traj.len() - 1, 0);
//! assert!((tip[0] - 0.366446853).abs() < 1e-6 && (tip[2] + 0.314312480).abs() < 1e-6);
//! # Ok::<(), softrod::Error>(())
//! ```
//!
//! A scene file gives the same through [`Simulation::from_scene_file`] or
//! [`Simulation::from_toml`], with the scene's `[initial]` state and `[run]`
//! settings.
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
    pub use softrod_dynamics::{
        Attachment, BodySpec, Joint, JointKind, Model, RodSpec, RodSpec as Rod,
    };
    pub use softrod_kinematics::{Basis, Frame, Rod as RodGeometry, Strain};
    pub use softrod_lie::{Pose, Vec3, Vec6};
    pub use softrod_mechanics::{Cable, Material, PointLoad, RodBody, Section, Tension};
    pub use softrod_scene::Integrator;
}
