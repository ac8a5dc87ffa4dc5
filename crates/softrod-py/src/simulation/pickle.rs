//! Pickling a `softrod.Simulation` (for Ray, multiprocessing): its state is
//! the scene text it was built from, its run settings, its initial state,
//! the cable tensions and joint forces last held by `step`, the
//! prescribed joints' transitions in force, and the scene's duration and
//! warnings — plain Python values, so a pickle holds no Rust memory and
//! loads in any process with the same softrod.
//!
//! `__reduce__` returns `(softrod._pickle.restore, (state,))`; `restore`
//! calls `Simulation._from_state(state)`, which rebuilds the model from the
//! text by the scene loader (the same path as `from_toml`, so the same
//! model to the bit) and puts the rest back.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use softrod::Integrator;

use super::Simulation;
use crate::errors::{input, to_py};

/// The version of the state dict (a pickle from another layout is refused
/// with a clear message instead of misread).
const VERSION: u32 = 1;

impl Simulation {
    /// The state dict of `__reduce__`.
    pub(super) fn pickle_state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let Some(scene) = &self.source else {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "this Simulation cannot be pickled: it was not built from a scene (from_file, \
                 from_toml, from_dict or Simulation(rods=...)); build it from one of those",
            ));
        };
        let s = self.sim.settings();
        let d = PyDict::new(py);
        d.set_item("version", VERSION)?;
        d.set_item("scene", scene.as_ref())?;
        let settings = PyDict::new(py);
        settings.set_item("integrator", s.integrator.name())?;
        settings.set_item("rtol", s.rtol)?;
        settings.set_item("atol", s.atol)?;
        settings.set_item("dt", s.dt)?;
        settings.set_item("output_every", s.output_every)?;
        settings.set_item("error_control", s.error_control)?;
        settings.set_item("linearly_implicit", s.linearly_implicit)?;
        settings.set_item("steps_to_outputs", s.steps_to_outputs)?;
        settings.set_item("project_closures", s.project_closures)?;
        settings.set_item("duration", s.duration)?;
        settings.set_item("energy_tolerance", s.energy_tolerance)?;
        d.set_item("settings", settings)?;
        let (q0, qd0) = self.sim.initial_state();
        d.set_item("q0", q0.as_slice().to_vec())?;
        d.set_item("qdot0", qd0.as_slice().to_vec())?;
        d.set_item("tensions", self.inputs.as_ref().map(|i| i.u.clone()))?;
        // What the last step held besides the tensions: the joint forces
        // (None: the actuators' schedules) and the prescribed joints'
        // transitions (PT1; empty: the scene's curves), as plain numbers
        // from which the same curves are rebuilt to the bit.
        d.set_item(
            "joint_forces",
            self.inputs.as_ref().and_then(|i| i.joint_forces.clone()),
        )?;
        let tr: Vec<[f64; 5]> = self
            .sim
            .prescribed_transitions()
            .iter()
            .map(|t| [t.t0, t.t1, t.x0, t.v0, t.x1])
            .collect();
        d.set_item("prescribed_transitions", tr)?;
        d.set_item("duration", self.duration)?;
        d.set_item("warnings", self.warnings.clone())?;
        Ok(d)
    }

    /// `(softrod._pickle.restore, (state,))`.
    pub(super) fn reduce<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let restore = py.import("softrod._pickle")?.getattr("restore")?;
        let state = self.pickle_state(py)?;
        PyTuple::new(py, [restore, PyTuple::new(py, [state])?.into_any()])
    }

    /// The simulation a state dict of [`Simulation::pickle_state`] describes.
    pub(super) fn from_state(state: &Bound<'_, PyDict>) -> PyResult<Self> {
        let item = |k: &str| -> PyResult<Bound<'_, PyAny>> {
            state
                .get_item(k)?
                .ok_or_else(|| input(format!("Simulation state: no {k:?}")))
        };
        let version: u32 = item("version")?.extract()?;
        if version != VERSION {
            return Err(input(format!(
                "Simulation state of version {version}: this softrod reads version {VERSION}"
            )));
        }
        let scene: String = item("scene")?.extract()?;
        let (sim, _, _) = softrod::Simulation::from_toml(&scene, "<pickle>").map_err(to_py)?;
        let mut me = Self::wrap(
            sim,
            item("warnings")?.extract()?,
            item("duration")?.extract()?,
        );
        me.source = Some(scene.into());
        let st = item("settings")?;
        let st = st
            .cast::<PyDict>()
            .map_err(|_| input("Simulation state: settings must be a dict"))?;
        let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
            st.get_item(k)?
                .ok_or_else(|| input(format!("Simulation state: no settings {k:?}")))
        };
        let name: String = get("integrator")?.extract()?;
        let integrator: Integrator = name
            .parse()
            .map_err(|e| input(format!("Simulation state: integrator: {e}")))?;
        let settings = softrod::Settings {
            integrator,
            rtol: get("rtol")?.extract()?,
            atol: get("atol")?.extract()?,
            dt: get("dt")?.extract()?,
            output_every: get("output_every")?.extract()?,
            error_control: get("error_control")?.extract()?,
            linearly_implicit: get("linearly_implicit")?.extract()?,
            // Absent from pickles written before the setting existed.
            steps_to_outputs: match st.get_item("steps_to_outputs")? {
                Some(v) => v.extract()?,
                None => false,
            },
            project_closures: match st.get_item("project_closures")? {
                Some(v) => v.extract()?,
                None => false,
            },
            duration: get("duration")?.extract()?,
            energy_tolerance: get("energy_tolerance")?.extract()?,
        };
        me.sim.set_settings(settings).map_err(to_py)?;
        let q0: Vec<f64> = item("q0")?.extract()?;
        let qd0: Vec<f64> = item("qdot0")?.extract()?;
        me.sim.set_initial_state(&q0, &qd0).map_err(to_py)?;
        if let Some(u) = item("tensions")?.extract::<Option<Vec<f64>>>()? {
            let nc = me.sim.model().n_cables();
            crate::control::check_tensions(nc, "Simulation state: tensions", &u).map_err(input)?;
            me.inputs()?.u = u;
        }
        // Absent from pickles written before these were kept.
        if let Some(f) = state.get_item("joint_forces")? {
            if let Some(f) = f.extract::<Option<Vec<f64>>>()? {
                let names = me.sim.joint_input_names();
                crate::control::check_joint_forces(&names, "Simulation state: joint_forces", &f)
                    .map_err(input)?;
                me.inputs()?.joint_forces = Some(f);
            }
        }
        if let Some(tr) = state.get_item("prescribed_transitions")? {
            let tr: Vec<[f64; 5]> = tr.extract()?;
            let tr: Vec<softrod::control::Transition> = tr
                .into_iter()
                .map(|[t0, t1, x0, v0, x1]| softrod::control::Transition { t0, t1, x0, v0, x1 })
                .collect();
            me.sim.set_prescribed_transitions(&tr).map_err(to_py)?;
        }
        Ok(me)
    }
}
