//! softrod simulates soft manipulators — slender soft arms, tentacles,
//! cable-driven continuum robots — with the Piecewise Constant Strain (PCS)
//! Cosserat-rod model. This crate is the one to depend on: it re-exports the
//! layers (`lie` → `kinematics` → `mechanics` → `dynamics` → `integrate`,
//! `scene`) and adds [`Simulation`]: a model with its initial state and run
//! settings, offering simulation, statics, modes, dynamics evaluations and
//! kinematics queries.
//!
//! A soft rod clamped horizontal and released under gravity for one second
//! with the recommended settings (the program of the repository's README;
//! the scene of `docs/theory.md` §8(h), whose tip at 1 s is known from a
//! DOP853 run at rtol 1e-12):
//!
//! ```
//! use softrod::prelude::*;
//!
//! let rubber = Material::builder().density(1000.0).young(1e7).poisson(0.5).build()?;
//! let arm = Rod::builder(0.5).pieces(8).circle(0.01).material(rubber)
//!     .strains([Strain::Ky, Strain::Qx, Strain::Qz]);
//! let model = Model::builder().rod(arm).gravity([0.0, 0.0, -9.81]).build()?;
//! let traj = Simulation::new(model).simulate(1.0)?;     // ESDIRK, rtol 1e-3, exact Jacobian
//! println!("tip at 1 s: {:?}", traj.tip_position(traj.len() - 1, 0));
//! # let tip = traj.tip_position(traj.len() - 1, 0);
//! # // The default tolerance keeps the tip within ~6e-5 m of the reference
//! # // over the second (docs/defaults.md); quadrature 4 against the
//! # // reference's 5 differs by < 1e-6 m.
//! # assert!((tip[0] - 0.391295819).abs() < 2e-4 && (tip[2] + 0.286765539).abs() < 2e-4);
//! # Ok::<(), softrod::Error>(())
//! ```
//!
//! Tighter tolerances converge to the reference (here rtol 1e-6 at 0.25 s):
//!
//! ```
//! use softrod::prelude::*;
//!
//! let material = Material::builder().density(1000.0).young(1e7).poisson(0.5).build()?;
//! let arm = Rod::builder(0.5).name("arm").pieces(8).circle(0.01).material(material)
//!     .strains([Strain::Ky, Strain::Qx, Strain::Qz]);
//! let model = Model::builder().rod(arm).gravity([0.0, 0.0, -9.81]).quadrature(5).build()?;
//! let mut sim = Simulation::new(model);
//! sim.set_settings(Settings::tolerances(1e-6, 1e-9))?;
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
//! Every run of [`Simulation::simulate_with`] watches what physics
//! guarantees: the energy balance `dE/dt = P_nc` (cables, loads, drag and
//! viscosity included; [`EnergyBalance`], reported in
//! [`RunSummary::energy`]), failing with [`Error::EnergyBalance`] beyond
//! [`Settings::energy_tolerance`] (default 0.1 of the energy in play) and
//! warning beyond a tenth of it; a positive stretch ([`Error::Stretch`]);
//! strains inside the model's validity (warnings). Before anything big is
//! allocated, tasks are checked against a memory budget ([`Limits`], 4 GiB
//! unless set with [`Simulation::set_limits`]; [`Error::TooLarge`]), a
//! setting rather than a reading of the machine's load.
//!
//! Conventions shared with the Python package:
//!
//! - **Time.** A [`Simulation`] keeps a clock for the prescribed joints
//!   (D59): [`Simulation::set_time`] sets it, and the evaluations that are
//!   functions of the configuration (poses, Jacobians, mass matrix,
//!   energies, gravity, closure residuals) read it; the equations of motion
//!   take their time first, `f(t, q, q̇)` (forward and inverse dynamics,
//!   bias force, drive forces, linearization, a step), and leave the clock
//!   alone. (Python has no clock: its kinematic queries take the keyword
//!   `t` instead.)
//! - **Durations.** [`Simulation::simulate`] and
//!   [`Simulation::simulate_with`] take the duration explicitly; a scene's
//!   `[run] duration` is in [`Settings::duration`], which front ends use
//!   when the user names none (the CLI, Python's `simulate` and
//!   `simulate_many` alike).
//! - **Names.** Velocities are `qdot` (`q̇`), as in the scene format and
//!   `trajectory.csv`; a rod is named by its name or its index
//!   ([`RodId`]).
//! - **Errors.** Each variant states its cause or returns it as its source,
//!   never both; [`report`] prints an error with each cause once.
//!
//! Where things are: [`simulation`](Simulation) (the front door, one
//! concern per file), [`record`] (what a run records at each output time
//! — a new output quantity or `trajectory.csv` column goes into
//! [`record::Record`] and [`record::Columns`]), [`study`] (work–precision
//! studies behind `softrod report`), [`limits`] (memory estimates),
//! [`control`] (inverse statics: cable tensions for targets,
//! [`Simulation::solve_actuation`]; docs/theory-control.md IS1–IS12),
//! [`Settings`] and the energy watch ([`EnergyBalance`]).
//!
//! Units are SI; twists and wrenches are 6-vectors, angular part first;
//! velocities and forces are in the body frame of the section, poses in the
//! world frame. The equations are in `docs/theory.md` of the repository,
//! whose labels (D1)… the documentation cites.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod control;
mod error;
pub mod limits;
pub mod record;
mod settings;
mod simulation;
pub mod study;
mod watch;

pub use control::{Actuation, ActuationOptions, Target};
pub use error::{Error, Result, report};
pub use limits::Limits;
pub use record::{Trajectory, TrajectoryRecorder};
pub use settings::{GENERALIZED_ALPHA_RHO_INF, Settings, output_times};
pub use simulation::{
    Equilibrium, Flow, Gradient, GradientMethod, GradientOptions, LossFn, LossTerm, ModalAnalysis,
    Observer, RodId, RunStatus, RunSummary, Sample, Simulation, Statics,
};
pub use softrod_integrate::Integrator;

pub use watch::EnergyBalance;

pub use softrod_dynamics as dynamics;
pub use softrod_integrate as integrate;
pub use softrod_kinematics as kinematics;
pub use softrod_lie as lie;
pub use softrod_mechanics as mechanics;
pub use softrod_scene as scene;

/// The names most programs need.
pub mod prelude {
    pub use crate::{Error, Settings, Simulation, Trajectory};
    pub use softrod_dynamics::{Attachment, BodySpec, Joint, JointKind, Model, Rod};
    pub use softrod_integrate::Integrator;
    pub use softrod_kinematics::{Basis, Frame, RodGeometry, Strain};
    pub use softrod_lie::{Pose, Vec3, Vec6};
    pub use softrod_mechanics::{Cable, Material, PointLoad, RodProperties, Section, Tension};
}

/// The README's examples, compiled and run as doctests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
