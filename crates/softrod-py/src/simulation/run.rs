//! Runs from Python: `simulate` (the facade's run, or a controller in the
//! loop) and `step`.

use nalgebra::DVector;
use pyo3::prelude::*;
use softrod::integrate::RodSystem;

use super::Simulation;
use crate::control::{
    ControlError, ControlledRun, check_substeps, check_tensions, simulate_controlled, step,
};
use crate::convert::{vec_out, vector};
use crate::errors::{dynamics, guard, guard_detached, input, integrate, simulation, to_py};
use crate::trajectory::{State, Trajectory};

/// Where a run of `simulate` starts and how it is driven.
pub(super) struct RunStart<'a, 'py> {
    /// Initial coordinates and velocities (None: the simulation's).
    pub q0: Option<&'a Bound<'py, PyAny>>,
    /// See `q0`.
    pub qdot0: Option<&'a Bound<'py, PyAny>>,
    /// `controller(t, q, qdot) -> u`, if any.
    pub controller: Option<Py<PyAny>>,
    /// Its hold time [s] (None: every accepted step).
    pub control_every: Option<f64>,
}

impl Simulation {
    /// `simulate(duration, …)` with the settings of this call.
    pub(super) fn simulate_impl(
        &mut self,
        py: Python<'_>,
        duration: Option<f64>,
        settings: softrod::Settings,
        start: RunStart<'_, '_>,
    ) -> PyResult<Trajectory> {
        let RunStart {
            q0,
            qdot0,
            controller,
            control_every,
        } = start;
        let duration = duration.or(self.duration).ok_or_else(|| {
            input("simulate needs a duration (this simulation has no scene [run] duration)")
        })?;
        let n = self.n();
        let (iq, iqd) = self.sim.initial_state();
        let q_start = match q0 {
            Some(q) => DVector::from_column_slice(vector(q, "q0", n)?.slice()),
            None => iq.clone(),
        };
        let qd_start = match qdot0 {
            Some(q) => DVector::from_column_slice(vector(q, "qdot0", n)?.slice()),
            None => iqd.clone(),
        };
        if let Some(dc) = control_every {
            if !(dc.is_finite() && dc > 0.0) {
                return Err(input(format!(
                    "control_every must be positive and finite, got {dc}"
                )));
            }
        }
        if !(duration.is_finite() && duration > 0.0) {
            return Err(to_py(softrod::Error::InvalidSetting {
                key: "duration",
                message: format!("must be positive and finite, got {duration}"),
            }));
        }
        match controller {
            None => {
                let sim = &mut self.sim;
                let traj = guard_detached(py, || {
                    let saved = sim.settings().clone();
                    let (sq, sqd) = {
                        let (a, b) = sim.initial_state();
                        (a.clone(), b.clone())
                    };
                    sim.set_settings(settings).map_err(to_py)?;
                    sim.set_initial_state(q_start.as_slice(), qd_start.as_slice())
                        .map_err(to_py)?;
                    let r = sim.simulate(duration);
                    sim.set_settings(saved).map_err(to_py)?;
                    sim.set_initial_state(sq.as_slice(), sqd.as_slice())
                        .map_err(to_py)?;
                    r.map_err(to_py)
                })?;
                Trajectory::new(py, traj, self.sim.model())
            }
            Some(f) => {
                let nc = self.sim.model().n_cables();
                self.inputs()?;
                let inputs = self.inputs.as_mut().expect("built above");
                inputs.tau_extra = None;
                inputs.joint_forces = None;
                // A run starts from a fresh contact state, as the facade's
                // does (CT15), and leaves what it committed for `contacts`
                // and `step`.
                inputs.sys.data.reset_contact();
                let call = |t: f64, q: &[f64], qd: &[f64], u: &mut Vec<f64>| -> PyResult<()> {
                    Python::attach(|py| {
                        let r = f.bind(py).call1((t, vec_out(py, q), vec_out(py, qd)))?;
                        let a = vector(&r, "the controller's u", nc)?;
                        u.clear();
                        u.extend_from_slice(a.slice());
                        Ok(())
                    })
                };
                let mut controller =
                    |t: f64, q: &[f64], qd: &[f64], u: &mut Vec<f64>| -> PyResult<()> {
                        call(t, q, qd, u)?;
                        check_tensions(nc, "the controller's u", u)
                            .map_err(|m| input(format!("at t = {t:e}: {m}")))
                    };
                let r = py.detach(|| {
                    guard(|| {
                        let run = ControlledRun {
                            duration,
                            q0: &q_start,
                            qd0: &qd_start,
                            control_every,
                        };
                        Ok(simulate_controlled(inputs, &settings, run, &mut controller))
                    })
                })?;
                self.sim.contact_state_from(&inputs.sys.data);
                match r {
                    Ok(traj) => Trajectory::new(py, traj, self.sim.model()),
                    Err(ControlError::Integrate(e)) => Err(integrate(e)),
                    Err(ControlError::Controller(e)) => Err(e),
                    Err(ControlError::Output { t, message }) => Err(simulation(
                        format!("output at t = {t:e} s failed: {message}"),
                        Some(t),
                    )),
                    Err(ControlError::Contact { t, error }) => {
                        Err(simulation(format!("at t = {t:e} s: {error}"), Some(t)))
                    }
                }
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn step_impl(
        &mut self,
        py: Python<'_>,
        state: PyRef<'_, State>,
        dt: f64,
        u: Option<&Bound<'_, PyAny>>,
        substeps: Option<usize>,
        joint_forces: Option<&Bound<'_, PyAny>>,
        prescribed_targets: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<State> {
        if let Some(k) = substeps {
            check_substeps(k).map_err(input)?;
        }
        let joint_forces = match joint_forces {
            Some(f) => Some(self.joint_forces(f)?),
            None => None,
        };
        let targets = match prescribed_targets {
            Some(p) => Some(self.prescribed_targets_arg(p)?),
            None => None,
        };
        let n = self.n();
        let q =
            DVector::from_column_slice(vector(state.q.bind(py).as_any(), "state.q", n)?.slice());
        let qd = DVector::from_column_slice(
            vector(state.qdot.bind(py).as_any(), "state.qdot", n)?.slice(),
        );
        let t = state.t;
        let settings = self.sim.settings().clone();
        let u = match u {
            Some(u) => Some(self.tensions(u)?),
            None => None,
        };
        if !(dt.is_finite() && dt > 0.0) {
            return Err(to_py(softrod::Error::InvalidSetting {
                key: "dt",
                message: format!("the step length must be positive and finite, got {dt}"),
            }));
        }
        // Every input checked: the command cannot leave a half-made step.
        if let Some(p) = &targets {
            self.sim.command_prescribed(t, dt, p).map_err(to_py)?;
        }
        let (q1, qd1) = match u {
            Some(u) => {
                self.inputs()?;
                self.sync_prescribed()?;
                let inputs = self.inputs.as_mut().expect("built above");
                inputs.u = u;
                inputs.tau_extra = None;
                inputs.joint_forces = joint_forces;
                inputs.sys.jacobian = settings.stiff_jacobian();
                self.sim.contact_state_into(&mut inputs.sys.data);
                let r = guard_detached(py, || {
                    step(&mut **inputs, &settings, t, dt, &q, &qd, substeps).map_err(to_py)
                })?;
                self.sim.contact_state_from(&inputs.sys.data);
                r
            }
            None => {
                if self.stepper.is_none() {
                    self.stepper = Some(Box::new(RodSystem::new(self.sim.model().clone())));
                }
                self.sync_prescribed()?;
                let sys = self.stepper.as_mut().expect("just set");
                sys.jacobian = settings.stiff_jacobian();
                sys.data
                    .set_joint_forces(&sys.model, joint_forces.as_deref())
                    .map_err(dynamics)?;
                self.sim.contact_state_into(&mut sys.data);
                let r = guard_detached(py, || {
                    step(&mut **sys, &settings, t, dt, &q, &qd, substeps).map_err(to_py)
                })?;
                self.sim.contact_state_from(&sys.data);
                r
            }
        };
        State::from_slices(py, t + dt, q1.as_slice(), qd1.as_slice())
    }
}
