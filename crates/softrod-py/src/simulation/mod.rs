//! `softrod.Simulation`: the facade's `Simulation` with numpy in and out.
//!
//! This file is the class's Python surface (signatures and docstrings);
//! the longer bodies live by concern beside it: [`kinematics`] (poses and
//! Jacobians along a rod), [`dynamics`] (evaluations with tension inputs),
//! [`analysis`] (statics, modes), [`run`] (simulation, steps).
//!
//! Time: Python has no clock. Every evaluation whose result can depend on
//! time (through prescribed joints or tension schedules) takes it as an
//! argument: the dynamics calls first, `f(t, q, qdot)` (forward and
//! inverse dynamics, bias, mass matrix, energies, gravity, drive forces,
//! linearization), the kinematic queries (poses, Jacobians, closure
//! residuals) as the keyword `t` (default 0), which only prescribed joints
//! read. Functions of the configuration alone (actuation, stiffness,
//! damping, Coriolis) take none.

mod actuation;
mod analysis;
mod dynamics;
mod gradient;
mod kinematics;
mod pickle;
mod run;

use nalgebra::DMatrix;
use numpy::{PyArray1, PyArray2, PyArrayDyn};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyString};
use softrod::dynamics::{
    Model, actuation_matrix, coriolis_matrix, damping_matrix, stiffness_matrix,
};
use softrod::integrate::RodSystem;

use crate::control::{CableInputs, check_joint_forces, check_tensions};
use crate::convert::{mat_out, vec_out, vector};
use crate::errors::{dynamics, guard, input, to_py};
use crate::model::simulation_of;
use crate::results::{Energies, Modes, Statics};
use crate::settings::Settings;
use crate::trajectory::{State, Trajectory};

/// The index of rod `rod` (a name or an index) in `model`.
pub fn rod_index(model: &Model, rod: &Bound<'_, PyAny>) -> PyResult<usize> {
    let n = model.rods().len();
    if let Ok(name) = rod.cast::<PyString>() {
        let name = name.to_str()?;
        return model
            .rods()
            .iter()
            .position(|r| r.spec.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = model.rods().iter().map(|r| r.spec.name.as_str()).collect();
                input(format!("no rod {name:?} (rods: {names:?})"))
            });
    }
    let i: isize = rod
        .extract()
        .map_err(|_| input("rod must be a rod name or an index"))?;
    let k = if i < 0 { i + n as isize } else { i };
    if !(0..n as isize).contains(&k) {
        return Err(input(format!("rod index {i} out of range for {n} rods")));
    }
    Ok(k as usize)
}

/// A model with its initial state and run settings: the front door of
/// softrod from Python.
///
/// Build one from a scene file (`Simulation.from_file(path)`), scene text
/// (`Simulation.from_toml(text)`), a scene as dicts
/// (`Simulation.from_dict(scene)`) or rods
/// (`Simulation(rods=[softrod.Rod(...)], gravity=[0, 0, -9.81])`, with
/// `bodies=`, `closures=`, `obstacles=`, `contact=` tables as a scene has
/// them).
///
/// Conventions: SI units; `q` are the generalized coordinates in the order
/// of `q_names`: each element's joint coordinates, then a rod's strain
/// coordinates (pieces base to tip, selected strains in the canonical order
/// kx, ky, kz, qx, qy, qz), elements in the scene's order; `qdot`, `qddot`
/// their rates; a rod is named by its name or its index; prescribed joints
/// are not coordinates, they move with the time `t` each call takes (first
/// in the dynamics calls, `f(t, q, qdot)`; the keyword `t`, default 0, of
/// the kinematic queries); poses are world-frame 4×4
/// homogeneous transforms `[[R, p], [0, 1]]`; twists are 6-vectors, angular
/// part first. Vectors and matrices are float64 numpy arrays; inputs of the
/// wrong shape raise `softrod.InputError` (a `ValueError`) naming the
/// argument and both shapes. Evaluations (dynamics, kinematics) take a few
/// microseconds and keep the GIL; `simulate`, `step`, `statics` and
/// `modes` release it. A Simulation is used by one thread at a time (a
/// second concurrent call raises RuntimeError "Already borrowed"):
/// `copy()` it for others, or use `softrod.simulate_many`.
#[pyclass(module = "softrod")]
pub struct Simulation {
    pub(crate) sim: softrod::Simulation,
    warnings: Vec<String>,
    /// The scene's `[run] duration` [s] (None when built in Python).
    pub(crate) duration: Option<f64>,
    /// The model with tension inputs `u`, built on first use.
    inputs: Option<Box<CableInputs>>,
    /// The full model as an integrable system, for `step` without `u`.
    stepper: Option<Box<RodSystem>>,
    /// The scene text this simulation was built from (what a pickle holds).
    source: Option<std::sync::Arc<str>>,
}

impl Clone for Simulation {
    fn clone(&self) -> Self {
        Self {
            sim: self.sim.clone(),
            warnings: self.warnings.clone(),
            duration: self.duration,
            inputs: self.inputs.clone(),
            stepper: self.stepper.clone(),
            source: self.source.clone(),
        }
    }
}

impl Simulation {
    pub(crate) fn wrap(
        sim: softrod::Simulation,
        warnings: Vec<String>,
        duration: Option<f64>,
    ) -> Self {
        Self {
            sim,
            warnings,
            duration,
            inputs: None,
            stepper: None,
            source: None,
        }
    }

    /// The wrapper of a loaded scene (`from_toml`, `from_file`).
    fn from_loaded(
        loaded: softrod::Result<(
            softrod::Simulation,
            softrod::scene::Scene,
            Vec<softrod::scene::Warning>,
        )>,
    ) -> PyResult<Self> {
        let (sim, scene, warnings) = loaded.map_err(to_py)?;
        Ok(Self::wrap(
            sim,
            warnings.iter().map(|w| w.to_string()).collect(),
            Some(scene.run.duration),
        ))
    }

    fn n(&self) -> usize {
        self.sim.n_dof()
    }

    fn inputs(&mut self) -> PyResult<&mut CableInputs> {
        if self.inputs.is_none() {
            self.inputs = Some(Box::new(
                CableInputs::new(self.sim.model()).map_err(dynamics)?,
            ));
        }
        Ok(self.inputs.as_mut().expect("just set"))
    }

    /// Joint forces checked against the model's actuated joint coordinates.
    pub(crate) fn joint_forces(&mut self, f: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let nj = self.sim.model().n_joint_inputs();
        if nj == 0 {
            return Err(input(
                "joint_forces: this simulation has no actuated joint (a scene joint with \
                 `actuator = { force, max_force }`)",
            ));
        }
        let a = vector(f, "joint_forces", nj)?;
        check_joint_forces(&self.sim.joint_input_names(), "joint_forces", a.slice())
            .map_err(input)?;
        Ok(a.slice().to_vec())
    }

    /// Prescribed-joint targets checked against the model: one per
    /// prescribed coordinate, finite, within the scene's bounds.
    pub(crate) fn prescribed_targets_arg(&self, p: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let model = self.sim.model();
        let np = model.n_prescribed();
        if np == 0 {
            return Err(input(
                "prescribed_targets: this simulation has no prescribed joint (a scene joint \
                 with `prescribed = { times, values, bounds }`)",
            ));
        }
        let a = vector(p, "prescribed_targets", np)?;
        softrod::control::targets::check_prescribed_targets(
            model,
            &self.sim.prescribed_names(),
            "prescribed_targets",
            a.slice(),
        )
        .map_err(to_py)?;
        Ok(a.slice().to_vec())
    }

    /// Makes the steppers' copies of the model follow the prescribed
    /// curves in force on `sim`.
    pub(crate) fn sync_prescribed(&mut self) -> PyResult<()> {
        if self.sim.model().n_prescribed() == 0 {
            return Ok(());
        }
        let src = self.sim.model();
        use softrod::control::targets::copy_prescribed_curves;
        if let Some(i) = self.inputs.as_mut() {
            copy_prescribed_curves(src, &mut i.sys.model).map_err(to_py)?;
        }
        if let Some(s) = self.stepper.as_mut() {
            copy_prescribed_curves(src, &mut s.model).map_err(to_py)?;
        }
        Ok(())
    }

    /// `u` checked against the model's cables.
    fn tensions(&mut self, u: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let nc = self.sim.model().n_cables();
        let a = vector(u, "u", nc)?;
        check_tensions(nc, "u", a.slice()).map_err(input)?;
        Ok(a.slice().to_vec())
    }
}

#[pymethods]
impl Simulation {
    /// A simulation of `rods` (softrod.Rod, named rod0, rod1, … where they
    /// have no name) under `gravity` [m/s², world frame], with `quadrature`
    /// Gauss points per piece (4: the scene default), from the rest shape at
    /// rest, with the recommended settings.
    ///
    /// What a scene file says beyond rods, with its keys and defaults
    /// (docs/scene-format.md): `bodies`, `closures`, `obstacles` lists of
    /// `[[body]]`, `[[closure]]`, `[[obstacle]]` tables (dicts, or
    /// `softrod.Body(...)`, `softrod.Closure(...)`, `softrod.Obstacle(...)`),
    /// `contact` the `[contact]` table (`softrod.ContactSettings(...)`); a rod may
    /// also be a `[[rod]]` dict. The whole is then read as the scene would
    /// read it (`Simulation.from_dict`), the rods before the bodies in
    /// `q`; errors name the key path (`obstacle[0].radius`).
    #[new]
    #[pyo3(signature = (rods, gravity = None, *, quadrature = 4, bodies = None, closures = None,
                        obstacles = None, contact = None))]
    fn new(
        rods: &Bound<'_, PyList>,
        gravity: Option<&Bound<'_, PyAny>>,
        quadrature: usize,
        bodies: Option<&Bound<'_, PyAny>>,
        closures: Option<&Bound<'_, PyAny>>,
        obstacles: Option<&Bound<'_, PyAny>>,
        contact: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let extras = crate::scene_dict::Extras {
            bodies,
            closures,
            obstacles,
            contact,
        };
        guard(|| {
            let mut me = if crate::scene_dict::needs_scene(rods, &extras) {
                let (sim, warnings) =
                    crate::scene_dict::simulation_with(rods, gravity, quadrature, &extras)?;
                Self::wrap(sim, warnings, None)
            } else {
                Self::wrap(simulation_of(rods, gravity, quadrature)?, Vec::new(), None)
            };
            // The scene text of the same simulation, for pickling (the
            // scene loader builds the same model: tests/test_pickle.py).
            let g = match gravity {
                Some(g) => Some(crate::convert::vec3(g, "gravity")?),
                None => None,
            };
            me.source = crate::scene_dict::document(rods, g, quadrature, &extras)
                .ok()
                .map(|doc| crate::scene_dict::text(&doc).into());
            Ok(me)
        })
    }

    /// The simulation a scene given as nested dicts and lists describes,
    /// with the keys of the TOML file (docs/scene-format.md): `{"world":
    /// {"gravity": [...]}, "rod": [{...}], "body": [...], "closure": [...],
    /// "obstacle": [...], "contact": {...}, "cable": [...], "load": [...],
    /// "initial": {...}, "run": {...}}`. Read by the scene loader itself:
    /// the same defaults, checks and warnings as `from_toml` (None values
    /// are left out: the default). Rods and bodies enter `q` in the order
    /// of the dict's keys and lists. Numpy arrays, `softrod.Section` and
    /// `softrod.Material` objects may stand for their values. Errors raise
    /// `softrod.SceneError` naming `name` and the key path.
    #[classmethod]
    #[pyo3(signature = (scene, *, name = "<dict>"))]
    fn from_dict(
        _cls: &Bound<'_, pyo3::types::PyType>,
        scene: &Bound<'_, pyo3::types::PyDict>,
        name: &str,
    ) -> PyResult<Self> {
        guard(|| {
            let doc = crate::scene_dict::dict_document(scene)?;
            let (sim, warnings, duration) = crate::scene_dict::simulation(&doc, name)?;
            let mut me = Self::wrap(sim, warnings, Some(duration));
            me.source = Some(crate::scene_dict::text(&doc).into());
            Ok(me)
        })
    }

    /// The simulation the TOML scene text `text` describes
    /// (docs/scene-format.md): its model, `[initial]` state and `[run]`
    /// settings; `name` stands for the file in messages. Invalid scenes
    /// raise `softrod.SceneError` naming the file, line, column and key
    /// path; warnings are in `.warnings`. For a scene file, call
    /// `Simulation.from_file(path)`.
    #[classmethod]
    #[pyo3(signature = (text, *, name = "<string>"))]
    fn from_toml(
        _cls: &Bound<'_, pyo3::types::PyType>,
        text: &Bound<'_, PyAny>,
        name: &str,
    ) -> PyResult<Self> {
        guard(|| {
            let Ok(text) = text.cast::<PyString>() else {
                return Err(input(
                    "Simulation.from_toml takes the scene text (a str); for a scene file call \
                     Simulation.from_file(path)",
                ));
            };
            let text = text.to_str()?;
            if !text.contains('\n') && !text.contains('=') {
                return Err(input(format!(
                    "Simulation.from_toml takes the scene text, and {text:?} looks like a file \
                     path: call Simulation.from_file({text:?})"
                )));
            }
            let mut me = Self::from_loaded(softrod::Simulation::from_toml(text, name))?;
            me.source = Some(text.into());
            Ok(me)
        })
    }

    /// The simulation the TOML scene file at `path` (str or os.PathLike)
    /// describes; as `from_toml` otherwise.
    #[classmethod]
    fn from_file(
        _cls: &Bound<'_, pyo3::types::PyType>,
        path: std::path::PathBuf,
    ) -> PyResult<Self> {
        guard(|| {
            let mut me = Self::from_loaded(softrod::Simulation::from_scene_file(&path))?;
            me.source = std::fs::read_to_string(&path).ok().map(Into::into);
            Ok(me)
        })
    }

    /// Number of generalized coordinates.
    #[getter]
    fn n_dof(&self) -> usize {
        self.n()
    }

    /// Number of cables (the length of a tension input `u`).
    #[getter]
    fn n_cables(&self) -> usize {
        self.sim.model().n_cables()
    }

    /// Number of actuated joint coordinates (the length of a `joint_forces`
    /// input; docs/theory-control.md IS14): each joint with an actuator
    /// contributes its coordinates, elements in model order.
    #[getter]
    fn n_joint_inputs(&self) -> usize {
        self.sim.model().n_joint_inputs()
    }

    /// The bound `|f_i| ≤ max_force_i` [N or N·m] of each actuated joint
    /// coordinate (`n_joint_inputs` of them, in their order), from the
    /// scene's `actuator = { max_force }`; `inf` where none is given.
    #[getter]
    fn joint_max_forces(&self) -> Vec<f64> {
        let model = self.sim.model();
        model
            .elements()
            .iter()
            .filter_map(|e| {
                let j = &e.attachment.joint;
                j.actuator.as_ref().map(|a| {
                    (0..j.actuated_dof())
                        .map(|i| a.bound(i))
                        .collect::<Vec<_>>()
                })
            })
            .flatten()
            .collect()
    }

    /// Names of the actuated joint coordinates, in the order of
    /// `joint_forces` (`"<element>.joint.<c>"`, as in `q_names`).
    #[getter]
    fn joint_input_names(&self) -> Vec<String> {
        self.sim.joint_input_names()
    }

    /// Number of prescribed joint coordinates (the length of a
    /// `prescribed_targets` of `step`).
    #[getter]
    fn n_prescribed(&self) -> usize {
        self.sim.model().n_prescribed()
    }

    /// The target range `(lo, hi)` [rad or m] of each prescribed coordinate
    /// (`prescribed_names` order) from the scene's
    /// `joint.prescribed.bounds`, None where the scene gives none.
    #[getter]
    fn prescribed_bounds(&self) -> Vec<Option<(f64, f64)>> {
        self.sim
            .prescribed_bounds()
            .into_iter()
            .map(|b| b.map(|[lo, hi]| (lo, hi)))
            .collect()
    }

    /// The targets of the last `step(..., prescribed_targets=...)` in force
    /// (n_prescribed,) [rad or m], or None while the scene's prescribed
    /// curves are (before any, and after `reset_prescribed`).
    #[getter]
    fn prescribed_targets<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        let tr = self.sim.prescribed_transitions();
        if tr.is_empty() {
            return None;
        }
        let x: Vec<f64> = tr.iter().map(|t| t.x1).collect();
        Some(vec_out(py, &x))
    }

    /// The prescribed coordinates' values and rates at time `t` [s]
    /// under the motion in force (the scene's curves, or the transitions of
    /// the last `prescribed_targets`): `(x, xdot)`, each (n_prescribed,), in
    /// rad or m and per s.
    #[allow(clippy::type_complexity)]
    fn prescribed_state<'py>(
        &self,
        py: Python<'py>,
        t: f64,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        if !t.is_finite() {
            return Err(input(format!("t must be finite, got {t}")));
        }
        let m = self.sim.model();
        let (x, v): (Vec<f64>, Vec<f64>) = (0..m.n_prescribed())
            .map(|i| {
                let (x, v, _) = m.prescribed_curve(i).expect("i < n_prescribed").eval(t);
                (x, v)
            })
            .unzip();
        Ok((vec_out(py, &x), vec_out(py, &v)))
    }

    /// Commands the prescribed joints to `targets` (n_prescribed,) over
    /// `[t, t + dt]` without stepping, as `step(..., prescribed_targets=...)`
    /// does before it integrates: each coordinate then follows the cubic
    /// from its position and rate at `t` to its target at rest at `t + dt`
    /// (poses and runs see it). The batched vector env keeps each copy's
    /// own Simulation in line with its `BatchStepper` copy this way.
    fn command_prescribed(&mut self, t: f64, dt: f64, targets: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = self.prescribed_targets_arg(targets)?;
        self.sim.command_prescribed(t, dt, &p).map_err(to_py)?;
        self.sync_prescribed()
    }

    /// Holds the prescribed joints at `values` (n_prescribed,) [rad or m,
    /// within the scene's bounds] at rest at every time, until the next
    /// `step(..., prescribed_targets=...)` or `reset_prescribed()`: statics,
    /// poses and runs then see the drive there (e.g. a task drawing a
    /// reachable target: `sim.hold_prescribed(x); sim.statics(...)`).
    fn hold_prescribed(&mut self, values: &Bound<'_, PyAny>) -> PyResult<()> {
        let model = self.sim.model();
        let np = model.n_prescribed();
        if np == 0 {
            return Err(input(
                "values: this simulation has no prescribed joint (a scene joint with \
                 `prescribed = { times, values, bounds }`)",
            ));
        }
        let a = vector(values, "values", np)?;
        self.sim.hold_prescribed(a.slice()).map_err(to_py)?;
        self.sync_prescribed()
    }

    /// Puts the scene's prescribed curves back in force after
    /// `step(..., prescribed_targets=...)` commanded others: an episode
    /// that starts over calls it (the environments' `reset` does), as it
    /// calls `reset_contact`.
    fn reset_prescribed(&mut self) -> PyResult<()> {
        self.sim.reset_prescribed();
        self.sync_prescribed()
    }

    /// A name for every generalized coordinate, in the order of `q`:
    /// `"<rod>.p<piece>.<strain>"` (e.g. `"arm.p0.ky"`), a joint's
    /// coordinates `"<element>.joint.<c>"` first in its element's.
    #[getter]
    fn q_names(&self) -> Vec<String> {
        self.sim.q_names()
    }

    /// The loop closures' residuals at `q` [m] (docs/theory.md D66), a dict
    /// from closure name to `max(|d|, L|r|)`, prescribed joints at time `t`
    /// [s]; empty without closures.
    #[pyo3(signature = (q, *, t = 0.0))]
    fn closure_residuals(
        &mut self,
        q: &Bound<'_, PyAny>,
        t: f64,
    ) -> PyResult<std::collections::BTreeMap<String, f64>> {
        guard(|| {
            kinematics::check_time(t)?;
            let q = vector(q, "q", self.n())?;
            self.sim.set_time(t);
            let r = self.sim.closure_residuals(q.slice()).map_err(to_py)?;
            Ok(r.into_iter().collect())
        })
    }

    /// The names of the prescribed joint coordinates (D59), in the order
    /// of `prescribed_forces`; empty without prescribed joints.
    #[getter]
    fn prescribed_names(&self) -> Vec<String> {
        self.sim.prescribed_names()
    }

    /// The rigid bodies' names, in the order of `body_poses`.
    #[getter]
    fn body_names(&self) -> Vec<String> {
        self.sim
            .model()
            .bodies()
            .iter()
            .map(|b| b.spec.name.clone())
            .collect()
    }

    /// The obstacles' names, in the order of `Contact.other_index`.
    #[getter]
    fn obstacle_names(&self) -> Vec<String> {
        self.sim
            .model()
            .obstacles()
            .iter()
            .map(|o| o.name.clone())
            .collect()
    }

    /// The active contacts at `(t, q, qdot)` with their forces
    /// (docs/theory-contact.md), a list of `softrod.Contact`; empty for a
    /// model without contact. The forces are those of the contact state
    /// this simulation holds (CT5, CT15): the stiffness scales its last
    /// `statics()` (without `loads`) raised or its last `simulate` (without
    /// `simulate` or `step` committed, and their friction anchors. Before
    /// any, the base stiffness of CT3 and no friction history (friction
    /// zero: the normal forces are the whole force). The forces of a run's
    /// samples are in `Trajectory.contacts`.
    #[pyo3(signature = (q, qdot = None, *, t = 0.0))]
    fn contacts(
        &mut self,
        q: &Bound<'_, PyAny>,
        qdot: Option<&Bound<'_, PyAny>>,
        t: f64,
    ) -> PyResult<Vec<crate::contacts::Contact>> {
        guard(|| {
            kinematics::check_time(t)?;
            let n = self.n();
            let q = vector(q, "q", n)?;
            let qd = match qdot {
                Some(v) => vector(v, "qdot", n)?.slice().to_vec(),
                None => vec![0.0; n],
            };
            let c = self
                .sim
                .contacts(t, q.slice(), &qd)
                .map_err(crate::errors::to_py)?;
            Ok(crate::contacts::Contact::list(self.sim.model(), &c))
        })
    }

    /// Forgets the contact state this simulation holds (the friction
    /// anchors and raised stiffnesses the last `simulate`, `statics` or
    /// `step` committed, docs/theory-contact.md CT5, CT15): the next `step`
    /// or `contacts` sees the base stiffness and no friction history, as
    /// on a new simulation. `simulate` and `statics` start fresh by
    /// themselves; a loop of `step`s from an initial state (an episode)
    /// calls this first. Nothing for a model without contact.
    fn reset_contact(&mut self) {
        self.sim.reset_contact();
    }

    /// The largest penetration `−gap` [m] of any contact at `q` (time `t`
    /// for prescribed joints and carried obstacles), 0 if none: geometry
    /// alone, the same whatever contact stiffness or friction state the
    /// simulation holds.
    #[pyo3(signature = (q, *, t = 0.0))]
    fn max_penetration(&self, q: &Bound<'_, PyAny>, t: f64) -> PyResult<f64> {
        guard(|| {
            kinematics::check_time(t)?;
            let q = vector(q, "q", self.n())?;
            self.sim
                .model()
                .max_penetration(t, q.slice())
                .map_err(dynamics)
        })
    }

    /// The generalized forces [N·m or N] the prescribed joints' drives
    /// apply at `(t, q, qdot)` (D60), in the order of `prescribed_names`.
    #[pyo3(signature = (t, q, qdot))]
    fn prescribed_forces<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        guard(|| {
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            let f = self
                .sim
                .prescribed_forces(t, q.slice(), qd.slice(), None)
                .map_err(to_py)?;
            Ok(vec_out(py, f.as_slice()))
        })
    }

    /// The scene's `[run] duration` [s], the default of `simulate`; None
    /// for a simulation built in Python.
    #[getter]
    fn duration(&self) -> Option<f64> {
        self.duration
    }

    /// Rod lengths L [m], in model order.
    #[getter]
    fn rod_lengths(&self) -> Vec<f64> {
        self.sim
            .model()
            .rods()
            .iter()
            .map(|r| r.spec.geometry.length())
            .collect()
    }

    /// Rod names, in model order.
    #[getter]
    fn rod_names(&self) -> Vec<String> {
        self.sim
            .model()
            .rods()
            .iter()
            .map(|r| r.spec.name.clone())
            .collect()
    }

    /// The coordinates of each rod: {name: (first index, count)}.
    #[getter]
    fn rod_dofs(&self) -> Vec<(String, usize, usize)> {
        self.sim
            .model()
            .rods()
            .iter()
            .map(|r| (r.spec.name.clone(), r.dof_offset, r.n_dof()))
            .collect()
    }

    /// Names of the force terms present ("inertia", "elasticity", "gravity", …).
    #[getter]
    fn terms(&self) -> Vec<String> {
        self.sim.model().terms()
    }

    /// The scene's warnings (suspicious but legal input).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// World gravity [m/s²] (zeros when absent).
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let g = self.sim.model().gravity().unwrap_or_default();
        vec_out(py, g.as_slice())
    }

    /// The run settings (a copy; assign a `softrod.Settings` to change them).
    #[getter]
    fn get_settings(&self) -> Settings {
        Settings {
            inner: self.sim.settings().clone(),
        }
    }

    #[setter]
    fn set_settings(&mut self, settings: Settings) -> PyResult<()> {
        self.sim.set_settings(settings.inner).map_err(to_py)
    }

    /// Initial coordinates and velocities `(q, qdot)`.
    fn initial_state<'py>(
        &self,
        py: Python<'py>,
    ) -> (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>) {
        let (q, qd) = self.sim.initial_state();
        (vec_out(py, q.as_slice()), vec_out(py, qd.as_slice()))
    }

    /// Sets the initial state (each (n_dof,)).
    fn set_initial_state(&mut self, q: &Bound<'_, PyAny>, qdot: &Bound<'_, PyAny>) -> PyResult<()> {
        let n = self.n();
        let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
        self.sim
            .set_initial_state(q.slice(), qd.slice())
            .map_err(to_py)
    }

    /// The initial state as a `softrod.State` at t = 0, to start the step API.
    fn initial(&self, py: Python<'_>) -> PyResult<State> {
        let (q, qd) = self.sim.initial_state();
        State::from_slices(py, 0.0, q.as_slice(), qd.as_slice())
    }

    /// World pose of rod `rod` (name or index) at abscissa `s` [m] for
    /// coordinates `q` (D7), prescribed joints at time `t` [s]: a 4×4
    /// homogeneous transform, or (len(s), 4, 4) for a 1-D array of
    /// abscissae (one kinematic sweep for all).
    #[pyo3(signature = (rod, s, q, *, t = 0.0))]
    fn pose<'py>(
        &mut self,
        py: Python<'py>,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| self.pose_py(py, t, rod, s, q))
    }

    /// Tip pose of rod `rod` for `q` (4×4, world frame), prescribed joints
    /// at time `t` [s].
    #[pyo3(signature = (rod, q, *, t = 0.0))]
    fn tip_pose<'py>(
        &mut self,
        py: Python<'py>,
        rod: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| {
            let i = rod_index(self.sim.model(), rod)?;
            let poses = self.world_poses(t, q)?;
            let mut out = vec![0.0; 16];
            crate::convert::pose_into(poses.tip(i), &mut out);
            crate::convert::array_out(py, out, &[4, 4])
        })
    }

    /// World poses (n_bodies, 4, 4) of the rigid bodies' frames for `q`, in
    /// the scene's order (D51), prescribed joints at time `t` [s]; shape
    /// (0, 4, 4) without bodies.
    #[pyo3(signature = (q, *, t = 0.0))]
    fn body_poses<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        t: f64,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| {
            let poses = self.world_poses(t, q)?;
            let bodies = poses.bodies();
            let mut out = vec![0.0; 16 * bodies.len()];
            for (g, o) in bodies.iter().zip(out.chunks_mut(16)) {
                crate::convert::pose_into(g, o);
            }
            crate::convert::array_out(py, out, &[bodies.len(), 4, 4])
        })
    }

    /// Geometric Jacobian J(s) (6, n_dof) of rod `rod` at `s` for `q`: the
    /// twist of the section is J q̇, angular part first (D11). `frame`:
    /// "body" (the section's own frame) or "world" (spatial twist). Every
    /// coordinate that moves the section has its column: the rod's pieces
    /// up to `s` and, on a robot, its joint's and its parents'; the others
    /// are zero. For a 1-D array `s`: (len(s), 6, n_dof). Prescribed joints
    /// at time `t` [s].
    #[pyo3(signature = (rod, s, q, frame = "body", *, t = 0.0))]
    fn jacobian<'py>(
        &mut self,
        py: Python<'py>,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        frame: &str,
        t: f64,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| self.jacobian_py(py, t, rod, s, q, frame))
    }

    /// Forward dynamics q̈ (n_dof,) at time `t` [s], coordinates `q`,
    /// velocities `qdot`, under the actuator generalized force `tau` (n_dof,
    /// default 0), by the O(N) articulated recursion (D23–D27). `u`
    /// (n_cables,) [N]: cable tensions replacing the scheduled ones (then
    /// the cables act as `A(q) u`, see `actuation_matrix`).
    #[pyo3(signature = (t, q, qdot, tau = None, *, u = None))]
    fn forward_dynamics<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        tau: Option<&Bound<'py, PyAny>>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.forward_dynamics_impl(py, t, q, qdot, tau, u)
    }

    /// Inverse dynamics: the actuator force τ_act (n_dof,) that gives
    /// `qddot` at `(t, q, qdot)` (D17–D18), with the scheduled cable
    /// tensions, or with tensions `u` when given (then τ_act is what is
    /// needed besides `A(q) u`).
    #[pyo3(signature = (t, q, qdot, qddot, *, u = None))]
    fn inverse_dynamics<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        qddot: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.inverse_dynamics_impl(py, t, q, qdot, qddot, u)
    }

    /// Mass matrix M(t, q) (n_dof, n_dof), symmetric positive definite
    /// (D19–D20); `t` [s] moves the prescribed joints.
    fn mass_matrix<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guard(|| {
            kinematics::check_time(t)?;
            let q = vector(q, "q", self.n())?;
            self.sim.set_time(t);
            let m = self.sim.mass_matrix(q.slice()).map_err(to_py)?;
            Ok(mat_out(py, &m))
        })
    }

    /// The bias b(t, q, q̇) = C q̇ + G + K(q) + D q̇ − τ_cables − Q_ext
    /// (n_dof,): the equations of motion read M q̈ + b = τ_act (D21–D22);
    /// with loop closures M q̈ + b = τ_act + Jᵀλ (b is the open tree's).
    fn bias_force<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        guard(|| {
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            let b = self
                .sim
                .bias_force(t, q.slice(), qd.slice())
                .map_err(to_py)?;
            Ok(vec_out(py, b.as_slice()))
        })
    }

    /// Coriolis/centrifugal matrix C(q, q̇) (n_dof, n_dof) with Ṁ − 2C
    /// skew-symmetric (D21); O(N·n_dof²), for analysis and control.
    fn coriolis_matrix<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guard(|| {
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            let c = coriolis_matrix(self.sim.model(), q.slice(), qd.slice()).map_err(dynamics)?;
            Ok(mat_out(py, &c))
        })
    }

    /// The Coriolis/centrifugal force C(q, q̇) q̇ (n_dof,).
    fn coriolis_force<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        self.coriolis_force_impl(py, q, qdot)
    }

    /// Generalized gravity G(t, q) = ∂V_g/∂q (n_dof,) (D22); zero without
    /// gravity.
    fn gravity_force<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        guard(|| {
            kinematics::check_time(t)?;
            let q = vector(q, "q", self.n())?;
            self.sim.set_time(t);
            let g = self.sim.gravity_force(q.slice()).map_err(to_py)?;
            Ok(vec_out(py, g.as_slice()))
        })
    }

    /// Generalized stiffness K = diag(K_n) (n_dof, n_dof), constant (D13).
    fn stiffness_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_out(py, &stiffness_matrix(self.sim.model()))
    }

    /// Generalized damping D = diag(D_n) (n_dof, n_dof), constant (D13).
    fn damping_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_out(py, &damping_matrix(self.sim.model()))
    }

    /// Actuation matrix A(q) (n_dof, n_cables): column c is the generalized
    /// force of cable c per newton of tension, −∂ℓ_c/∂q (D15).
    fn actuation_matrix<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guard(|| {
            let q = vector(q, "q", self.n())?;
            let a: DMatrix<f64> =
                actuation_matrix(self.sim.model(), q.slice()).map_err(dynamics)?;
            Ok(mat_out(py, &a))
        })
    }

    /// Linearization of `x' = f(x, u)`, `x = (q, qdot)`, about `(t, q, qdot)`
    /// and the cable tensions `u` (n_cables,) [N] (default: the scheduled
    /// tensions at `t`), from the analytic derivatives of the dynamics
    /// (theory-derivatives.md): returns `(A, B)`, `A = df/dx`
    /// (2 n_dof, 2 n_dof) = `[[0, I], [dqdd/dq, dqdd/dqdot]]`,
    /// `B = df/du` (2 n_dof, n_cables) [per N]. Rows and columns of `A`
    /// are `q` then `qdot` in the order of `q_names`. What LQR, MPC and
    /// trajectory optimization need; about a static equilibrium use
    /// `statics().q` and zero velocities.
    #[pyo3(signature = (t, q, qdot, *, u = None))]
    #[allow(clippy::type_complexity)]
    fn linearize<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
        self.linearize_impl(py, t, q, qdot, u)
    }

    /// Kinetic, elastic and gravitational energy at `(t, q, qdot)` [J];
    /// with prescribed joints the kinetic energy includes their motion at
    /// `t`.
    fn energies(
        &mut self,
        t: f64,
        q: &Bound<'_, PyAny>,
        qdot: &Bound<'_, PyAny>,
    ) -> PyResult<Energies> {
        guard(|| {
            kinematics::check_time(t)?;
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            self.sim.set_time(t);
            let e = self.sim.energies(q.slice(), qd.slice()).map_err(to_py)?;
            Ok(Energies::from(&e))
        })
    }

    /// Whether the model has static loads (gravity, loads, cables): then its
    /// equilibrium differs from the rest shape.
    #[getter]
    fn has_static_loads(&self) -> bool {
        self.sim.has_static_loads()
    }

    /// Static equilibrium under every static term at t = 0, from the initial
    /// q (Newton with line search and load continuation), with what
    /// `softrod statics --json` reports beside it (`softrod.Statics`: tip and
    /// body poses, closure residuals, stability, warnings). Raises
    /// `softrod.SimulationError` when it does not converge. Releases the GIL.
    ///
    /// For actuation and load studies without editing the scene:
    /// `tensions` (n_cables,) [N, ≥ 0] replace the cables' schedules for
    /// this solve; `loads`, a list of `(rod, softrod.PointLoad)` pairs (rod
    /// a name or an index), are added to the model's loads for this solve;
    /// `joint_forces` (n_joint_inputs,) [N or N·m] replace the joint
    /// actuators' schedules for this solve (IS14).
    #[pyo3(signature = (*, tensions=None, loads=None, joint_forces=None))]
    fn statics(
        &mut self,
        py: Python<'_>,
        tensions: Option<&Bound<'_, PyAny>>,
        loads: Option<&Bound<'_, PyAny>>,
        joint_forces: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Statics> {
        self.statics_impl(py, tensions, loads, joint_forces)
    }

    /// Inverse statics (docs/theory-control.md IS1–IS14): the cable tensions
    /// `0 ≤ T ≤ max_tension` [N], the forces of the joints with an actuator
    /// (`|f| ≤ max_force`, N or N·m, IS14) and of the unknown point loads
    /// (IS13), and the static equilibrium (with loop
    /// closures, the constrained one) that bring rod sections or body frames
    /// closest to `targets`, the least effort among equally close ones.
    /// `targets`: a list of dicts `{"rod": name or index (default 0), "s":
    /// arc length [m] (default the tip), "position": (3,) [m, world],
    /// "rotation": (3, 3) section → world, "weight": > 0 (default 1)}`, or,
    /// for a rigid body's frame (origin and axes, as `Statics` reports its
    /// pose), `{"body": name or index, "position", "rotation", "weight"}`
    /// (no "rod" or "s"), each with a position, a rotation or both. `max_tension`: one number for
    /// every cable or one per cable (default none). `effort_weight`: the
    /// relative weight ρ of the effort term. `warm_start`: a previous result
    /// (its tensions and q start the search: a target that moved a little
    /// costs a few iterations). `unknown_loads`: point forces to solve for, a
    /// list of dicts `{"rod": name or index, "s": [m] (default the tip),
    /// "max_force": one bound for |f_x|, |f_y|, |f_z| or three [N] (default
    /// none)}`; default the scene's `[[load]]`s with `unknown = true`
    /// (`[]`: none). Returns a dict: `converged`, `reached`,
    /// `message`, `tensions`, `q`, `bounds` ("free", "lower", "upper" per
    /// cable), `forces` ((n_u, 3) world forces of the unknown loads [N]),
    /// `force_bounds` (per load three bound names), `joint_forces` (one per
    /// actuated joint coordinate, elements in order [N or N·m]),
    /// `joint_force_bounds`, `residual` (weighted target error), `targets` (per target:
    /// reached `position`, `rotation`, `position_error`, `rotation_error`),
    /// `iterations`, `statics_iterations`, `cost`, `effort_weight`. A target
    /// out of reach returns the closest reachable shape with `reached`
    /// False. Bad input raises `softrod.InputError`; an iteration that does
    /// not converge raises `softrod.SimulationError` with its residual.
    /// Releases the GIL.
    #[pyo3(signature = (targets, *, max_tension=None, effort_weight=1e-9, reach_tolerance=1e-6, max_iterations=100, warm_start=None, t=0.0, unknown_loads=None))]
    #[allow(clippy::too_many_arguments)]
    fn solve_actuation<'py>(
        &mut self,
        py: Python<'py>,
        targets: &Bound<'py, PyAny>,
        max_tension: Option<&Bound<'py, PyAny>>,
        effort_weight: f64,
        reach_tolerance: f64,
        max_iterations: usize,
        warm_start: Option<&Bound<'py, pyo3::types::PyDict>>,
        t: f64,
        unknown_loads: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let settings = actuation::Settings {
            max_tension,
            effort_weight,
            reach_tolerance,
            max_iterations,
            warm_start,
            t,
            unknown_loads,
        };
        self.solve_actuation_impl(py, targets, settings)
    }

    /// The loss `L` of a run of `duration` seconds (default the scene's)
    /// from the initial state and its exact gradient with respect to
    /// `params` (docs/theory-control.md G1–G9): returns `(value, {param:
    /// gradient})`, the shape `scipy.optimize.minimize(jac=True)` takes.
    /// `params`: names among `"q0"`, `"qdot0"` (arrays of n_dof),
    /// `"ROD.young"`, `"ROD.shear_modulus"`, `"ROD.density"`,
    /// `"ROD.viscosity"`, `"BODY.mass"` (floats), `"cableN.tension"` (an
    /// array, one entry per value of the tension table),
    /// `"ELEMENT.prescribed"` (the samples of the prescribed joint of rod or
    /// body ELEMENT, in the shape of its `values`: `(samples,)` for one
    /// coordinate, `(samples, dof)` for more; G17–G20, G28),
    /// `"ELEMENT.actuator"` (the force values of the actuator on ELEMENT's
    /// joint, a table shaped as its `values`, a constant as `(dof,)`;
    /// G29). `loss`: a dict or a
    /// list of dicts — `{"type": "position", "rod": name or index, "s":
    /// arc length (default the tip), "times": (k,), "targets": (k, 3) [m],
    /// "weight": w}` for `½ w ‖p(t) − target‖²`, `{"type": "quadratic",
    /// "times", "q_weights", "qdot_weights" (number or (n_dof,)), "q_ref"}`
    /// for `½ Σ wq (q − q_ref)² + wv q̇²` — or a callable
    /// `l(t, q, qdot) -> (value, dl_dq, dl_dqdot)` evaluated at `times`.
    /// The gradient is the discrete adjoint of the run (`esdirk`, `esdirk5`
    /// or `radau5`, the scene's integrator; its step
    /// sequence held fixed; the steps end on every loss time): exact for
    /// the computed trajectory to round-off and the Newton tolerance
    /// (`newton_tol`). `fixed_step`: fixed steps of that size (one step
    /// sequence whatever the parameters). Bad input raises
    /// `softrod.InputError` naming the parameter or loss key. Holds the GIL
    /// (a callable loss is called during the run). `method`: `"adjoint"`
    /// (default; cost independent of the number of parameters) or
    /// `"forward"` (forward sensitivities, G21: for few parameters on small
    /// models; the same gradient to round-off).
    #[pyo3(signature = (loss, params, duration = None, *, times = None, fixed_step = None, newton_tol = None, method = None))]
    #[allow(clippy::too_many_arguments)]
    fn value_and_gradient<'py>(
        &mut self,
        py: Python<'py>,
        loss: &Bound<'py, PyAny>,
        params: Vec<String>,
        duration: Option<f64>,
        times: Option<Bound<'py, PyAny>>,
        fixed_step: Option<f64>,
        newton_tol: Option<f64>,
        method: Option<String>,
    ) -> PyResult<(f64, Bound<'py, pyo3::types::PyDict>)> {
        let method = match method.as_deref() {
            None | Some("adjoint") => softrod::GradientMethod::Adjoint,
            Some("forward") => softrod::GradientMethod::Forward,
            Some(other) => {
                return Err(input(format!(
                    "method: '{other}' is not a gradient method (adjoint, forward)"
                )));
            }
        };
        let options = softrod::GradientOptions {
            fixed_step,
            newton_tol,
            method,
        };
        self.value_and_gradient_impl(py, loss, params, duration, times, options)
    }

    /// Undamped natural modes about the static equilibrium (the rest shape
    /// when the model has no static loads). Releases the GIL.
    fn modes(&mut self, py: Python<'_>) -> PyResult<Modes> {
        self.modes_impl(py)
    }

    /// The `count` lowest undamped modes about the static equilibrium (the
    /// rest shape without static loads), lowest first: the same modes as
    /// `modes()`, but open models of at least 160 coordinates whose joints
    /// all have springs are solved without dense matrices (shift-invert
    /// Lanczos, docs/theory.md E11), so thousands of pieces take a second.
    /// Releases the GIL.
    #[pyo3(signature = (count = 10))]
    fn lowest_modes(&mut self, py: Python<'_>, count: usize) -> PyResult<Modes> {
        self.lowest_modes_impl(py, count)
    }

    /// Undamped natural modes of the model linearized about `q` (which
    /// should be an equilibrium). Releases the GIL.
    fn modes_about(&mut self, py: Python<'_>, q: &Bound<'_, PyAny>) -> PyResult<Modes> {
        self.modes_about_impl(py, q)
    }

    /// Integrates `duration` seconds (default: the scene's `[run]
    /// duration`) and returns a `softrod.Trajectory`.
    ///
    /// Keywords override the run settings for this call only:
    /// `integrator`, `rtol`, `atol`, `dt`, `output_every`, `error_control`,
    /// `linearly_implicit`, `steps_to_outputs`, `project_closures` (see `softrod.Settings`); `q0`, `qdot0`
    /// (n_dof,) override the initial state.
    ///
    /// Without `controller` this is the facade's `Simulation::simulate`,
    /// the same integration as `softrod run` (same samples, same bits), with
    /// the GIL released throughout.
    ///
    /// `controller(t, q, qdot) -> u`: cable tensions (n_cables,) [N, ≥ 0]
    /// that replace the scheduled ones, held constant between calls (a
    /// zero-order hold): it is called at t = 0 and then after every
    /// accepted integrator step (`control_every=None`), or every
    /// `control_every` seconds (the run is then integrated in segments of
    /// that length, so the hold is exact whatever the integrator does).
    /// Each call re-takes the GIL and costs the Python function plus
    /// about 2–3 µs of crossing (docs/performance.md, "Python"); with
    /// `control_every=None` it runs once per integrator step, so a stiff
    /// adaptive run of 1 s with ~500 steps pays it ~500 times. An exception
    /// raised by the controller ends the run and propagates.
    #[pyo3(signature = (duration = None, *, output_every = None, integrator = None, rtol = None,
                        atol = None, dt = None, error_control = None, linearly_implicit = None,
                        steps_to_outputs = None, project_closures = None, q0 = None, qdot0 = None, controller = None,
                        control_every = None))]
    #[allow(clippy::too_many_arguments)]
    fn simulate(
        &mut self,
        py: Python<'_>,
        duration: Option<f64>,
        output_every: Option<f64>,
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        dt: Option<f64>,
        error_control: Option<bool>,
        linearly_implicit: Option<bool>,
        steps_to_outputs: Option<bool>,
        project_closures: Option<bool>,
        q0: Option<&Bound<'_, PyAny>>,
        qdot0: Option<&Bound<'_, PyAny>>,
        controller: Option<Py<PyAny>>,
        control_every: Option<f64>,
    ) -> PyResult<Trajectory> {
        let mut settings = self.sim.settings().clone();
        crate::settings::overrides(
            &mut settings,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            error_control,
            linearly_implicit,
            steps_to_outputs,
            project_closures,
        )?;
        let start = run::RunStart {
            q0,
            qdot0,
            controller,
            control_every,
        };
        self.simulate_impl(py, duration, settings, start)
    }

    /// One step of `dt` seconds from `state` (a `softrod.State`), with the
    /// run settings' integrator, returning the state at `state.t + dt`.
    /// `u` (n_cables,) [N]: cable tensions held over the step (replacing
    /// the scheduled ones); None: the scheduled tensions. `joint_forces`
    /// (n_joint_inputs,) [N or N·m, finite]: the joint actuators' forces
    /// held over the step (docs/theory-control.md IS14, replacing their
    /// schedules); None: the schedules. For RL and MPC
    /// loops: `state = sim.step(state, 1e-3, u)`. Each call starts the
    /// integrator afresh (first step `settings.dt`, capped at `dt`), so a
    /// loop of steps equals `simulate(controller=…, control_every=dt)`.
    /// `substeps` (an int k ≥ 1): instead of adapting, take k fixed steps
    /// of `dt / k` with the settings' integrator (an implicit method halves
    /// a step whose Newton iteration fails; rtol and atol then only weight
    /// its Newton test): a fixed cost per call, at an accuracy the caller
    /// must check (docs/envs.md, "Integration"). Releases the GIL.
    ///
    /// Contact: a step continues from the contact state this simulation
    /// holds (friction anchors and raised stiffnesses, docs/theory-contact.md
    /// CT5, CT15, left by the last `simulate`, `statics` or `step`) and
    /// commits its own after each accepted internal step, as `simulate`
    /// does — so friction sticks, and a contact deeper than the CT15 bound
    /// raises `SimulationError`. A loop of steps that starts an episode
    /// from an initial state calls `reset_contact()` first (the
    /// environments' `reset` does).
    ///
    /// `prescribed_targets` (n_prescribed,) [rad or m, finite, within the
    /// scene's `joint.prescribed.bounds` where given]: the prescribed
    /// joints' targets for `state.t + dt`. Each prescribed coordinate then
    /// follows the cubic from its position and rate at `state.t` (under the
    /// motion in force: the scene's curve, or the previous target's
    /// transition) to its target, reached at rest at `state.t + dt` and
    /// held there (C¹ across periods; docs/envs.md, "Actions"). The
    /// transition stays in force for this simulation's evaluations and
    /// runs until the next command or `reset_prescribed()`. None: the
    /// motion in force goes on. Errors name the coordinate
    /// (`prescribed_names`).
    #[pyo3(signature = (state, dt, u = None, *, substeps = None, joint_forces = None,
                        prescribed_targets = None))]
    #[allow(clippy::too_many_arguments)]
    fn step(
        &mut self,
        py: Python<'_>,
        state: PyRef<'_, State>,
        dt: f64,
        u: Option<&Bound<'_, PyAny>>,
        substeps: Option<usize>,
        joint_forces: Option<&Bound<'_, PyAny>>,
        prescribed_targets: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<State> {
        self.step_impl(py, state, dt, u, substeps, joint_forces, prescribed_targets)
    }

    /// An independent copy (its own buffers), e.g. for another thread.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __copy__(&self) -> Self {
        self.clone()
    }

    fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
        self.clone()
    }

    /// Pickling (Ray, multiprocessing): the scene text the simulation was
    /// built from, its settings, initial state, the tensions and joint
    /// forces `step` last held, the prescribed-joint transitions in force,
    /// its duration and warnings — plain values; loading rebuilds the
    /// model by the scene loader, so a loaded copy steps and simulates bit
    /// for bit as the original. A Simulation not built from a scene
    /// raises TypeError.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
        self.reduce(py)
    }

    /// The simulation a pickle's state dict describes (`__reduce__`).
    #[staticmethod]
    fn _from_state(state: &Bound<'_, pyo3::types::PyDict>) -> PyResult<Self> {
        guard(|| Self::from_state(state))
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation(rods={:?}, n_dof={}, terms={:?})",
            self.rod_names(),
            self.n(),
            self.terms()
        )
    }
}
