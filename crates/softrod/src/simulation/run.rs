//! Time integration: the observer a run hands its samples to, and the
//! integration behind [`Simulation::simulate_with`] and
//! [`Simulation::step`].

use nalgebra::DVector;
use softrod_dynamics::{Data, Model};
use softrod_integrate::{
    Control, Hooks, ProjectionMisses, RodSystem, Stats, StepInfo, integrate_second_order,
};

use super::Simulation;
use crate::error::{Error, Result};
use crate::limits::dense_matrices_of;
use crate::settings::output_times;
use crate::watch::{EnergyBalance, Watch};

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

    /// Asked after each accepted step: `true` stops the run there (status
    /// [`RunStatus::Stopped`]; the samples end at the last output time).
    /// For a stop request that must not wait for the next output time — a
    /// signal during a run whose output times are far apart.
    fn stop_requested(&mut self) -> bool {
        false
    }

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

impl Simulation {
    /// Integrates `duration` seconds from the initial state, handing each
    /// sample to `observer` as it is produced (the integrator's dense output
    /// at the output times; nothing is kept here).
    ///
    /// The run starts from a fresh contact state (docs/theory-contact.md
    /// CT15: base stiffness, no friction anchors), whatever an earlier run
    /// or [`Simulation::statics`] committed: the same call gives the same
    /// bits whatever came before it. The state it ends with stays for
    /// [`Simulation::contacts`] and [`Simulation::step`] to continue from.
    pub fn simulate_with(
        &mut self,
        duration: f64,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary> {
        self.check_run(duration)?;
        self.system.data.reset_contact();
        let times = output_times(duration, self.settings.output_spacing(duration));
        let (q0, qd0) = (self.q0.clone(), self.qd0.clone());
        self.integrate_span((0.0, duration), times, &q0, &qd0, observer, true)
    }

    /// One step of `dt` seconds from `(t, q, q̇)` with the run settings'
    /// integrator and the current inputs ([`Simulation::set_cable_tensions`]):
    /// the state at `t + dt`. For reinforcement-learning and MPC loops that
    /// set `u` between steps. Each call starts the integrator afresh (an
    /// adaptive method takes as many internal steps as its tolerance needs;
    /// a stiff one evaluates its Jacobian once per call). A continuation:
    /// the contact state (friction anchors, raised stiffnesses, CT15) is
    /// the one the last run, statics or step left, and this step commits
    /// its own; a loop of steps from the initial state after another run
    /// should start with [`Simulation::reset_contact`].
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
        // Steps end where a drive stops or changes rate (D59) rather than
        // straddling it: the dense outputs there would be off the closures.
        opts.breakpoints = self.system.model.breakpoints();
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
        self.system.forget_contact_linearization();
        self.system.reset_projection_misses();
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
        let (energy, mut warnings): (Option<EnergyBalance>, Vec<String>) = match hooks.watch {
            Some(w) => {
                let (b, warn) = w.finish();
                (Some(b), warn)
            }
            None => (None, Vec::new()),
        };
        if let Some(w) = projection_warning(self.system.projection_misses()) {
            warnings.push(w);
        }
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

/// What a run says when the projection onto the closures (D121) gave up at
/// some step ends: there the loops were held by the stabilization alone
/// (still watched: a loop that comes apart stops the run), which the user
/// asked not to rely on.
fn projection_warning(m: ProjectionMisses) -> Option<String> {
    (m.count > 0).then(|| {
        format!(
            "project_closures: the projection onto the closures did not converge at {} step \
             end(s), first at t = {} s (closure residual left there up to {:.3e} m); those \
             steps kept the stabilized state",
            m.count, m.first_t, m.largest_residual
        )
    })
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
        if self.observer.stop_requested() {
            return Control::Stop;
        }
        let (q, qd) = info.y.as_slice().split_at(self.n);
        if let Some(w) = &mut self.watch {
            if let Err(e) = w.step(&sys.model, &sys.data, info.t, q, qd) {
                self.violation = Some(e);
                return Control::Stop;
            }
        }
        // Contact friction (docs/theory-contact.md CT5): the anchors move
        // only at accepted steps.
        let contact_control = match sys.commit_contact_control(info.t, q, qd) {
            Ok(c) => c,
            Err(e) => {
                self.failure = Some((info.t, e.to_string()));
                return Control::Stop;
            }
        };
        let contact_changed = contact_control != Control::Continue;
        if contact_changed {
            // The next step's law (anchors, stiffness: CT5, CT15) is not
            // this one's: its power from here on is the new law's.
            if let Some(w) = &mut self.watch {
                if let Err(e) = w.inputs_changed(&sys.model, &sys.data, info.t, q, qd) {
                    self.violation = Some(e);
                    return Control::Stop;
                }
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
        // A raised stiffness changes the law's slope (the Jacobians go);
        // moved anchors and healing offsets only its forces here (CT25).
        contact_control
    }
}
