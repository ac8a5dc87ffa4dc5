//! `softrod.Simulation`: the facade's `Simulation` with numpy in and out.

use std::str::FromStr;

use nalgebra::{DMatrix, DVector, Matrix6xX};
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyString};
use softrod::dynamics::{
    Model, actuation_matrix, coriolis_matrix, damping_matrix, stiffness_matrix,
};
use softrod::integrate::RodSystem;
use softrod::kinematics::{Frame, RodKinematics};
use softrod::lie::Pose;
use softrod::scene::Integrator;
use softrod::{Equilibrium, Settings as RustSettings};

use crate::control::{CableInputs, ControlError, check_tensions, simulate_controlled, step};
use crate::convert::{array, array_out, mat_out, pose_into, vec_out, vector};
use crate::errors::{dynamics, guard, guard_detached, input, integrate, simulation, to_py};
use crate::model::{Rod, build_model};
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

/// Run settings: integrator, tolerances, steps and output spacing.
///
/// `integrator`: "esdirk" (the default: stiff, adaptive, error controlled,
/// Newton on the exact Jacobian), "radau5" (Radau IIA order 5, faster on
/// small models at tight tolerances), "rosenbrock" (linearly implicit,
/// adaptive), "dopri5" (explicit adaptive), "rk4" (explicit, fixed `dt`)
/// or "generalized-alpha" (implicit, fixed `dt`; with `error_control` the
/// step adapts to `rtol`/`atol`; with `linearly_implicit` one Newton
/// iteration per step, the fast IMEX scheme). `rtol`, `atol`: tolerances
/// of the adaptive methods; setting `rtol` alone also lowers `atol` to it
/// if `atol` was larger, so that the error tracks `rtol`. `dt` [s]: step of the fixed-step methods, first
/// step of the adaptive ones. `output_every` [s]: spacing of the samples
/// (None: a thousandth of the duration). Defaults: `softrod.Settings()`,
/// the recommended setting of docs/defaults.md.
#[pyclass(module = "softrod", from_py_object)]
#[derive(Clone)]
pub struct Settings {
    pub(crate) inner: RustSettings,
}

fn integrator(name: &str) -> PyResult<Integrator> {
    Integrator::from_str(name).map_err(|e| input(format!("integrator: {e}")))
}

/// Applies the keyword overrides of `Settings(...)` and `simulate(...)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn overrides(
    s: &mut RustSettings,
    integrator_name: Option<&str>,
    rtol: Option<f64>,
    atol: Option<f64>,
    dt: Option<f64>,
    output_every: Option<f64>,
    error_control: Option<bool>,
    linearly_implicit: Option<bool>,
) -> PyResult<()> {
    if let Some(i) = integrator_name {
        s.integrator = integrator(i)?;
    }
    if let Some(v) = rtol {
        *s = s.clone().with_rtol(v);
    }
    if let Some(v) = atol {
        s.atol = v;
    }
    if let Some(v) = dt {
        s.dt = v;
    }
    if let Some(v) = output_every {
        s.output_every = Some(v);
    }
    if let Some(v) = error_control {
        s.error_control = v;
    }
    if let Some(v) = linearly_implicit {
        s.linearly_implicit = v;
    }
    s.validate().map_err(to_py)
}

#[pymethods]
impl Settings {
    #[new]
    #[pyo3(signature = (integrator = None, rtol = None, atol = None, dt = None, output_every = None,
                        error_control = None, linearly_implicit = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        integrator: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        dt: Option<f64>,
        output_every: Option<f64>,
        error_control: Option<bool>,
        linearly_implicit: Option<bool>,
    ) -> PyResult<Self> {
        let mut inner = RustSettings {
            output_every: None,
            ..RustSettings::default()
        };
        overrides(
            &mut inner,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            error_control,
            linearly_implicit,
        )?;
        Ok(Self { inner })
    }

    /// The integrator's name.
    #[getter]
    fn integrator(&self) -> &'static str {
        self.inner.integrator.name()
    }

    /// Relative tolerance (adaptive methods).
    #[getter]
    fn rtol(&self) -> f64 {
        self.inner.rtol
    }

    /// Absolute tolerance (adaptive methods; units of q, q̇).
    #[getter]
    fn atol(&self) -> f64 {
        self.inner.atol
    }

    /// Fixed step / first adaptive step [s].
    #[getter]
    fn dt(&self) -> f64 {
        self.inner.dt
    }

    /// Sample spacing [s], or None (a thousandth of the duration).
    #[getter]
    fn output_every(&self) -> Option<f64> {
        self.inner.output_every
    }

    /// Generalized-α only: adapt the step to rtol/atol.
    #[getter]
    fn error_control(&self) -> bool {
        self.inner.error_control
    }

    /// Generalized-α only: one Newton iteration per step (IMEX).
    #[getter]
    fn linearly_implicit(&self) -> bool {
        self.inner.linearly_implicit
    }

    fn __repr__(&self) -> String {
        let s = &self.inner;
        format!(
            "Settings(integrator={:?}, rtol={:?}, atol={:?}, dt={:?}, output_every={}, \
             error_control={}, linearly_implicit={})",
            s.integrator.name(),
            s.rtol,
            s.atol,
            s.dt,
            s.output_every.map_or("None".into(), |v| format!("{v:?}")),
            if s.error_control { "True" } else { "False" },
            if s.linearly_implicit { "True" } else { "False" },
        )
    }
}

/// Kinetic, elastic and gravitational energy [J] at one state.
#[pyclass(frozen, module = "softrod", get_all)]
pub struct Energies {
    /// ½ q̇ᵀ M q̇; with prescribed joints it includes their motion (then
    /// it is the kinetic energy of the whole model, not ½ q̇ᵀ M q̇).
    kinetic: f64,
    /// ½ Σ ∫ (ξ − ξ*)ᵀ Γ (ξ − ξ*) ds.
    elastic: f64,
    /// −∫ ρA g·p ds (0 without gravity).
    gravitational: f64,
    /// The sum.
    total: f64,
}

#[pymethods]
impl Energies {
    fn __repr__(&self) -> String {
        format!(
            "Energies(kinetic={:?}, elastic={:?}, gravitational={:?}, total={:?})",
            self.kinetic, self.elastic, self.gravitational, self.total
        )
    }
}

/// A static equilibrium: `q` (n_dof,), Newton `iterations`, final
/// `residual` (max-abs generalized force [N or N·m]) and the number of
/// `load_steps` of the load continuation.
#[pyclass(frozen, module = "softrod")]
pub struct Statics {
    q: Py<PyArray1<f64>>,
    #[pyo3(get)]
    iterations: usize,
    #[pyo3(get)]
    residual: f64,
    #[pyo3(get)]
    load_steps: usize,
}

#[pymethods]
impl Statics {
    /// Equilibrium coordinates (n_dof,).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.q.bind(py).clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Statics(iterations={}, residual={:e}, load_steps={})",
            self.iterations, self.residual, self.load_steps
        )
    }
}

/// Undamped natural modes, lowest first: `omega` [rad/s] (an unstable
/// equilibrium shows negative values), `frequencies_hz`, `shapes` (n_dof,
/// n_modes), M-orthonormal columns, the `equilibrium` they are about
/// ("rest" or "statics") and its coordinates `q_equilibrium`, and the
/// `asymmetry` of the tangent stiffness (non-zero with follower loads or
/// cables; its symmetric part is used).
#[pyclass(frozen, module = "softrod")]
pub struct Modes {
    omega: Py<PyArray1<f64>>,
    shapes: Py<PyArray2<f64>>,
    q_equilibrium: Py<PyArray1<f64>>,
    #[pyo3(get)]
    equilibrium: &'static str,
    #[pyo3(get)]
    asymmetry: f64,
}

#[pymethods]
impl Modes {
    /// Angular frequencies (n_modes,) [rad/s].
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.omega.bind(py).clone()
    }

    /// Frequencies ω/2π (n_modes,) [Hz].
    #[getter]
    fn frequencies_hz<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let w = self.omega.bind(py).readonly();
        let f: Vec<f64> = w
            .as_slice()?
            .iter()
            .map(|w| w / (2.0 * std::f64::consts::PI))
            .collect();
        Ok(PyArray1::from_vec(py, f))
    }

    /// Mode shapes (n_dof, n_modes), one per column.
    #[getter]
    fn shapes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.shapes.bind(py).clone()
    }

    /// The equilibrium the model was linearized about (n_dof,).
    #[getter]
    fn q_equilibrium<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.q_equilibrium.bind(py).clone()
    }
}

fn modes_py(py: Python<'_>, m: &softrod::dynamics::Modes, eq: &'static str, q: &[f64]) -> Modes {
    Modes {
        omega: vec_out(py, m.omega.as_slice()).unbind(),
        shapes: mat_out(py, &m.shapes).unbind(),
        q_equilibrium: vec_out(py, q).unbind(),
        equilibrium: eq,
        asymmetry: m.asymmetry,
    }
}

/// A model with its initial state and run settings: the front door of
/// softrod from Python.
///
/// Build one from a scene (`Simulation.from_toml(path_or_text)`) or from
/// rods (`Simulation(rods=[softrod.Rod(...)], gravity=[0, 0, -9.81])`).
///
/// Conventions: SI units; `q` are the generalized coordinates in the order
/// of `q_names`: each element's joint coordinates, then a rod's strain
/// coordinates (pieces base to tip, selected strains in the canonical order
/// kx, ky, kz, qx, qy, qz), elements in the scene's order; `qdot`, `qddot`
/// their rates; prescribed joints are not coordinates, they move with the
/// time `t` of the call, or `time` (`set_time`) for the evaluations that
/// take none; poses are world-frame 4×4
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
    duration: Option<f64>,
    /// The model with tension inputs `u`, built on first use.
    inputs: Option<Box<CableInputs>>,
    /// The full model as an integrable system, for `step` without `u`.
    stepper: Option<Box<RodSystem>>,
}

impl Clone for Simulation {
    fn clone(&self) -> Self {
        Self {
            sim: self.sim.clone(),
            warnings: self.warnings.clone(),
            duration: self.duration,
            inputs: self.inputs.clone(),
            stepper: self.stepper.clone(),
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
        }
    }

    fn n(&self) -> usize {
        self.sim.n_dof()
    }

    fn rod_name(&self, rod: &Bound<'_, PyAny>) -> PyResult<String> {
        let i = rod_index(self.sim.model(), rod)?;
        Ok(self.sim.model().rods()[i].spec.name.clone())
    }

    fn inputs(&mut self) -> PyResult<&mut CableInputs> {
        if self.inputs.is_none() {
            self.inputs = Some(Box::new(
                CableInputs::new(self.sim.model()).map_err(dynamics)?,
            ));
        }
        Ok(self.inputs.as_mut().expect("just set"))
    }

    /// `u` checked against the model's cables.
    fn tensions(&mut self, u: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let nc = self.sim.model().n_cables();
        let a = vector(u, "u", nc)?;
        check_tensions(nc, "u", a.slice()).map_err(input)?;
        Ok(a.slice().to_vec())
    }

    /// Evaluates `f` over the poses/Jacobians at one `s` (a number: shape
    /// `item`) or many (a 1-D array: shape `(len(s),) + item`).
    #[allow(clippy::type_complexity)]
    fn along<'py>(
        &self,
        py: Python<'py>,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        item: &[usize],
        f: &dyn Fn(
            &RodKinematics,
            &softrod::kinematics::Rod,
            (usize, &Pose, &[f64]),
            f64,
            &mut [f64],
        ) -> PyResult<()>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let q = vector(q, "q", self.n())?;
        let i = rod_index(self.sim.model(), rod)?;
        let rm = &self.sim.model().rods()[i];
        let to_world = self
            .sim
            .rod_to_world(&rm.spec.name, q.slice())
            .map_err(to_py)?;
        let mut kin = RodKinematics::new(&rm.spec.rod);
        kin.update(&rm.spec.rod, &q.slice()[rm.dofs()], None, None)
            .map_err(|e| input(e.to_string()))?;
        let size: usize = item.iter().product();
        let (points, scalar): (Vec<f64>, bool) = match s.extract::<f64>() {
            Ok(x) => (vec![x], true),
            Err(_) => {
                let a = array(s, "s")?;
                if a.shape().len() != 1 {
                    return Err(input(format!(
                        "s must be a number or 1-D, got shape {:?}",
                        a.shape()
                    )));
                }
                (a.slice().to_vec(), false)
            }
        };
        let mut out = vec![0.0; size * points.len()];
        for (k, &x) in points.iter().enumerate() {
            f(
                &kin,
                &rm.spec.rod,
                (i, &to_world, q.slice()),
                x,
                &mut out[k * size..(k + 1) * size],
            )?;
        }
        let mut shape = Vec::with_capacity(item.len() + 1);
        if !scalar {
            shape.push(points.len());
        }
        shape.extend_from_slice(item);
        array_out(py, out, &shape)
    }
}

fn frame(name: &str) -> PyResult<Frame> {
    match name {
        "body" => Ok(Frame::Body),
        "world" | "spatial" => Ok(Frame::Spatial),
        other => Err(input(format!(
            "frame must be \"body\" or \"world\", got {other:?}"
        ))),
    }
}

#[pymethods]
impl Simulation {
    /// A simulation of `rods` (softrod.Rod, named rod0, rod1, … where they
    /// have no name) under `gravity` [m/s², world frame], with `quadrature`
    /// Gauss points per piece (4: the scene default), from the rest shape at
    /// rest, with the recommended settings.
    #[new]
    #[pyo3(signature = (rods, gravity = None, *, quadrature = 4))]
    fn new(
        rods: &Bound<'_, PyList>,
        gravity: Option<&Bound<'_, PyAny>>,
        quadrature: usize,
    ) -> PyResult<Self> {
        guard(|| {
            let mut refs = Vec::with_capacity(rods.len());
            for (i, r) in rods.iter().enumerate() {
                let r = r
                    .cast_into::<Rod>()
                    .map_err(|_| input(format!("Simulation(rods[{i}]) is not a softrod.Rod")))?;
                refs.push(r.borrow());
            }
            let g = match gravity {
                Some(g) => Some(crate::convert::vec3(g, "gravity")?),
                None => None,
            };
            if quadrature == 0 {
                return Err(input("quadrature must be at least 1 Gauss point per piece"));
            }
            let model = build_model(&refs, g, quadrature)?;
            let mut sim = softrod::Simulation::new(model);
            // Samples every thousandth of the run, whatever its length (a
            // scene's [run] default is a fixed spacing).
            sim.set_settings(RustSettings {
                output_every: None,
                ..sim.settings().clone()
            })
            .map_err(to_py)?;
            Ok(Self::wrap(sim, Vec::new(), None))
        })
    }

    /// The simulation a TOML scene describes (docs/scene-format.md): its
    /// model, `[initial]` state and `[run]` settings. `scene` is a path
    /// (str or os.PathLike) or the scene text itself (a str containing a
    /// newline or "="). Invalid scenes raise `softrod.SceneError` naming the
    /// file, line, column and key path; warnings are in `.warnings`.
    #[classmethod]
    fn from_toml(
        _cls: &Bound<'_, pyo3::types::PyType>,
        scene: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        guard(|| {
            let text: Option<String> = match scene.cast::<PyString>() {
                Ok(s) => {
                    let s = s.to_str()?;
                    (s.contains('\n') || s.contains('=')).then(|| s.to_string())
                }
                Err(_) => None,
            };
            let (sim, scene, warnings) = match text {
                Some(t) => softrod::Simulation::from_toml(&t, "<string>"),
                None => {
                    let path: std::path::PathBuf = scene
                        .extract()
                        .map_err(|_| input("scene must be a path or the scene text"))?;
                    softrod::Simulation::from_scene_file(&path)
                }
            }
            .map_err(to_py)?;
            Ok(Self::wrap(
                sim,
                warnings.iter().map(|w| w.to_string()).collect(),
                Some(scene.run.duration),
            ))
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

    /// A name for every generalized coordinate, in the order of `q`:
    /// `"<rod>.p<piece>.<strain>"` (e.g. `"arm.p0.ky"`), a joint's
    /// coordinates `"<element>.joint.<c>"` first in its element's.
    #[getter]
    fn q_names(&self) -> Vec<String> {
        self.sim.q_names()
    }

    /// The loop closures' residuals at `q` [m] (docs/theory.md D66), a dict
    /// from closure name to `max(|d|, L|r|)`; empty without closures.
    fn closure_residuals(
        &mut self,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<std::collections::BTreeMap<String, f64>> {
        guard(|| {
            let n = self.n();
            let q = vector(q, "q", n)?;
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

    /// The time [s] of the prescribed joints (D59) for the evaluations
    /// that take none: `pose`, `tip_pose`, `jacobian`, `body_poses`,
    /// `mass_matrix`, `energies`, `gravity_force`, `closure_residuals`. 0
    /// until `set_time` moves it; the calls that take a `t` do not.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// Sets `time` [s] (see there); irrelevant without prescribed joints.
    fn set_time(&mut self, t: f64) -> PyResult<()> {
        if !t.is_finite() {
            return Err(input(format!("t must be finite, got {t}")));
        }
        self.sim.set_time(t);
        Ok(())
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
            .map(|r| r.spec.rod.length())
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
    /// coordinates `q` (D7): a 4×4 homogeneous transform, or (len(s), 4, 4)
    /// for a 1-D array of abscissae (one kinematic sweep for all).
    fn pose<'py>(
        &self,
        py: Python<'py>,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| {
            self.along(
                py,
                rod,
                s,
                q,
                &[4, 4],
                &|kin, r, (_, to_world, _), x, out| {
                    let g = kin
                        .pose_at(r, x)
                        .map_err(|e| input(format!("s = {x}: {e}")))?;
                    pose_into(&to_world.compose(&g), out);
                    Ok(())
                },
            )
        })
    }

    /// Tip pose of rod `rod` for `q` (4×4, world frame).
    fn tip_pose<'py>(
        &self,
        py: Python<'py>,
        rod: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| {
            let q = vector(q, "q", self.n())?;
            let name = self.rod_name(rod)?;
            let g = self.sim.tip_pose(&name, q.slice()).map_err(to_py)?;
            let mut out = vec![0.0; 16];
            pose_into(&g, &mut out);
            array_out(py, out, &[4, 4])
        })
    }

    /// World poses (n_bodies, 4, 4) of the rigid bodies' frames for `q`, in
    /// the scene's order (D51); shape (0, 4, 4) without bodies.
    fn body_poses<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| {
            let q = vector(q, "q", self.n())?;
            let poses = self.sim.body_poses(q.slice()).map_err(to_py)?;
            let mut out = vec![0.0; 16 * poses.len()];
            for (g, o) in poses.iter().zip(out.chunks_mut(16)) {
                pose_into(g, o);
            }
            array_out(py, out, &[poses.len(), 4, 4])
        })
    }

    /// Geometric Jacobian J(s) (6, n_dof) of rod `rod` at `s` for `q`: the
    /// twist of the section is J q̇, angular part first (D11). `frame`:
    /// "body" (the section's own frame) or "world" (spatial twist). Every
    /// coordinate that moves the section has its column: the rod's pieces
    /// up to `s` and, on a robot, its joint's and its parents'; the others
    /// are zero. For a 1-D array `s`: (len(s), 6, n_dof).
    #[pyo3(signature = (rod, s, q, frame = "body"))]
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        frame: &str,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        guard(|| {
            let f = self::frame(frame)?;
            let n = self.n();
            let model = self.sim.model();
            self.along(py, rod, s, q, &[6, n], &|kin, r, (i, _, qs), x, out| {
                let rm = &model.rods()[i];
                if model.is_articulated() {
                    // Joints and ancestors move the section too.
                    let j = self
                        .sim
                        .jacobian(&rm.spec.name, x, qs, f)
                        .map_err(|e| input(format!("s = {x}: {e}")))?;
                    for row in 0..6 {
                        for c in 0..n {
                            out[row * n + c] = j[(row, c)];
                        }
                    }
                    return Ok(());
                }
                let mut local = Matrix6xX::zeros(rm.n_dof());
                kin.jacobian_at(r, x, f, &mut local)
                    .map_err(|e| input(format!("s = {x}: {e}")))?;
                for row in 0..6 {
                    for c in 0..rm.n_dof() {
                        out[row * n + rm.dof_offset + c] = local[(row, c)];
                    }
                }
                Ok(())
            })
        })
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
        guard(|| {
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            let tau = match tau {
                Some(t) => Some(vector(t, "tau", n)?),
                None => None,
            };
            if let Some(u) = u {
                let u = self.tensions(u)?;
                let inputs = self.inputs()?;
                inputs.u = u;
                inputs.tau_extra = tau.map(|t| DVector::from_column_slice(t.slice()));
                let qdd = inputs
                    .forward_dynamics(t, q.slice(), qd.slice())
                    .map_err(dynamics)?;
                return Ok(vec_out(py, qdd.as_slice()));
            }
            let qdd = self
                .sim
                .forward_dynamics(t, q.slice(), qd.slice(), tau.as_ref().map(|a| a.slice()))
                .map_err(to_py)?;
            Ok(vec_out(py, qdd.as_slice()))
        })
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
        guard(|| {
            let n = self.n();
            let (q, qd, qdd) = (
                vector(q, "q", n)?,
                vector(qdot, "qdot", n)?,
                vector(qddot, "qddot", n)?,
            );
            if let Some(u) = u {
                let u = self.tensions(u)?;
                let inputs = self.inputs()?;
                inputs.u = u;
                inputs.tau_extra = None;
                inputs.sync().map_err(dynamics)?;
                let s = &mut inputs.sys;
                let tau = softrod::dynamics::inverse_dynamics(
                    &s.model,
                    &mut s.data,
                    t,
                    q.slice(),
                    qd.slice(),
                    qdd.slice(),
                )
                .map_err(dynamics)?;
                return Ok(vec_out(py, tau.as_slice()));
            }
            let tau = self
                .sim
                .inverse_dynamics(t, q.slice(), qd.slice(), qdd.slice())
                .map_err(to_py)?;
            Ok(vec_out(py, tau.as_slice()))
        })
    }

    /// Mass matrix M(q) (n_dof, n_dof), symmetric positive definite (D19–D20).
    fn mass_matrix<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guard(|| {
            let q = vector(q, "q", self.n())?;
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
        guard(|| {
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            let c = coriolis_matrix(self.sim.model(), q.slice(), qd.slice()).map_err(dynamics)?;
            let f = c * DVector::from_column_slice(qd.slice());
            Ok(vec_out(py, f.as_slice()))
        })
    }

    /// Generalized gravity G(q) = ∂V_g/∂q (n_dof,) (D22); zero without gravity.
    fn gravity_force<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        guard(|| {
            let q = vector(q, "q", self.n())?;
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
        guard(|| {
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            let u = match u {
                Some(u) => Some(self.tensions(u)?),
                None => None,
            };
            let previous = self.sim.cable_tensions().map(<[f64]>::to_vec);
            if let Some(u) = &u {
                self.sim.set_cable_tensions(Some(u)).map_err(to_py)?;
            }
            let lin = self.sim.linearize(t, q.slice(), qd.slice());
            if u.is_some() {
                self.sim
                    .set_cable_tensions(previous.as_deref())
                    .map_err(to_py)?;
            }
            let lin = lin.map_err(to_py)?;
            Ok((mat_out(py, &lin.a), mat_out(py, &lin.b)))
        })
    }

    /// Kinetic, elastic and gravitational energy at `(q, qdot)` [J].
    fn energies(&mut self, q: &Bound<'_, PyAny>, qdot: &Bound<'_, PyAny>) -> PyResult<Energies> {
        guard(|| {
            let n = self.n();
            let (q, qd) = (vector(q, "q", n)?, vector(qdot, "qdot", n)?);
            let e = self.sim.energies(q.slice(), qd.slice()).map_err(to_py)?;
            Ok(Energies {
                kinetic: e.kinetic,
                elastic: e.elastic,
                gravitational: e.gravitational,
                total: e.total(),
            })
        })
    }

    /// Whether the model has static loads (gravity, loads, cables): then its
    /// equilibrium differs from the rest shape.
    #[getter]
    fn has_static_loads(&self) -> bool {
        self.sim.has_static_loads()
    }

    /// Static equilibrium under every static term at t = 0, from the initial
    /// q (Newton with line search and load continuation). Raises
    /// `softrod.SimulationError` when it does not converge. Releases the GIL.
    fn statics(&mut self, py: Python<'_>) -> PyResult<Statics> {
        let sim = &mut self.sim;
        let r = guard_detached(py, || sim.statics().map_err(to_py))?;
        Ok(Statics {
            q: vec_out(py, r.q.as_slice()).unbind(),
            iterations: r.iterations,
            residual: r.residual,
            load_steps: r.load_steps,
        })
    }

    /// Undamped natural modes about the static equilibrium (the rest shape
    /// when the model has no static loads). Releases the GIL.
    fn modes(&mut self, py: Python<'_>) -> PyResult<Modes> {
        let sim = &mut self.sim;
        let m = guard_detached(py, || sim.modes().map_err(to_py))?;
        let (eq, q) = match &m.equilibrium {
            Equilibrium::Rest => ("rest", vec![0.0; self.n()]),
            Equilibrium::Statics(q) => ("statics", q.as_slice().to_vec()),
        };
        Ok(modes_py(py, &m.modes, eq, &q))
    }

    /// Undamped natural modes of the model linearized about `q` (which
    /// should be an equilibrium). Releases the GIL.
    fn modes_about(&mut self, py: Python<'_>, q: &Bound<'_, PyAny>) -> PyResult<Modes> {
        let qv = vector(q, "q", self.n())?.slice().to_vec();
        let sim = &mut self.sim;
        let m = guard_detached(py, || sim.modes_about(&qv).map_err(to_py))?;
        Ok(modes_py(py, &m, "given", &qv))
    }

    /// Integrates `duration` seconds (default: the scene's `[run]
    /// duration`) and returns a `softrod.Trajectory`.
    ///
    /// Keywords override the run settings for this call only:
    /// `integrator`, `rtol`, `atol`, `dt`, `output_every`, `error_control`,
    /// `linearly_implicit` (see `softrod.Settings`); `q0`, `qdot0`
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
                        q0 = None, qdot0 = None, controller = None, control_every = None))]
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
        q0: Option<&Bound<'_, PyAny>>,
        qdot0: Option<&Bound<'_, PyAny>>,
        controller: Option<Py<PyAny>>,
        control_every: Option<f64>,
    ) -> PyResult<Trajectory> {
        let duration = duration.or(self.duration).ok_or_else(|| {
            input("simulate needs a duration (this simulation has no scene [run] duration)")
        })?;
        let mut settings = self.sim.settings().clone();
        overrides(
            &mut settings,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            error_control,
            linearly_implicit,
        )?;
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
                        Ok(simulate_controlled(
                            inputs,
                            &settings,
                            duration,
                            &q_start,
                            &qd_start,
                            control_every,
                            &mut controller,
                        ))
                    })
                })?;
                match r {
                    Ok(traj) => Trajectory::new(py, traj, self.sim.model()),
                    Err(ControlError::Integrate(e)) => Err(integrate(e)),
                    Err(ControlError::Controller(e)) => Err(e),
                    Err(ControlError::Output { t, message }) => Err(simulation(
                        format!("output at t = {t:e} s failed: {message}"),
                        Some(t),
                    )),
                }
            }
        }
    }

    /// One step of `dt` seconds from `state` (a `softrod.State`), with the
    /// run settings' integrator, returning the state at `state.t + dt`.
    /// `u` (n_cables,) [N]: cable tensions held over the step (replacing
    /// the scheduled ones); None: the scheduled tensions. For RL and MPC
    /// loops: `state = sim.step(state, 1e-3, u)`. Each call starts the
    /// integrator afresh (first step `settings.dt`, capped at `dt`), so a
    /// loop of steps equals `simulate(controller=…, control_every=dt)`.
    /// Releases the GIL.
    #[pyo3(signature = (state, dt, u = None))]
    fn step(
        &mut self,
        py: Python<'_>,
        state: PyRef<'_, State>,
        dt: f64,
        u: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<State> {
        let n = self.n();
        let q =
            DVector::from_column_slice(vector(state.q.bind(py).as_any(), "state.q", n)?.slice());
        let qd = DVector::from_column_slice(
            vector(state.qdot.bind(py).as_any(), "state.qdot", n)?.slice(),
        );
        let t = state.t;
        let settings = self.sim.settings().clone();
        let (q1, qd1) = match u {
            Some(u) => {
                let u = self.tensions(u)?;
                let inputs = self.inputs()?;
                inputs.u = u;
                inputs.tau_extra = None;
                inputs.sys.jacobian = settings.stiff_jacobian();
                guard_detached(py, || {
                    step(inputs, &settings, t, dt, &q, &qd).map_err(to_py)
                })?
            }
            None => {
                if self.stepper.is_none() {
                    self.stepper = Some(Box::new(RodSystem::new(self.sim.model().clone())));
                }
                let sys = self.stepper.as_mut().expect("just set");
                sys.jacobian = settings.stiff_jacobian();
                guard_detached(py, || {
                    step(&mut **sys, &settings, t, dt, &q, &qd).map_err(to_py)
                })?
            }
        };
        State::from_slices(py, t + dt, q1.as_slice(), qd1.as_slice())
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

    fn __repr__(&self) -> String {
        format!(
            "Simulation(rods={:?}, n_dof={}, terms={:?})",
            self.rod_names(),
            self.n(),
            self.terms()
        )
    }
}
