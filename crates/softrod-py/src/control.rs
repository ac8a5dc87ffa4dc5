//! Cable-tension inputs `u` and the integration paths that use them: the
//! step API and simulation with a controller in the loop.
//!
//! [`CableInputs`] holds a copy of the model (joints, bodies and closures
//! included) whose `Data` evaluates the cables at the tensions `u` (one per
//! cable, in model order: rod by rod, in the order given) instead of their
//! schedules (`Data::set_cable_tensions`): the cables then act as
//! `A(q) u`, with `A(q) = −∂ℓ/∂q` the actuation matrix (D15) evaluated at the
//! current `q` in every right-hand side (so the force follows the rod within
//! a step; it is `u` that is held, not `τ`), and the exact Jacobians include
//! `∂(A(q)u)/∂q`.

use nalgebra::DVector;
use softrod::Settings;
use softrod::dynamics::{DynamicsError, Model, forward_dynamics};
use softrod::integrate::{
    Control, Hooks, IntegrateError, Options, RodSystem, SecondOrderSystem, Status, StepControl,
    StepInfo, integrate_second_order,
};
use softrod::{RunStatus, Trajectory, TrajectoryRecorder, output_times};

/// A model's cables as inputs `u`.
#[derive(Clone, Debug)]
pub struct CableInputs {
    /// The model and its buffers; its `Data` evaluates the cables at `u`
    /// and its `tau` is `τ_extra` (re-synchronized before each evaluation).
    pub sys: RodSystem,
    /// The tensions `u` [N] (n_cables).
    pub u: Vec<f64>,
    /// An actuator force besides the cables (n_dof), if any.
    pub tau_extra: Option<DVector<f64>>,
    /// The joint actuators' forces held with `u` [N or N·m]
    /// (`Model::n_joint_inputs`, docs/theory-control.md IS14), or `None`
    /// for the actuators' schedules.
    pub joint_forces: Option<Vec<f64>>,
}

impl CableInputs {
    /// The inputs of `model` (any number of cables, zero included), all at
    /// zero tension.
    pub fn new(model: &Model) -> Result<Self, DynamicsError> {
        Ok(Self {
            sys: RodSystem::new(model.clone()),
            u: vec![0.0; model.n_cables()],
            tau_extra: None,
            joint_forces: None,
        })
    }

    /// Hands `u`, the joint forces and `τ_extra` to the system (`u` was
    /// checked on entry: non-negative and finite, one per cable; the joint
    /// forces finite, one per actuated coordinate).
    pub fn sync(&mut self) -> Result<(), DynamicsError> {
        let s = &mut self.sys;
        s.data.set_cable_tensions(&s.model, Some(&self.u))?;
        s.data
            .set_joint_forces(&s.model, self.joint_forces.as_deref())?;
        match (&self.tau_extra, &mut s.tau) {
            (None, tau) => *tau = None,
            (Some(t), Some(tau)) => tau.copy_from(t),
            (Some(t), tau) => *tau = Some(t.clone()),
        }
        Ok(())
    }

    /// Forward dynamics `q̈` under the inputs.
    pub fn forward_dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<&DVector<f64>, DynamicsError> {
        self.sync()?;
        let s = &mut self.sys;
        forward_dynamics(
            &s.model,
            &mut s.data,
            t,
            q,
            qd,
            s.tau.as_ref().map(|v| v.as_slice()),
        )
    }
}

impl SecondOrderSystem for CableInputs {
    type Error = DynamicsError;

    fn dim(&self) -> usize {
        self.sys.dim()
    }

    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), DynamicsError> {
        self.sync()?;
        self.sys.accel(t, q, qd, qdd)
    }

    /// The system's exact Jacobians at the held `u` (`∂(A(q)u)/∂q`
    /// included).
    fn jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        dqdd_dq: &mut nalgebra::DMatrix<f64>,
        dqdd_dqd: &mut nalgebra::DMatrix<f64>,
    ) -> Result<(), DynamicsError> {
        self.sync()?;
        self.sys.jacobians(t, q, qd, dqdd_dq, dqdd_dqd)
    }

    fn mass_form_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        mass: &mut nalgebra::DMatrix<f64>,
        constant: Option<(&mut nalgebra::DMatrix<f64>, &mut nalgebra::DMatrix<f64>)>,
    ) -> Result<bool, DynamicsError> {
        self.sys.mass_form_jacobians(t, q, qd, mass, constant)
    }

    fn has_mass_form(&self) -> bool {
        self.sys.has_mass_form()
    }

    /// The rod's O(N) shifted-mass factorization `M(q) + aK + bD`: the
    /// cables' `u` does not enter it (their force `A(q) u` is a load term,
    /// which the structured Newton matrix leaves out like gravity). Without
    /// this forward the implicit methods fell back to the dense exact
    /// Jacobian at every update (docs/performance.md, "Learning
    /// environments").
    fn factor_shifted_mass(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        a: f64,
        b: f64,
    ) -> Result<bool, DynamicsError> {
        self.sys.factor_shifted_mass(t, q, a, b)
    }

    fn solve_shifted_mass(&mut self, x: &mut DVector<f64>) -> Result<(), DynamicsError> {
        self.sys.solve_shifted_mass(x)
    }

    /// The contact's stiffness and damping in the shifted matrix
    /// (docs/theory-contact.md CT17): `u` does not enter them.
    fn linearize_shifted(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
    ) -> Result<(), DynamicsError> {
        self.sys.linearize_shifted(t, q, qd)
    }

    /// The rod system's choice (CT27): without it a step with inputs would
    /// iterate on another matrix than the same step without them.
    fn relinearize_in_newton(&self) -> bool {
        self.sys.relinearize_in_newton()
    }

    /// The rod system's friction stops (CT29): `u` does not enter the
    /// contact law.
    fn step_event_fraction(
        &mut self,
        h: f64,
        t0: f64,
        q0: &DVector<f64>,
        qd0: &DVector<f64>,
        t1: f64,
        q1: &DVector<f64>,
        qd1: &DVector<f64>,
    ) -> Result<Option<f64>, DynamicsError> {
        self.sys.step_event_fraction(h, t0, q0, qd0, t1, q1, qd1)
    }

    fn force_residual(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        r: &mut DVector<f64>,
    ) -> Result<bool, DynamicsError> {
        self.sync()?;
        self.sys.force_residual(t, q, qd, qdd, r)
    }

    /// `u` is piecewise constant (a change is signalled to the integrator)
    /// and replaces the tension schedules, so time enters only through
    /// prescribed joints.
    fn is_autonomous(&self) -> bool {
        self.sys.is_autonomous()
    }
}

/// Keeps the samples of a run: the facade's recorder, fed from the
/// integrator's output hook with the prescribed joints set to each time.
pub struct Recorder {
    inner: TrajectoryRecorder,
}

impl Recorder {
    pub fn new(model: &Model) -> Self {
        Self {
            inner: TrajectoryRecorder::new(model),
        }
    }

    /// Records the state `y = (q, q̇)` at `t`.
    pub fn record(&mut self, sys: &mut RodSystem, t: f64, y: &DVector<f64>) -> Result<(), String> {
        let n = sys.model.n_dof();
        let (q, qd) = y.as_slice().split_at(n);
        sys.model.set_time(&mut sys.data, t);
        self.inner.record(&sys.model, &mut sys.data, t, q, qd)
    }
}

/// Checks `u`: one finite, non-negative tension per cable.
pub fn check_tensions(n_cables: usize, what: &str, u: &[f64]) -> Result<(), String> {
    if u.len() != n_cables {
        return Err(format!(
            "{what} must have shape ({n_cables},) (one tension per cable), got ({},)",
            u.len()
        ));
    }
    if let Some((i, v)) = u
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
    {
        return Err(format!(
            "{what}[{i}] = {v}: cable tensions must be finite and >= 0 (a cable cannot push)"
        ));
    }
    Ok(())
}

/// Checks joint forces: one finite value per actuated joint coordinate
/// (`names`, `softrod::Simulation::joint_input_names`); messages name the
/// coordinate.
pub fn check_joint_forces(names: &[String], what: &str, f: &[f64]) -> Result<(), String> {
    let n_inputs = names.len();
    if f.len() != n_inputs {
        return Err(format!(
            "{what} must have shape ({n_inputs},) (one force per actuated joint coordinate: \
             {names:?}), got ({},)",
            f.len()
        ));
    }
    if let Some((i, v)) = f.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(format!(
            "{what}[{i}] ({}) = {v}: joint forces must be finite",
            names[i]
        ));
    }
    Ok(())
}

/// Why a controlled run stopped early.
pub enum ControlError {
    /// The integrator failed.
    Integrate(IntegrateError),
    /// The controller (Python) raised or returned a bad `u`: already a
    /// Python exception.
    Controller(pyo3::PyErr),
    /// Recording a sample failed.
    Output { t: f64, message: String },
    /// Committing the contact state after an accepted step failed (a
    /// contact deeper than the bound, docs/theory-contact.md CT15).
    Contact { t: f64, error: DynamicsError },
}

/// Systems whose contact state (friction anchors, raised stiffnesses;
/// docs/theory-contact.md CT5, CT15) moves at accepted steps, as
/// `Simulation::simulate`'s does.
pub trait CommitContact {
    /// `RodSystem::commit_contact_control` of the system's rod model: what
    /// changed, as the step hook reports it (CT25: a raised stiffness drops
    /// the Jacobians, moved anchors only re-evaluate the forces).
    fn commit_contact(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<Control, DynamicsError>;

    /// `RodSystem::forget_contact_linearization`: a step starts afresh,
    /// whatever the workspace integrated before.
    fn forget_contact_linearization(&mut self);
}

impl CommitContact for RodSystem {
    fn commit_contact(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<Control, DynamicsError> {
        self.commit_contact_control(t, q, qd)
    }

    fn forget_contact_linearization(&mut self) {
        RodSystem::forget_contact_linearization(self);
    }
}

impl CommitContact for CableInputs {
    fn commit_contact(&mut self, t: f64, q: &[f64], qd: &[f64]) -> Result<Control, DynamicsError> {
        self.sys.commit_contact_control(t, q, qd)
    }

    fn forget_contact_linearization(&mut self) {
        self.sys.forget_contact_linearization();
    }
}

/// The step API's hooks: only the contact commit after every accepted step
/// (without it friction never sticks and the penetration bound is never
/// checked on stepped, environment and batched runs).
struct CommitHooks {
    n: usize,
    failure: Option<DynamicsError>,
}

impl<S: SecondOrderSystem + CommitContact> Hooks<S> for CommitHooks {
    fn keep_outputs(&self) -> bool {
        false
    }

    fn step(&mut self, info: &StepInfo<'_>, sys: &mut S) -> Control {
        let (q, qd) = info.y.as_slice().split_at(self.n);
        match sys.commit_contact(info.t, q, qd) {
            Ok(control) => control,
            Err(e) => {
                self.failure = Some(e);
                Control::Stop
            }
        }
    }
}

/// A controller: `u = f(t, q, q̇)`, written into `u`.
pub type ControllerFn<'a> =
    dyn FnMut(f64, &[f64], &[f64], &mut Vec<f64>) -> Result<(), pyo3::PyErr> + 'a;

/// What a controlled run integrates: `duration` seconds from `(q0, q̇0)`,
/// with the controller sampled after every accepted integrator step
/// (`control_every = None`) or every `control_every` seconds.
pub struct ControlledRun<'a> {
    /// Simulated time \[s\].
    pub duration: f64,
    /// Initial coordinates (n_dof).
    pub q0: &'a DVector<f64>,
    /// Initial velocities (n_dof).
    pub qd0: &'a DVector<f64>,
    /// The control period \[s\], or `None` for every accepted step.
    pub control_every: Option<f64>,
}

/// Integrates `run` with `u` from `controller` held constant between
/// updates (zero-order hold): at `t = 0`, then after every accepted
/// integrator step (`control_every = None`) or every `control_every`
/// seconds (the run is integrated in segments of that length, restarting
/// the integrator at each, so the hold is exact whatever the integrator's
/// steps).
pub fn simulate_controlled(
    inputs: &mut CableInputs,
    settings: &Settings,
    run: ControlledRun<'_>,
    controller: &mut ControllerFn<'_>,
) -> Result<Trajectory, ControlError> {
    let ControlledRun {
        duration,
        q0,
        qd0,
        control_every,
    } = run;
    let (method, base_opts) =
        settings
            .method_and_options(duration)
            .map_err(|e| ControlError::Output {
                t: 0.0,
                message: e.to_string(),
            })?;
    // Steps end where a drive stops or changes rate, as in Simulation's runs.
    let mut base_opts = base_opts;
    base_opts.breakpoints = inputs.sys.model.breakpoints();
    inputs.sys.jacobian = settings.stiff_jacobian();
    let times = output_times(duration, settings.output_spacing(duration));
    let n = inputs.dim();
    let mut rec = Recorder::new(&inputs.sys.model);
    let mut stats = softrod::integrate::Stats::default();
    let mut u = std::mem::take(&mut inputs.u);
    controller(0.0, q0.as_slice(), qd0.as_slice(), &mut u).map_err(ControlError::Controller)?;
    inputs.u = u;

    let segments: Vec<(f64, f64)> = match control_every {
        None => vec![(0.0, duration)],
        Some(dc) => {
            let k = (duration / dc - 1e-9).ceil().max(1.0) as usize;
            (0..k)
                .map(|i| (i as f64 * dc, ((i + 1) as f64 * dc).min(duration)))
                .collect()
        }
    };
    let (mut q, mut qd) = (q0.clone(), qd0.clone());
    let mut next_output = 0usize;
    let per_step = control_every.is_none();
    for (k, &(t0, t1)) in segments.iter().enumerate() {
        if k > 0 {
            let mut u = std::mem::take(&mut inputs.u);
            controller(t0, q.as_slice(), qd.as_slice(), &mut u)
                .map_err(ControlError::Controller)?;
            inputs.u = u;
        }
        let first = next_output;
        while next_output < times.len() && (times[next_output] <= t1 || k + 1 == segments.len()) {
            next_output += 1;
        }
        let mut opts: Options = base_opts.clone();
        opts.t_eval = Some(times[first..next_output].to_vec());
        if let StepControl::Adaptive { h0: Some(h) } = opts.step {
            opts.step = StepControl::Adaptive {
                h0: Some(h.min(t1 - t0)),
            };
        }
        let mut hooks = ControlHooks {
            n,
            rec: &mut rec,
            controller: if per_step {
                Some(&mut *controller)
            } else {
                None
            },
            failure: None,
        };
        inputs.forget_contact_linearization();
        let result = integrate_second_order(inputs, method, (t0, t1), &q, &qd, &opts, &mut hooks);
        if let Some(f) = hooks.failure {
            return Err(f);
        }
        let sol = result.map_err(ControlError::Integrate)?;
        add_stats(&mut stats, &sol.stats);
        q.copy_from(&sol.y_final.rows(0, n));
        qd.copy_from(&sol.y_final.rows(n, n));
        rec.inner.trajectory_mut().summary.t_final = sol.t_final;
        if sol.status != Status::Completed {
            rec.inner.trajectory_mut().summary.status = RunStatus::Stopped;
            break;
        }
    }
    let warning = rec.inner.penetration_warning(&inputs.sys.model);
    let mut traj = rec.inner.into_trajectory();
    traj.summary.stats = stats;
    traj.summary.warnings.extend(warning);
    Ok(traj)
}

/// The integrator's hooks of a controlled segment, as one object: the
/// record of the samples, the controller after every accepted step (when it
/// runs per step) and what went wrong (the integrator only hears `Stop`).
struct ControlHooks<'r, 'c> {
    /// Coordinates (`y = (q, q̇)` has `2n`).
    n: usize,
    rec: &'r mut Recorder,
    /// The controller, when it runs after every accepted step.
    controller: Option<&'r mut ControllerFn<'c>>,
    failure: Option<ControlError>,
}

impl Hooks<CableInputs> for ControlHooks<'_, '_> {
    fn keep_outputs(&self) -> bool {
        false
    }

    fn output(&mut self, t: f64, y: &DVector<f64>, sys: &mut CableInputs) -> Control {
        match self.rec.record(&mut sys.sys, t, y) {
            Ok(()) => Control::Continue,
            Err(message) => {
                self.failure = Some(ControlError::Output { t, message });
                Control::Stop
            }
        }
    }

    /// The contact commit, then `u` from the controller at the step's end,
    /// held from there on.
    fn step(&mut self, info: &StepInfo<'_>, sys: &mut CableInputs) -> Control {
        let (q, qd) = info.y.as_slice().split_at(self.n);
        let contact_control = match sys.commit_contact(info.t, q, qd) {
            Ok(control) => control,
            Err(error) => {
                self.failure = Some(ControlError::Contact { t: info.t, error });
                return Control::Stop;
            }
        };
        let Some(controller) = self.controller.as_mut() else {
            return contact_control;
        };
        let mut u = std::mem::take(&mut sys.u);
        let r = controller(info.t, q, qd, &mut u);
        sys.u = u;
        match r {
            Ok(()) => Control::SystemChanged,
            Err(e) => {
                self.failure = Some(ControlError::Controller(e));
                Control::Stop
            }
        }
    }
}

fn add_stats(acc: &mut softrod::integrate::Stats, s: &softrod::integrate::Stats) {
    acc.steps += s.steps;
    acc.rejected_steps += s.rejected_steps;
    acc.rhs_evaluations += s.rhs_evaluations;
    acc.jacobian_evaluations += s.jacobian_evaluations;
    acc.factorizations += s.factorizations;
    acc.lu_solves += s.lu_solves;
    acc.newton_iterations += s.newton_iterations;
}

/// One step of the step API: from `(t, q, q̇)` over `dt` with the run
/// settings' integrator, on `sys` (a [`RodSystem`] with the scheduled
/// tensions, or [`CableInputs`] with `u` held). Returns `(q, q̇)` at `t + dt`.
///
/// `substeps`: `None` integrates with the settings (adaptive methods adapt,
/// starting from `settings.dt`); `Some(k)` takes `k` fixed steps of
/// `dt / k` with the settings' integrator (an implicit method still halves a
/// step whose Newton iteration fails; `rtol`, `atol` then only weight its
/// Newton test).
pub fn step<S: SecondOrderSystem + CommitContact>(
    sys: &mut S,
    settings: &Settings,
    t: f64,
    dt: f64,
    q: &DVector<f64>,
    qd: &DVector<f64>,
    substeps: Option<usize>,
) -> Result<(DVector<f64>, DVector<f64>), softrod::Error> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(softrod::Error::InvalidSetting {
            key: "dt",
            message: format!("the step length must be positive and finite, got {dt}"),
        });
    }
    let (method, mut opts) = settings.method_and_options(dt)?;
    if let Some(k) = substeps {
        check_substeps(k).map_err(|message| softrod::Error::InvalidSetting {
            key: "substeps",
            message,
        })?;
        opts.step = StepControl::Fixed(dt / k as f64);
        opts.max_steps = 2 * k + 100;
    }
    opts.t_eval = Some(Vec::new());
    let n = sys.dim();
    let mut hooks = CommitHooks { n, failure: None };
    sys.forget_contact_linearization();
    let result = integrate_second_order(sys, method, (t, t + dt), q, qd, &opts, &mut hooks);
    if let Some(e) = hooks.failure {
        return Err(e.into());
    }
    let sol = result?;
    Ok((
        sol.y_final.rows(0, n).into_owned(),
        sol.y_final.rows(n, n).into_owned(),
    ))
}

/// Checks a number of fixed steps per call: at least 1, at most 10⁶.
pub fn check_substeps(k: usize) -> Result<(), String> {
    if (1..=1_000_000).contains(&k) {
        Ok(())
    } else {
        Err(format!("substeps must be between 1 and 1000000, got {k}"))
    }
}
