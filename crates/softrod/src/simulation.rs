//! [`Simulation`]: a model, its initial state and its run settings, with
//! everything a user does with them.

use std::path::Path;

use nalgebra::{DMatrix, DVector, Matrix6xX};
use softrod_dynamics::{
    Data, ElementKind, Energies, FdDerivatives, Linearization, Model, Modes, StaticsOptions,
    StaticsResult, actuation_matrix, bias_force, coriolis_matrix, damping_matrix, energies,
    forward_dynamics, generalized_gravity, inverse_dynamics, linearize, mass_matrix, modes,
    statics, stiffness_matrix,
};
use softrod_integrate::{Control, Hooks, RodSystem, Stats, StepInfo, integrate_second_order};
use softrod_kinematics::{Frame, RodKinematics, Strain};
use softrod_lie::Pose;
use softrod_scene::{Scene, Warning};

use crate::error::{Error, Result};
use crate::limits::{
    Limits, MODES_DENSE_MATRICES, STATICS_DENSE_MATRICES, check_memory, dense_bytes,
    dense_matrices_of, output_sample_count,
};
use crate::settings::{Settings, output_times};
use crate::watch::{EnergyBalance, Watch};

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
}

/// Which equilibrium [`Simulation::modes`] linearized about.
#[derive(Clone, Debug, PartialEq)]
pub enum Equilibrium {
    /// The rest shape `q = 0` (the model has no static loads).
    Rest,
    /// The static equilibrium under the model's static loads.
    Statics(DVector<f64>),
}

/// Natural modes and the equilibrium they are about.
#[derive(Clone, Debug)]
pub struct ModalAnalysis {
    /// Frequencies and shapes (see [`Modes`]).
    pub modes: Modes,
    /// The equilibrium.
    pub equilibrium: Equilibrium,
}

/// What an [`Observer`] sees at each output time.
pub struct Sample<'a> {
    /// Time \[s\].
    pub t: f64,
    /// Coordinates (n_dof).
    pub q: &'a [f64],
    /// Velocities (n_dof).
    pub qd: &'a [f64],
    /// The model, for derived quantities.
    pub model: &'a Model,
    /// Its buffers, for evaluations at this sample (energies, …).
    pub data: &'a mut Data,
}

/// Whether a run goes on after a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flow {
    /// Go on.
    Continue,
    /// End the run here ([`RunStatus::Stopped`]).
    Stop,
}

/// Receives a run's samples as the integration produces them (streaming:
/// nothing is kept unless the observer keeps it).
pub trait Observer {
    /// Called at `t = 0` and at every output time, in order. An error ends
    /// the run with [`Error::Output`].
    fn sample(&mut self, sample: Sample<'_>) -> Result<Flow, String>;

    /// Called after each accepted step (e.g. for a progress bar).
    fn step(&mut self, _t: f64, _stats: &Stats) {}

    /// A controller in the loop: called after each accepted step with the
    /// state there; write new cable tensions into `u` (one per cable, model
    /// order, \[N\], ≥ 0; it holds the current ones) and return `true` to
    /// apply them from this time on (zero-order hold; the integrator then
    /// discards its cached derivatives, which costs one extra evaluation of
    /// the dynamics per change). The default never changes them.
    fn inputs(&mut self, _t: f64, _q: &[f64], _qd: &[f64], _u: &mut [f64]) -> bool {
        false
    }
}

/// How a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunStatus {
    /// The full duration was simulated.
    Completed,
    /// The observer stopped it.
    Stopped,
}

/// Summary of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    /// How it ended.
    pub status: RunStatus,
    /// Time reached \[s\].
    pub t_final: f64,
    /// The integrator's work counters.
    pub stats: Stats,
    /// Samples delivered to the observer.
    pub samples: usize,
    /// The energy balance measured along the run ([`EnergyBalance`];
    /// `None` for [`Simulation::step`], which does not watch).
    pub energy: Option<EnergyBalance>,
    /// What the watch found suspicious but not wrong: an energy drift
    /// beyond a tenth of `energy_tolerance`, strains or curvatures beyond
    /// the model's validity.
    pub warnings: Vec<String>,
}

impl Default for RunSummary {
    fn default() -> Self {
        Self {
            status: RunStatus::Completed,
            t_final: 0.0,
            stats: Stats::default(),
            samples: 0,
            energy: None,
            warnings: Vec::new(),
        }
    }
}

/// A run kept in memory: samples at the output times.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// Output times \[s\].
    pub t: Vec<f64>,
    /// Coordinates at each time.
    pub q: Vec<DVector<f64>>,
    /// Velocities at each time.
    pub qd: Vec<DVector<f64>>,
    /// Tip pose of every rod (world frame) at each time: `tips[i][rod]`.
    pub tips: Vec<Vec<Pose>>,
    /// Energies at each time.
    pub energies: Vec<Energies>,
    /// How the run ended.
    pub summary: RunSummary,
}

impl Trajectory {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Tip position of rod `rod` at sample `i` [m, world frame].
    pub fn tip_position(&self, i: usize, rod: usize) -> [f64; 3] {
        let p = self.tips[i][rod].translation;
        [p[0], p[1], p[2]]
    }
}

/// Keeps every sample of a run as a [`Trajectory`]: the state, the
/// energies and every rod's tip pose in the world frame (through joints and
/// parents on articulated models). The observer behind
/// [`Simulation::simulate`]; front ends that drive the integrator
/// themselves (a controller in the loop) record with [`Self::record`].
pub struct TrajectoryRecorder {
    traj: Trajectory,
    kin: Vec<RodKinematics>,
}

impl TrajectoryRecorder {
    /// An empty record for runs of `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            traj: Trajectory {
                t: Vec::new(),
                q: Vec::new(),
                qd: Vec::new(),
                tips: Vec::new(),
                energies: Vec::new(),
                summary: RunSummary::default(),
            },
            kin: model
                .rods()
                .iter()
                .map(|r| RodKinematics::new(&r.spec.rod))
                .collect(),
        }
    }

    /// Records the state `(q, q̇)` at `t`; `data` must have the prescribed
    /// joints at `t` ([`Model::set_time`]).
    pub fn record(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> std::result::Result<(), String> {
        let e = energies(model, data, q, qd).map_err(|e| e.to_string())?;
        let mut tips = Vec::with_capacity(self.kin.len());
        let articulated = model.is_articulated();
        if articulated {
            softrod_dynamics::frames(model, data, q).map_err(|e| e.to_string())?;
        }
        for (i, (k, r)) in self.kin.iter_mut().zip(model.rods()).enumerate() {
            k.update(&r.spec.rod, &q[r.dofs()], None, None)
                .map_err(|e| e.to_string())?;
            tips.push(if articulated {
                data.rod_to_world(model, i).compose(k.tip_pose())
            } else {
                *k.tip_pose()
            });
        }
        let tr = &mut self.traj;
        tr.t.push(t);
        tr.q.push(DVector::from_column_slice(q));
        tr.qd.push(DVector::from_column_slice(qd));
        tr.tips.push(tips);
        tr.energies.push(e);
        tr.summary.samples += 1;
        Ok(())
    }

    /// The record so far (its summary is the caller's to fill).
    pub fn trajectory_mut(&mut self) -> &mut Trajectory {
        &mut self.traj
    }

    /// The record.
    pub fn into_trajectory(self) -> Trajectory {
        self.traj
    }
}

impl Observer for TrajectoryRecorder {
    fn sample(&mut self, s: Sample<'_>) -> std::result::Result<Flow, String> {
        self.record(s.model, s.data, s.t, s.q, s.qd)?;
        Ok(Flow::Continue)
    }
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
            limits: Limits::of_machine(),
            time: 0.0,
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
        sim.q0 = built.q0;
        sim.qd0 = built.qd0;
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
                for (n, piece) in rm.spec.rod.pieces().iter().enumerate() {
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
    /// (default: [`Limits::of_machine`]).
    pub fn limits(&self) -> &Limits {
        &self.limits
    }

    /// Replaces the memory limit.
    pub fn set_limits(&mut self, limits: Limits) {
        self.limits = limits;
    }

    /// Refuses `task` if its `count` dense `n_dof × n_dof` matrices exceed
    /// the memory limit, naming the `pieces` of the rod with the most DoFs.
    fn check_dense(&self, task: &str, count: u64) -> Result<()> {
        let n = self.n_dof();
        let estimate = dense_bytes(count, n);
        if estimate <= self.limits.memory {
            return Ok(());
        }
        let (i, r) = self
            .model()
            .rods()
            .iter()
            .enumerate()
            .max_by_key(|(_, r)| r.n_dof())
            .expect("a model with DoFs has rods");
        check_memory(
            format!("rod[{i}].pieces"),
            format!(
                "{task}: {count} dense {n}×{n} matrices (n_dof = {n}; rod {:?} has {} pieces, {} DoF)",
                r.spec.name,
                r.spec.rod.n_pieces(),
                r.n_dof()
            ),
            estimate,
            &self.limits,
        )
    }

    /// Refuses a run whose output samples (`bytes_per_sample` each) exceed
    /// the memory limit, naming `run.output_every`.
    fn check_samples(&self, duration: f64, bytes_per_sample: u64) -> Result<()> {
        let every = self.settings.output_spacing(duration);
        let estimate = output_sample_count(duration, every)
            .map_or(u64::MAX, |n| n.saturating_mul(bytes_per_sample));
        check_memory(
            "run.output_every".into(),
            format!(
                "{duration} s sampled every {every} s: {:.3e} samples of {bytes_per_sample} bytes",
                duration / every
            ),
            estimate,
            &self.limits,
        )
    }

    /// Initial coordinates and velocities.
    pub fn initial_state(&self) -> (&DVector<f64>, &DVector<f64>) {
        (&self.q0, &self.qd0)
    }

    /// Sets the initial state (each of length `n_dof`, finite).
    pub fn set_initial_state(&mut self, q: &[f64], qd: &[f64]) -> Result<()> {
        self.check("q", q)?;
        self.check("qdot", qd)?;
        self.q0 = DVector::from_column_slice(q);
        self.qd0 = DVector::from_column_slice(qd);
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

    fn rod_index(&self, rod: &str) -> Result<usize> {
        self.model()
            .rods()
            .iter()
            .position(|r| r.spec.name == rod)
            .ok_or_else(|| Error::UnknownRod(format!("'{rod}'")))
    }

    fn kinematics(&self, rod: &str, q: &[f64]) -> Result<(usize, RodKinematics)> {
        self.check("q", q)?;
        let i = self.rod_index(rod)?;
        let r = &self.model().rods()[i];
        let mut k = RodKinematics::new(&r.spec.rod);
        k.update(&r.spec.rod, &q[r.dofs()], None, None)?;
        Ok((i, k))
    }

    /// The map from rod `i`'s kinematic poses to the world at `q`: the
    /// identity for a rod clamped to the world, else through its parents'
    /// poses (allocates a `Data` for a model with joints or parents).
    fn to_world(&self, i: usize, q: &[f64]) -> Result<Pose> {
        let model = self.model();
        if !model.is_articulated() {
            return Ok(Pose::identity());
        }
        let mut data = Data::new(model);
        model.set_time(&mut data, self.time);
        softrod_dynamics::frames(model, &mut data, q)?;
        Ok(data.rod_to_world(model, i))
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

    /// The map from rod `rod`'s kinematic poses (`softrod_kinematics`, which
    /// start at its `Rod::base`) to the world at `q`: the identity for a
    /// rod clamped to the world, else through its joint and parents (D51;
    /// prescribed joints at the time of [`Self::set_time`]).
    pub fn rod_to_world(&self, rod: &str, q: &[f64]) -> Result<Pose> {
        self.check("q", q)?;
        let i = self.rod_index(rod)?;
        self.to_world(i, q)
    }

    /// World pose of rod `rod` at abscissa `s` \[m\] for coordinates `q` (D7).
    pub fn pose(&self, rod: &str, s: f64, q: &[f64]) -> Result<Pose> {
        let (i, k) = self.kinematics(rod, q)?;
        let local = k.pose_at(&self.model().rods()[i].spec.rod, s)?;
        Ok(self.to_world(i, q)?.compose(&local))
    }

    /// Tip pose of rod `rod` for coordinates `q` (world frame).
    pub fn tip_pose(&self, rod: &str, q: &[f64]) -> Result<Pose> {
        let (i, k) = self.kinematics(rod, q)?;
        Ok(self.to_world(i, q)?.compose(k.tip_pose()))
    }

    /// World poses of the rigid bodies' frames for coordinates `q` (one per
    /// body, in the order of [`Model::bodies`]; empty without bodies).
    pub fn body_poses(&self, q: &[f64]) -> Result<Vec<Pose>> {
        self.check("q", q)?;
        let model = self.model();
        if model.bodies().is_empty() {
            return Ok(Vec::new());
        }
        let mut data = Data::new(model);
        model.set_time(&mut data, self.time);
        softrod_dynamics::frames(model, &mut data, q)?;
        Ok(data.body_poses)
    }

    /// Geometric Jacobian `J(s)` (6 × n_dof) of rod `rod` at `s` in `frame`:
    /// the twist of the section is `J q̇` (D11). On a model of clamped rods
    /// the columns of other rods are 0; on an articulated one every
    /// coordinate that moves the section has its column — its joint's and
    /// its ancestors' too (`softrod_dynamics::section_jacobian`; prescribed
    /// joints at the time of [`Self::set_time`]).
    pub fn jacobian(&self, rod: &str, s: f64, q: &[f64], frame: Frame) -> Result<Matrix6xX<f64>> {
        let model = self.model();
        if model.is_articulated() {
            self.check("q", q)?;
            let i = self.rod_index(rod)?;
            let mut data = Data::new(model);
            model.set_time(&mut data, self.time);
            let (g, spatial) = softrod_dynamics::section_jacobian(model, &mut data, q, i, s)?;
            return Ok(match frame {
                Frame::Spatial => spatial,
                Frame::Body => g.ad_inv().to_mat6() * spatial,
                Frame::Mixed => {
                    // (R ω, R v) of the body twist.
                    let mut mixed = g.ad_inv().to_mat6() * spatial;
                    for c in 0..mixed.ncols() {
                        let w = g.rotation * mixed.fixed_view::<3, 1>(0, c);
                        let v = g.rotation * mixed.fixed_view::<3, 1>(3, c);
                        mixed.fixed_view_mut::<3, 1>(0, c).copy_from(&w);
                        mixed.fixed_view_mut::<3, 1>(3, c).copy_from(&v);
                    }
                    mixed
                }
            });
        }
        let (i, k) = self.kinematics(rod, q)?;
        let r = &self.model().rods()[i];
        let mut local = Matrix6xX::zeros(r.n_dof());
        k.jacobian_at(&r.spec.rod, s, frame, &mut local)?;
        let mut j = Matrix6xX::zeros(self.n_dof());
        j.columns_mut(r.dof_offset, r.n_dof()).copy_from(&local);
        Ok(j)
    }

    /// Forward dynamics `q̈(t, q, q̇)` under actuator force `tau` (n_dof,
    /// `None`: 0) by the O(N) articulated recursion (D23–D27).
    pub fn forward_dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        tau: Option<&[f64]>,
    ) -> Result<DVector<f64>> {
        let s = &mut self.system;
        Ok(forward_dynamics(&s.model, &mut s.data, t, q, qd, tau)?.clone())
    }

    /// The generalized forces the prescribed joints' drives apply (D60;
    /// N·m or N, in the order of [`Self::prescribed_names`]) at
    /// `(t, q, q̇)` under actuator force `tau`, from the forward dynamics;
    /// empty without prescribed joints.
    pub fn prescribed_forces(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        tau: Option<&[f64]>,
    ) -> Result<DVector<f64>> {
        let s = &mut self.system;
        forward_dynamics(&s.model, &mut s.data, t, q, qd, tau)?;
        Ok(s.data.prescribed_force.clone())
    }

    /// The closures' names and residuals at `q` (one per `[[closure]]`, in
    /// order): `max(‖d‖, ℓ‖r‖)` \[m\], the misfit of the held frames
    /// (docs/theory.md D66); empty without closures.
    pub fn closure_residuals(&mut self, q: &[f64]) -> Result<Vec<(String, f64)>> {
        self.check("q", q)?;
        let (model, data) = self.at_time();
        if !model.has_closures() {
            return Ok(Vec::new());
        }
        let r = softrod_dynamics::closure_residuals(model, data, q)?;
        Ok(model.closures().map(|c| c.name.clone()).zip(r).collect())
    }

    /// Inverse dynamics: the actuator force `τ_act` that gives `q̈` at
    /// `(t, q, q̇)` (D17–D18).
    pub fn inverse_dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
    ) -> Result<DVector<f64>> {
        let s = &mut self.system;
        Ok(inverse_dynamics(&s.model, &mut s.data, t, q, qd, qdd)?.clone())
    }

    /// Mass matrix `M(q)` (n_dof × n_dof, symmetric positive definite; D19–D20).
    pub fn mass_matrix(&mut self, q: &[f64]) -> Result<DMatrix<f64>> {
        let (model, data) = self.at_time();
        Ok(mass_matrix(model, data, q)?.clone())
    }

    /// Kinetic, elastic and gravitational energy at `(q, q̇)` \[J\]; with
    /// prescribed joints the kinetic energy includes their motion at
    /// [`Self::time`] (it is not `½q̇ᵀMq̇` then).
    pub fn energies(&mut self, q: &[f64], qd: &[f64]) -> Result<Energies> {
        let (model, data) = self.at_time();
        Ok(energies(model, data, q, qd)?)
    }

    /// Bias force `b(q, q̇) = C q̇ + G + τ_e + D q̇ − τ_c − Q_ext` at time `t`
    /// (n_dof): `M q̈ + b = τ_act` (D21–D22).
    pub fn bias_force(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<DVector<f64>> {
        let s = &mut self.system;
        Ok(bias_force(&s.model, &mut s.data, t, q, qd)?.clone())
    }

    /// Coriolis matrix `C(q, q̇)` (n_dof × n_dof, D21), with `Ṁ − 2C`
    /// skew-symmetric.
    pub fn coriolis_matrix(&self, q: &[f64], qd: &[f64]) -> Result<DMatrix<f64>> {
        Ok(coriolis_matrix(self.model(), q, qd)?)
    }

    /// Generalized gravity `G(q) = ∂V_g/∂q` (n_dof, D22).
    pub fn gravity_force(&mut self, q: &[f64]) -> Result<DVector<f64>> {
        let (model, data) = self.at_time();
        Ok(generalized_gravity(model, data, q)?)
    }

    /// Stiffness matrix `K` (n_dof × n_dof, block-diagonal per piece, D13).
    pub fn stiffness_matrix(&self) -> DMatrix<f64> {
        stiffness_matrix(self.model())
    }

    /// Damping matrix `D` (n_dof × n_dof, block-diagonal per piece, D13).
    pub fn damping_matrix(&self) -> DMatrix<f64> {
        damping_matrix(self.model())
    }

    /// Actuation matrix `∂τ_c/∂u` at `q` (n_dof × n_cables): the
    /// generalized force of each cable per newton of tension (D15).
    pub fn actuation_matrix(&self, q: &[f64]) -> Result<DMatrix<f64>> {
        Ok(actuation_matrix(self.model(), q)?)
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

    /// Linearization `ẋ ≈ f(x₀, u₀) + A (x − x₀) + B (u − u₀)` of the
    /// dynamics about `(q, q̇)` at `t`, `x = (q, q̇)` (2·n_dof), `u` the cable
    /// tensions (the inputs, or the schedules at `t`), from the analytic
    /// derivatives (D30–D49): what LQR, MPC and trajectory optimization need.
    pub fn linearize(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<Linearization> {
        let s = &mut self.system;
        let mut work = FdDerivatives::new(&s.model);
        Ok(linearize(&s.model, &mut s.data, &mut work, t, q, qd, None)?)
    }

    /// Whether the rest shape `q = 0` is not an equilibrium at `t = 0`: the
    /// static force there ([`softrod_dynamics::static_force`]: gravity,
    /// loads on rods and bodies, cables, stress-free strains other than the
    /// rest strain, joint springs off their rest) is not zero.
    pub fn has_static_loads(&self) -> bool {
        let m = self.model();
        let mut data = Data::new(m);
        let z = vec![0.0; m.n_dof()];
        softrod_dynamics::static_force(m, &mut data, 0.0, &z)
            .map_or(true, |f| f.iter().any(|v| *v != 0.0))
    }

    /// Static equilibrium under every static term at `t = 0`, from the
    /// initial `q` (Newton with line search and load continuation).
    pub fn statics(&mut self) -> Result<StaticsResult> {
        self.check_statics()?;
        let s = &mut self.system;
        Ok(statics(
            &s.model,
            &mut s.data,
            self.q0.as_slice(),
            &StaticsOptions::default(),
        )?)
    }

    /// Undamped natural modes about the static equilibrium (the rest shape
    /// when the model has no static loads).
    pub fn modes(&mut self) -> Result<ModalAnalysis> {
        self.check_dense("modes", STATICS_DENSE_MATRICES + MODES_DENSE_MATRICES)?;
        let equilibrium = if self.has_static_loads() {
            Equilibrium::Statics(self.statics()?.q)
        } else {
            Equilibrium::Rest
        };
        let q = match &equilibrium {
            Equilibrium::Rest => DVector::zeros(self.n_dof()),
            Equilibrium::Statics(q) => q.clone(),
        };
        let modes = self.modes_about(q.as_slice())?;
        Ok(ModalAnalysis { modes, equilibrium })
    }

    /// Undamped natural modes of the model linearized about `q` (which
    /// should be an equilibrium; an unstable one shows negative `ω`).
    pub fn modes_about(&mut self, q: &[f64]) -> Result<Modes> {
        self.check("q", q)?;
        self.check_dense("modes", MODES_DENSE_MATRICES)?;
        let s = &mut self.system;
        Ok(modes(&s.model, &mut s.data, q, 0.0)?)
    }

    /// Integrates `duration` seconds from the initial state with the run
    /// settings and keeps the samples (every `output_every`).
    pub fn simulate(&mut self, duration: f64) -> Result<Trajectory> {
        let rods = self.model().rods().len();
        let per_sample = 8
            + 2 * (std::mem::size_of::<DVector<f64>>() + 8 * self.n_dof())
            + std::mem::size_of::<Vec<Pose>>()
            + rods * std::mem::size_of::<Pose>()
            + std::mem::size_of::<Energies>();
        if duration.is_finite() && duration > 0.0 {
            self.check_samples(duration, per_sample as u64)?;
        }
        let mut keep = TrajectoryRecorder::new(self.model());
        let summary = self.simulate_with(duration, &mut keep)?;
        let mut traj = keep.into_trajectory();
        traj.summary = summary;
        Ok(traj)
    }

    /// The checks a run of `duration` seconds passes before it starts: the
    /// settings, the output samples and the integrator's dense matrices
    /// against the machine's memory ([`Error::TooLarge`], naming the key).
    /// `softrod check` calls it, so that it rejects what `softrod run`
    /// would.
    pub fn check_run(&self, duration: f64) -> Result<()> {
        if !(duration.is_finite() && duration > 0.0) {
            return Err(Error::InvalidSetting {
                key: "duration",
                message: format!("must be positive and finite, got {duration}"),
            });
        }
        self.settings.validate()?;
        // The output times are kept (8 bytes each).
        self.check_samples(duration, 8)?;
        let (method, _) = self.settings.method_and_options(duration)?;
        self.check_dense(
            &format!("the {} integrator", self.settings.integrator.name()),
            dense_matrices_of(method),
        )
    }

    /// The check [`Simulation::statics`] passes before it starts: its dense
    /// matrices against the machine's memory ([`Error::TooLarge`]).
    pub fn check_statics(&self) -> Result<()> {
        self.check_dense("statics", STATICS_DENSE_MATRICES)
    }

    /// Integrates `duration` seconds from the initial state, handing each
    /// sample to `observer` as it is produced (the integrator's dense output
    /// at the output times; nothing is kept here).
    pub fn simulate_with(
        &mut self,
        duration: f64,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary> {
        self.check_run(duration)?;
        let times = output_times(duration, self.settings.output_spacing(duration));
        let (q0, qd0) = (self.q0.clone(), self.qd0.clone());
        self.integrate_span((0.0, duration), times, &q0, &qd0, observer, true)
    }

    /// One step of `dt` seconds from `(t, q, q̇)` with the run settings'
    /// integrator and the current inputs ([`Simulation::set_cable_tensions`]):
    /// the state at `t + dt`. For reinforcement-learning and MPC loops that
    /// set `u` between steps. Each call starts the integrator afresh (an
    /// adaptive method takes as many internal steps as its tolerance needs;
    /// a stiff one evaluates its Jacobian once per call).
    pub fn step(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        dt: f64,
    ) -> Result<(DVector<f64>, DVector<f64>)> {
        self.check("q", q)?;
        self.check("qdot", qd)?;
        if !(dt.is_finite() && dt > 0.0 && (t + dt) > t) {
            return Err(Error::InvalidSetting {
                key: "dt",
                message: format!("a step must be positive and finite, got {dt} at t = {t}"),
            });
        }
        struct Last(Option<(DVector<f64>, DVector<f64>)>);
        impl Observer for Last {
            fn sample(&mut self, s: Sample<'_>) -> Result<Flow, String> {
                self.0 = Some((
                    DVector::from_column_slice(s.q),
                    DVector::from_column_slice(s.qd),
                ));
                Ok(Flow::Continue)
            }
        }
        let mut last = Last(None);
        let (q0, qd0) = (
            DVector::from_column_slice(q),
            DVector::from_column_slice(qd),
        );
        self.integrate_span((t, t + dt), vec![t, t + dt], &q0, &qd0, &mut last, false)?;
        last.0.ok_or(Error::Output {
            t: t + dt,
            message: "the step produced no state".into(),
        })
    }

    /// The integration over `t_span` with samples at `times`; `watch`:
    /// check the energy balance and the strains at every accepted step.
    fn integrate_span(
        &mut self,
        t_span: (f64, f64),
        times: Vec<f64>,
        q0: &DVector<f64>,
        qd0: &DVector<f64>,
        observer: &mut dyn Observer,
        watch: bool,
    ) -> Result<RunSummary> {
        let (t0, t1) = t_span;
        let (method, mut opts) = self.settings.method_and_options(t1 - t0)?;
        self.check_dense(
            &format!("the {} integrator", self.settings.integrator.name()),
            dense_matrices_of(method),
        )?;
        opts.t_eval = Some(times);
        self.system.jacobian = self.settings.stiff_jacobian();
        let saved_inputs = self.system.data.cable_tensions().map(<[f64]>::to_vec);
        let watch = if watch && self.settings.energy_tolerance.is_finite() {
            let s = &self.system;
            let mut w = Watch::new(&s.model, &s.data, self.settings.energy_tolerance)?;
            w.start(&s.model, &s.data, t0, q0.as_slice(), qd0.as_slice())?;
            Some(w)
        } else {
            None
        };
        let mut hooks = RunHooks {
            n: self.n_dof(),
            u: saved_inputs
                .clone()
                .unwrap_or_else(|| vec![0.0; self.n_cables()]),
            observer,
            watch,
            samples: 0,
            failure: None,
            violation: None,
        };
        let result =
            integrate_second_order(&mut self.system, method, t_span, q0, qd0, &opts, &mut hooks);
        let s = &mut self.system;
        s.data
            .set_cable_tensions(&s.model, saved_inputs.as_deref())
            .expect("restoring inputs that were valid");
        if let Some((t, message)) = hooks.failure {
            return Err(Error::Output { t, message });
        }
        if let Some(e) = hooks.violation {
            return Err(e);
        }
        let sol = result?;
        let status = if sol.status == softrod_integrate::Status::Completed {
            RunStatus::Completed
        } else {
            RunStatus::Stopped
        };
        let (energy, warnings): (Option<EnergyBalance>, Vec<String>) = match hooks.watch {
            Some(w) => {
                let (b, warn) = w.finish();
                (Some(b), warn)
            }
            None => (None, Vec::new()),
        };
        Ok(RunSummary {
            status,
            t_final: sol.t_final,
            stats: sol.stats,
            samples: hooks.samples,
            energy,
            warnings,
        })
    }
}

/// The integrator's hooks of a facade run, as one object: the observer
/// (samples, steps, a controller's inputs), the watch of the energy balance
/// and strains, and what went wrong (the integrator only hears `Stop`).
struct RunHooks<'o> {
    /// Coordinates per rod system (`y = (q, q̇)` has `2n`).
    n: usize,
    /// The cable tensions the controller writes (one per cable).
    u: Vec<f64>,
    observer: &'o mut dyn Observer,
    watch: Option<Watch>,
    /// Samples delivered to the observer.
    samples: usize,
    /// An observer or controller failure, at its time.
    failure: Option<(f64, String)>,
    /// A watch violation (energy balance, strain validity).
    violation: Option<Error>,
}

impl Hooks<RodSystem> for RunHooks<'_> {
    fn keep_outputs(&self) -> bool {
        false
    }

    fn output(&mut self, t: f64, y: &DVector<f64>, sys: &mut RodSystem) -> Control {
        let (q, qd) = y.as_slice().split_at(self.n);
        // Prescribed joints (D59) at the sample's time.
        sys.model.set_time(&mut sys.data, t);
        let sample = Sample {
            t,
            q,
            qd,
            model: &sys.model,
            data: &mut sys.data,
        };
        match self.observer.sample(sample) {
            Ok(flow) => {
                self.samples += 1;
                match flow {
                    Flow::Continue => Control::Continue,
                    Flow::Stop => Control::Stop,
                }
            }
            Err(message) => {
                self.failure = Some((t, message));
                Control::Stop
            }
        }
    }

    fn step(&mut self, info: &StepInfo<'_>, sys: &mut RodSystem) -> Control {
        self.observer.step(info.t, info.stats);
        let (q, qd) = info.y.as_slice().split_at(self.n);
        if let Some(w) = &mut self.watch {
            if let Err(e) = w.step(&sys.model, &sys.data, info.t, q, qd) {
                self.violation = Some(e);
                return Control::Stop;
            }
        }
        if !self.u.is_empty() && self.observer.inputs(info.t, q, qd, &mut self.u) {
            if let Err(e) = sys.data.set_cable_tensions(&sys.model, Some(&self.u)) {
                self.failure = Some((info.t, format!("controller: {e}")));
                return Control::Stop;
            }
            if let Some(w) = &mut self.watch {
                if let Err(e) = w.inputs_changed(&sys.model, &sys.data, info.t, q, qd) {
                    self.violation = Some(e);
                    return Control::Stop;
                }
            }
            return Control::SystemChanged;
        }
        Control::Continue
    }
}

/// The names of a joint's coordinates (see [`Simulation::q_names`]).
fn joint_names(e: &softrod_dynamics::ElementInfo) -> Vec<String> {
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
