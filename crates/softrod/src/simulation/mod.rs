//! [`Simulation`]: a model, its initial state and its run settings, with
//! everything a user does with them, one concern per file: construction,
//! names and state here; [`kinematics`] (world poses, Jacobians),
//! [`dynamics`] (evaluations of the equations of motion), [`analysis`]
//! (statics, modes), [`checks`] (what a task is refused for before it
//! allocates) and [`run`] (time integration with an [`Observer`]).
//!
//! Time: a `Simulation` keeps a clock ([`Simulation::set_time`], 0 at
//! first) for the prescribed joints (D59) of the evaluations that are
//! functions of the configuration (poses, Jacobians, mass matrix, energies,
//! gravity, closure residuals); the equations of motion take their time as
//! the first argument, `f(t, q, q̇)` (forward and inverse dynamics, bias
//! force, drive forces, linearization, a step) and leave the clock alone.

mod actuation;
mod analysis;
mod checks;
mod dynamics;
mod gradient;
mod kinematics;
mod run;

pub use analysis::{Equilibrium, ModalAnalysis, Statics};
pub use gradient::{Gradient, GradientMethod, GradientOptions, LossFn, LossTerm};
pub use kinematics::RodId;
pub use run::{Flow, Observer, RunStatus, RunSummary, Sample};

use std::path::Path;

use nalgebra::DVector;
use softrod_dynamics::{Data, ElementKind, Model};
use softrod_integrate::RodSystem;
use softrod_kinematics::Strain;
use softrod_scene::{Scene, Warning};

use crate::error::{Error, Result};
use crate::limits::Limits;
use crate::record::{Trajectory, TrajectoryRecorder};
use crate::settings::Settings;

/// A model with its initial state and run settings: the front door of
/// softrod. Every evaluation reuses buffers held inside, so a `Simulation`
/// is `&mut` for calls and [`Clone`] for parallel runs.
///
/// Coordinates: `q` (strain coordinates, `n_dof`), `q̇`, `q̈` in the
/// model's order (rods in order, pieces base to tip, selected strains in
/// canonical order); SI units; poses in the world frame.
#[derive(Clone, Debug)]
pub struct Simulation {
    system: RodSystem,
    settings: Settings,
    q0: DVector<f64>,
    qd0: DVector<f64>,
    limits: Limits,
    /// The time \[s\] of the prescribed joints for the evaluations that take
    /// none ([`Self::set_time`]); the calls that take a `t` do not move it.
    time: f64,
    /// The scene's `[[load]]`s with `unknown = true` (IS13): what
    /// [`Self::scene_unknown_loads`] gives the inverse statics.
    unknown_loads: Vec<crate::control::UnknownLoad>,
    /// The scene's prescribed curves, saved when a target is first
    /// commanded ([`Self::command_prescribed`]); `None` before.
    scene_curves: Option<Vec<softrod_dynamics::Curve>>,
    /// The transitions in force (PT1), one per prescribed coordinate;
    /// empty: the scene's curves.
    transitions: Vec<crate::control::Transition>,
}

impl Simulation {
    /// A simulation of `model` from its rest shape, at rest, with the
    /// recommended settings.
    pub fn new(model: Model) -> Self {
        let n = model.n_dof();
        Self {
            system: RodSystem::new(model),
            settings: Settings::default(),
            q0: DVector::zeros(n),
            qd0: DVector::zeros(n),
            limits: Limits::default(),
            time: 0.0,
            unknown_loads: Vec::new(),
            scene_curves: None,
            transitions: Vec::new(),
        }
    }

    /// The simulation a validated scene describes: its model, `[initial]`
    /// state and `[run]` settings.
    pub fn from_scene(scene: &Scene) -> Result<Self> {
        let built = scene.build()?;
        let settings = Settings::from_run(&scene.run);
        settings.validate()?;
        let mut sim = Self::new(built.model);
        sim.settings = settings;
        if let Some(gib) = scene.run.memory_limit_gib {
            sim.limits.memory = (gib * (1u64 << 30) as f64).min(u64::MAX as f64) as u64;
        }
        sim.q0 = built.q0;
        sim.qd0 = built.qd0;
        sim.unknown_loads = scene
            .unknown_loads
            .iter()
            .map(|u| crate::control::UnknownLoad {
                rod: u.rod,
                s: u.s,
                min: u.max_force.map(|m| -m),
                max: u.max_force,
            })
            .collect();
        Ok(sim)
    }

    /// Reads, validates and builds the scene file at `path`; returns the
    /// simulation and the scene's warnings (suspicious but legal input).
    pub fn from_scene_file(path: impl AsRef<Path>) -> Result<(Self, Scene, Vec<Warning>)> {
        let (scene, warnings) = Scene::from_path(path.as_ref())?;
        Ok((Self::from_scene(&scene)?, scene, warnings))
    }

    /// As [`Simulation::from_scene_file`] for scene text; `name` stands for
    /// the file in messages.
    pub fn from_toml(text: &str, name: &str) -> Result<(Self, Scene, Vec<Warning>)> {
        let (scene, warnings) = Scene::from_str(text, name)?;
        Ok((Self::from_scene(&scene)?, scene, warnings))
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.system.model
    }

    /// A name for every coordinate of `q`, in its order: `"ROD.pN.STRAIN"`
    /// (`"arm.p0.ky"`: rod `arm`, piece 0 from the base, bending about local
    /// y), the strain as the scene's `strains` names it; a piece with a
    /// general basis matrix names its columns `b0`, `b1`, …. A joint's
    /// coordinates come first in its element's: `"ELEMENT.joint.C"` with `C`
    /// `theta` (revolute), `d` (prismatic), `theta0`, `theta1` (universal),
    /// `rx`, `ry`, `rz` (spherical; free adds `x`, `y`, `z`). The same names
    /// serve `q̇` (and the `q`/`qdot` columns of `trajectory.csv`).
    pub fn q_names(&self) -> Vec<String> {
        let model = self.model();
        let mut names = Vec::with_capacity(model.n_dof());
        for e in model.elements() {
            if !e.joint_dofs.is_empty() {
                names.extend(joint_names(e));
            }
            if let ElementKind::Rod(r) = e.kind {
                let rm = &model.rods()[r];
                for (n, piece) in rm.spec.geometry.pieces().iter().enumerate() {
                    match piece.basis.selection() {
                        Some(sel) => {
                            names.extend(sel.iter().map(|&i| {
                                format!("{}.p{n}.{}", rm.spec.name, Strain::ALL[i].name())
                            }))
                        }
                        None => names.extend(
                            (0..piece.basis.dof()).map(|j| format!("{}.p{n}.b{j}", rm.spec.name)),
                        ),
                    }
                }
            }
        }
        names
    }

    /// A name for every prescribed joint coordinate (D59), in the order of
    /// [`Data::prescribed_q`] and [`Data::prescribed_force`]: as in
    /// [`Self::q_names`], `"ELEMENT.joint.C"`.
    pub fn prescribed_names(&self) -> Vec<String> {
        self.model()
            .elements()
            .iter()
            .filter(|e| !e.prescribed_dofs.is_empty())
            .flat_map(joint_names)
            .collect()
    }

    /// Number of generalized coordinates.
    pub fn n_dof(&self) -> usize {
        self.system.model.n_dof()
    }

    /// The run settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Replaces the run settings (checked).
    pub fn set_settings(&mut self, settings: Settings) -> Result<()> {
        settings.validate()?;
        self.settings = settings;
        Ok(())
    }

    /// The memory limit the tasks are checked against before they allocate
    /// (default: [`Limits::default`], a fixed documented budget: what the
    /// checks refuse does not depend on the machine's load).
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Replaces the memory limit.
    pub fn set_limits(&mut self, limits: Limits) {
        self.limits = limits;
    }

    /// Initial coordinates and velocities.
    pub fn initial_state(&self) -> (&DVector<f64>, &DVector<f64>) {
        (&self.q0, &self.qd0)
    }

    /// Sets the initial state (each of length `n_dof`, finite).
    pub fn set_initial_state(&mut self, q: &[f64], qdot: &[f64]) -> Result<()> {
        self.check("q", q)?;
        self.check("qdot", qdot)?;
        self.q0 = DVector::from_column_slice(q);
        self.qd0 = DVector::from_column_slice(qdot);
        Ok(())
    }

    fn check(&self, what: &'static str, v: &[f64]) -> Result<()> {
        let n = self.n_dof();
        if v.len() != n {
            return Err(Error::SizeMismatch {
                what,
                got: v.len(),
                expected: n,
            });
        }
        Ok(())
    }

    /// Sets the time \[s\] of the prescribed joints' motion (D59) for the
    /// evaluations that take none: [`Self::pose`], [`Self::tip_pose`],
    /// [`Self::rod_to_world`], [`Self::jacobian`], [`Self::body_poses`],
    /// [`Self::mass_matrix`], [`Self::energies`], [`Self::gravity_force`],
    /// [`Self::closure_residuals`]. It starts at 0, and only this call moves
    /// it: the evaluations that take a `t` (dynamics, runs) leave it alone.
    /// Irrelevant without prescribed joints.
    pub fn set_time(&mut self, t: f64) {
        self.time = t;
    }

    /// The time of [`Self::set_time`] \[s\].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The system's buffers with the prescribed joints at [`Self::time`].
    fn at_time(&mut self) -> (&Model, &mut Data) {
        let s = &mut self.system;
        s.model.set_time(&mut s.data, self.time);
        (&s.model, &mut s.data)
    }

    /// Number of cables: the length of the inputs `u`.
    pub fn n_cables(&self) -> usize {
        self.model().n_cables()
    }

    /// Sets cable-tension inputs `u` (one per cable in model order, \[N\],
    /// ≥ 0) that replace the cables' schedules in every evaluation and run
    /// of this simulation; `None` restores the schedules.
    pub fn set_cable_tensions(&mut self, u: Option<&[f64]>) -> Result<()> {
        let s = &mut self.system;
        Ok(s.data.set_cable_tensions(&s.model, u)?)
    }

    /// The inputs set by [`Simulation::set_cable_tensions`], if any.
    pub fn cable_tensions(&self) -> Option<&[f64]> {
        self.system.data.cable_tensions()
    }

    /// Sets the joint actuators' forces `f` \[N or N·m\] (one per actuated
    /// joint coordinate, `Model::n_joint_inputs` order; docs/theory-control.md
    /// IS14) that replace the actuators' schedules in every evaluation and
    /// run of this simulation; `None` restores the schedules. Errors: the
    /// wrong length, a value that is not finite.
    pub fn set_joint_forces(&mut self, f: Option<&[f64]>) -> Result<()> {
        let s = &mut self.system;
        Ok(s.data.set_joint_forces(&s.model, f)?)
    }

    /// The inputs set by [`Simulation::set_joint_forces`], if any.
    pub fn joint_forces(&self) -> Option<&[f64]> {
        self.system.data.joint_forces()
    }

    /// Names of the actuated joint coordinates (the entries of
    /// [`Self::set_joint_forces`]' `f`, `Model::n_joint_inputs` order), as
    /// in [`Self::q_names`]: `"ELEMENT.joint.C"`.
    pub fn joint_input_names(&self) -> Vec<String> {
        self.model()
            .elements()
            .iter()
            .filter(|e| e.attachment.joint.actuated_dof() > 0)
            .flat_map(joint_names)
            .collect()
    }

    /// The target bounds `[lo, hi]` of each prescribed coordinate (rad or
    /// m; the scene's `joint.prescribed.bounds`), `None` where the scene
    /// gives none; [`Self::prescribed_names`] order.
    pub fn prescribed_bounds(&self) -> Vec<Option<[f64; 2]>> {
        let m = self.model();
        (0..m.n_prescribed())
            .map(|i| m.prescribed_bounds(i))
            .collect()
    }

    /// Commands the prescribed joints to `targets` (one per prescribed
    /// coordinate, [`Self::prescribed_names`] order, rad or m) over the
    /// period `[t, t + dt]`: each coordinate then follows the cubic
    /// transition from its position and rate at `t` to its target, reached
    /// at rest at `t + dt` and held after (docs/envs.md;
    /// [`crate::control::targets`] PT1). Every evaluation and run of this
    /// simulation then uses these curves, until the next command or
    /// [`Self::reset_prescribed`].
    ///
    /// Errors (input): no prescribed joint, the wrong count, a target not
    /// finite or outside its joint's `prescribed.bounds` (named by
    /// coordinate), `dt ≤ 0`.
    pub fn command_prescribed(&mut self, t: f64, dt: f64, targets: &[f64]) -> Result<()> {
        use crate::control::targets;
        let names = self.prescribed_names();
        targets::check_prescribed_targets(self.model(), &names, "prescribed_targets", targets)?;
        if self.scene_curves.is_none() {
            self.scene_curves = Some(self.scene_prescribed_curves());
        }
        let mut out = std::mem::take(&mut self.transitions);
        let r = targets::command_prescribed_targets(
            &mut self.system.model,
            &names,
            t,
            dt,
            targets,
            &mut out,
        );
        self.transitions = out;
        r
    }

    /// Holds the prescribed joints at `values` (one per prescribed
    /// coordinate, checked as [`Self::command_prescribed`]'s targets) at
    /// rest at every time, until the next command or
    /// [`Self::reset_prescribed`]: for statics and poses with the drive
    /// elsewhere than the scene puts it (a task's target draw). Recorded
    /// as transitions from and to the value, at rest.
    pub fn hold_prescribed(&mut self, values: &[f64]) -> Result<()> {
        let names = self.prescribed_names();
        crate::control::targets::check_prescribed_targets(self.model(), &names, "values", values)?;
        let held: Vec<crate::control::Transition> = values
            .iter()
            .map(|&x| crate::control::Transition {
                t0: 0.0,
                t1: 1.0,
                x0: x,
                v0: 0.0,
                x1: x,
            })
            .collect();
        self.set_prescribed_transitions(&held)
    }

    /// The transitions in force (one per prescribed coordinate), empty when
    /// the scene's curves are: what [`Self::set_prescribed_transitions`]
    /// puts back (a pickle keeps them).
    pub fn prescribed_transitions(&self) -> &[crate::control::Transition] {
        &self.transitions
    }

    /// Puts `transitions` (one per prescribed coordinate, from
    /// [`Self::prescribed_transitions`]) in force; empty: the scene's
    /// curves ([`Self::reset_prescribed`]).
    pub fn set_prescribed_transitions(
        &mut self,
        transitions: &[crate::control::Transition],
    ) -> Result<()> {
        use crate::control::targets;
        let np = self.model().n_prescribed();
        if transitions.is_empty() {
            self.reset_prescribed();
            return Ok(());
        }
        if transitions.len() != np {
            return Err(Error::SizeMismatch {
                what: "prescribed transitions",
                got: transitions.len(),
                expected: np,
            });
        }
        if self.scene_curves.is_none() {
            self.scene_curves = Some(self.scene_prescribed_curves());
        }
        let names = self.prescribed_names();
        targets::install(&mut self.system.model, &names, transitions)?;
        self.transitions = transitions.to_vec();
        Ok(())
    }

    /// Puts the scene's prescribed curves back in force (after
    /// [`Self::command_prescribed`]): an episode that starts over does this.
    pub fn reset_prescribed(&mut self) {
        if let Some(curves) = self.scene_curves.take() {
            for (i, c) in curves.into_iter().enumerate() {
                self.system
                    .model
                    .set_prescribed_curve(i, c)
                    .expect("the scene's own curves");
            }
        }
        self.transitions.clear();
    }

    /// The scene's prescribed curves (those in force before any
    /// [`Self::command_prescribed`]), one per prescribed coordinate.
    pub fn scene_prescribed_curves(&self) -> Vec<softrod_dynamics::Curve> {
        match &self.scene_curves {
            Some(c) => c.clone(),
            None => {
                let m = self.model();
                (0..m.n_prescribed())
                    .map(|i| m.prescribed_curve(i).expect("i < n_prescribed").clone())
                    .collect()
            }
        }
    }

    /// The point forces the scene marks unknown (`[[load]] unknown = true`,
    /// docs/theory-control.md IS13), with their bounds `|f_k| ≤ max_force`,
    /// in file order: what `softrod inverse` solves for beside the tensions
    /// and actuated joints' forces (pass them as
    /// [`crate::control::ActuationOptions::unknown_loads`]). Empty for a
    /// simulation not built from a scene.
    pub fn scene_unknown_loads(&self) -> &[crate::control::UnknownLoad] {
        &self.unknown_loads
    }

    /// Integrates `duration` seconds from the initial state with the run
    /// settings and keeps the samples (every `output_every`).
    pub fn simulate(&mut self, duration: f64) -> Result<Trajectory> {
        let per_sample = Trajectory::bytes_per_sample(
            &crate::record::Columns::of(self.model()),
            self.model().rods().len(),
        );
        if duration.is_finite() && duration > 0.0 {
            self.check_samples(duration, per_sample)?;
        }
        let mut keep = TrajectoryRecorder::new(self.model());
        let summary = self.simulate_with(duration, &mut keep)?;
        let warning = keep.penetration_warning(self.model());
        let mut traj = keep.into_trajectory();
        traj.summary = summary;
        traj.summary.warnings.extend(warning);
        Ok(traj)
    }
}

/// The names of a joint's coordinates (see [`Simulation::q_names`]).
pub(crate) fn joint_names(e: &softrod_dynamics::ElementInfo) -> Vec<String> {
    use softrod_dynamics::JointKind;
    let parts: &[&str] = match e.attachment.joint.kind {
        JointKind::Fixed => &[],
        JointKind::Revolute { .. } => &["theta"],
        JointKind::Prismatic { .. } => &["d"],
        JointKind::Universal { .. } => &["theta0", "theta1"],
        JointKind::Spherical => &["rx", "ry", "rz"],
        JointKind::Free => &["rx", "ry", "rz", "x", "y", "z"],
    };
    parts
        .iter()
        .map(|c| format!("{}.joint.{c}", e.name))
        .collect()
}
