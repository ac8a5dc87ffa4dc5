//! The results of an evaluation or analysis: `softrod.Energies`,
//! `softrod.Statics`, `softrod.Modes`.

use std::collections::BTreeMap;

use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{mat_out, vec_out};

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

impl From<&softrod::dynamics::Energies> for Energies {
    fn from(e: &softrod::dynamics::Energies) -> Self {
        Self {
            kinetic: e.kinetic,
            elastic: e.elastic,
            gravitational: e.gravitational,
            total: e.total(),
        }
    }
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

/// A static equilibrium, with what `softrod statics --json` reports: `q`
/// (n_dof,), `converged` (always True: a failure raises), Newton
/// `iterations`, final `residual` (max-abs generalized force [N or N·m]),
/// `load_steps` of the load continuation, `stable` (no linearized mode is
/// unstable, rigid ones being neutral; None when the model is too large to
/// check), the first rod's `tip` pose (4, 4), every rod's tip pose `tips` and body pose
/// `bodies` by name (4, 4) [m], loop-closure residuals `closures` by name
/// [m] and `warnings`; with obstacles, the `contacts` at the equilibrium (a
/// list of `softrod.Contact`; frictionless: statics has no friction
/// history) and their `max_penetration` [m].
#[pyclass(frozen, module = "softrod")]
pub struct Statics {
    pub(crate) q: Py<PyArray1<f64>>,
    #[pyo3(get)]
    pub(crate) converged: bool,
    #[pyo3(get)]
    pub(crate) iterations: usize,
    #[pyo3(get)]
    pub(crate) residual: f64,
    #[pyo3(get)]
    pub(crate) load_steps: usize,
    #[pyo3(get)]
    pub(crate) stable: Option<bool>,
    pub(crate) tip: Py<PyArrayDyn<f64>>,
    pub(crate) tips: Vec<(String, Py<PyArrayDyn<f64>>)>,
    pub(crate) bodies: Vec<(String, Py<PyArrayDyn<f64>>)>,
    #[pyo3(get)]
    pub(crate) closures: BTreeMap<String, f64>,
    #[pyo3(get)]
    pub(crate) warnings: Vec<String>,
    #[pyo3(get)]
    pub(crate) contacts: Vec<Py<crate::contacts::Contact>>,
    #[pyo3(get)]
    pub(crate) max_penetration: f64,
}

fn named<'py>(
    py: Python<'py>,
    list: &[(String, Py<PyArrayDyn<f64>>)],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, pose) in list {
        d.set_item(name, pose.bind(py))?;
    }
    Ok(d)
}

#[pymethods]
impl Statics {
    /// Equilibrium coordinates (n_dof,).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.q.bind(py).clone()
    }

    /// The first rod's tip pose (4, 4) at the equilibrium (world frame, m).
    #[getter]
    fn tip<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        self.tip.bind(py).clone()
    }

    /// Every rod's tip pose (4, 4) by rod name.
    #[getter]
    fn tips<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        named(py, &self.tips)
    }

    /// Every rigid body's pose (4, 4) by body name (empty without bodies).
    #[getter]
    fn bodies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        named(py, &self.bodies)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let tip = self.tip.bind(py).readonly();
        let g = tip.as_slice()?;
        let stable = match self.stable {
            Some(true) => "True",
            Some(false) => "False",
            None => "None",
        };
        let mut s = format!(
            "Statics(converged={}, iterations={}, load_steps={}, residual={:.3e}, \
             tip=[{:.6}, {:.6}, {:.6}] m, stable={stable}",
            if self.converged { "True" } else { "False" },
            self.iterations,
            self.load_steps,
            self.residual,
            g[3],
            g[7],
            g[11],
        );
        if !self.closures.is_empty() {
            let worst = self.closures.values().fold(0.0_f64, |a, b| a.max(*b));
            s.push_str(&format!(
                ", closures={} (worst {worst:.1e} m)",
                self.closures.len()
            ));
        }
        if !self.warnings.is_empty() {
            s.push_str(&format!(", warnings={}", self.warnings.len()));
        }
        s.push(')');
        Ok(s)
    }
}

/// Undamped natural modes, lowest first: `omega` [rad/s] (an unstable
/// equilibrium shows negative values, a rigid (zero) mode exactly 0),
/// `frequencies_hz`, `shapes` (n_dof, n_modes), M-orthonormal columns, the
/// `equilibrium` they are about ("rest" or "statics") and its coordinates
/// `q_equilibrium`, the `asymmetry` of the tangent stiffness (non-zero
/// with follower loads or cables; its symmetric part is used),
/// `rigid_tolerance` (the |ω²| [rad²/s²] at or below which a mode counts
/// as rigid), `n_rigid` and `n_unstable`, and the equilibrium's validity
/// `warnings` (as `Statics.warnings`; empty for `modes_about`).
#[pyclass(frozen, module = "softrod")]
pub struct Modes {
    omega: Py<PyArray1<f64>>,
    shapes: Py<PyArray2<f64>>,
    q_equilibrium: Py<PyArray1<f64>>,
    #[pyo3(get)]
    equilibrium: &'static str,
    #[pyo3(get)]
    asymmetry: f64,
    #[pyo3(get)]
    rigid_tolerance: f64,
    #[pyo3(get)]
    n_rigid: usize,
    #[pyo3(get)]
    n_unstable: usize,
    #[pyo3(get)]
    warnings: Vec<String>,
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

    /// `Modes(24 about statics: 0.927, 5.81, 16.3, … Hz)`: the count, the
    /// equilibrium and the lowest frequencies.
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let w = self.omega.bind(py).readonly();
        let w = w.as_slice()?;
        let shown: Vec<String> = w
            .iter()
            .take(REPR_MODES)
            .map(|w| format!("{:.4}", w / (2.0 * std::f64::consts::PI)))
            .collect();
        let more = if w.len() > REPR_MODES { ", …" } else { "" };
        Ok(format!(
            "Modes({} about {}: {}{more} Hz)",
            w.len(),
            self.equilibrium,
            shown.join(", ")
        ))
    }
}

/// Frequencies a `Modes` repr shows.
const REPR_MODES: usize = 4;

pub(crate) fn modes_py(
    py: Python<'_>,
    m: &softrod::dynamics::Modes,
    eq: &'static str,
    q: &[f64],
    warnings: Vec<String>,
) -> Modes {
    Modes {
        omega: vec_out(py, m.omega.as_slice()).unbind(),
        shapes: mat_out(py, &m.shapes).unbind(),
        q_equilibrium: vec_out(py, q).unbind(),
        equilibrium: eq,
        asymmetry: m.asymmetry,
        rigid_tolerance: m.rigid_tolerance,
        n_rigid: m.n_rigid(),
        n_unstable: m.n_unstable(),
        warnings,
    }
}
