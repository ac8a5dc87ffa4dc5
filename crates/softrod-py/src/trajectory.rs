//! A run as numpy arrays, and the state of the step API.

use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use softrod::dynamics::Model;
use softrod::record::{Columns, WorldPoses};
use softrod::{RunStatus, Trajectory as RustTrajectory};

use crate::convert::{array, array_out, vec_out, vector};
use crate::errors::input;

/// Makes `a` read-only: the arrays of a trajectory are shared by every
/// access, so an in-place change by the caller must not alter the record.
fn frozen<'py, T>(a: Bound<'py, T>) -> PyResult<Bound<'py, T>> {
    a.as_any().getattr("flags")?.setattr("writeable", false)?;
    Ok(a)
}

/// A simulated run: samples at the output times, as read-only float64
/// numpy arrays (index 0 is `t = 0`).
///
/// - `t` (n_samples,) [s]
/// - `q`, `qdot` (n_samples, n_dof): coordinates (see `Simulation.q_names`)
///   and their rates
/// - `tip_position` (n_samples, 3) [m], `tip_rotation` (n_samples, 3, 3):
///   the tip pose of the first rod in the world frame; `tip_positions`
///   (n_samples, n_rods, 3), `tip_rotations` (n_samples, n_rods, 3, 3) for
///   every rod
/// - `kinetic`, `elastic`, `gravitational`, `energy` (n_samples,) [J]
/// - `tension`, `power` (n_samples, n_cables) [N, W]: each cable's tension
///   and the power it puts into the rods
/// - `prescribed`, `prescribed_force` (n_samples, n_prescribed): the
///   prescribed joints' coordinates and their drives' forces (D59–D60)
/// - `columns`, `table` (n_samples, len(columns)): every number as
///   `softrod run` writes `trajectory.csv`, in its column order
/// - `shape(i, rod, s)`: positions along a rod at sample `i`
/// - `contacts` (a list per sample of `softrod.Contact`), `max_penetration`
///   [m], `max_contacts`: the contacts as `contacts.csv` and summary.json
///   give them
#[pyclass(frozen, module = "softrod")]
pub struct Trajectory {
    t: Py<PyArray1<f64>>,
    q: Py<PyArray2<f64>>,
    qdot: Py<PyArray2<f64>>,
    tip_positions: Py<PyArrayDyn<f64>>,
    tip_rotations: Py<PyArrayDyn<f64>>,
    kinetic: Py<PyArray1<f64>>,
    elastic: Py<PyArray1<f64>>,
    gravitational: Py<PyArray1<f64>>,
    tension: Py<PyArray2<f64>>,
    power: Py<PyArray2<f64>>,
    prescribed: Py<PyArray2<f64>>,
    prescribed_force: Py<PyArray2<f64>>,
    columns: Vec<String>,
    table: Py<PyArray2<f64>>,
    status: &'static str,
    t_final: f64,
    stats: softrod::integrate::Stats,
    energy: Option<softrod::EnergyBalance>,
    warnings: Vec<String>,
    n: usize,
    model: Model,
    /// The contacts at each sample (with the run's friction state).
    contacts: Vec<Vec<softrod::mechanics::ContactPoint>>,
    max_penetration: f64,
    max_contacts: usize,
}

fn rows<'py, R: AsRef<[f64]>>(
    py: Python<'py>,
    v: &[R],
    n: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let mut data = Vec::with_capacity(v.len() * n);
    for r in v {
        data.extend_from_slice(r.as_ref());
    }
    PyArray1::from_vec(py, data).reshape([v.len(), n])
}

/// The rows of `trajectory.csv` (see `softrod::record::Columns`).
fn table<'py>(py: Python<'py>, tr: &RustTrajectory) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let c: &Columns = &tr.columns;
    let mut data = Vec::with_capacity(tr.len() * c.width());
    for i in 0..tr.len() {
        c.push_row(tr.row(i), &mut data);
    }
    PyArray1::from_vec(py, data).reshape([tr.len(), c.width()])
}

impl Trajectory {
    /// The Python view of a run of `model`.
    pub fn new(py: Python<'_>, mut tr: RustTrajectory, model: &Model) -> PyResult<Self> {
        let contacts = std::mem::take(&mut tr.contacts);
        let n = model.n_dof();
        let m = tr.len();
        let nr = model.rods().len();
        let mut tp = Vec::with_capacity(m * nr * 3);
        let mut tr9 = Vec::with_capacity(m * nr * 9);
        for tips in &tr.tips {
            for g in tips {
                tp.extend_from_slice(g.translation.as_slice());
                for i in 0..3 {
                    for j in 0..3 {
                        tr9.push(g.rotation[(i, j)]);
                    }
                }
            }
        }
        let e = |f: fn(&softrod::dynamics::Energies) -> f64| -> Vec<f64> {
            tr.energies.iter().map(f).collect()
        };
        Ok(Self {
            t: frozen(vec_out(py, &tr.t))?.unbind(),
            q: frozen(rows(py, &tr.q, n)?)?.unbind(),
            qdot: frozen(rows(py, &tr.qdot, n)?)?.unbind(),
            tip_positions: frozen(array_out(py, tp, &[m, nr, 3])?)?.unbind(),
            tip_rotations: frozen(array_out(py, tr9, &[m, nr, 3, 3])?)?.unbind(),
            kinetic: frozen(PyArray1::from_vec(py, e(|e| e.kinetic)))?.unbind(),
            elastic: frozen(PyArray1::from_vec(py, e(|e| e.elastic)))?.unbind(),
            gravitational: frozen(PyArray1::from_vec(py, e(|e| e.gravitational)))?.unbind(),
            tension: frozen(rows(py, &tr.tensions, tr.columns.n_cables)?)?.unbind(),
            power: frozen(rows(py, &tr.cable_power, tr.columns.n_cables)?)?.unbind(),
            prescribed: frozen(rows(py, &tr.prescribed_q, tr.columns.n_prescribed)?)?.unbind(),
            prescribed_force: frozen(rows(py, &tr.prescribed_force, tr.columns.n_prescribed)?)?
                .unbind(),
            columns: tr.columns.names(),
            table: frozen(table(py, &tr)?)?.unbind(),
            status: match tr.summary.status {
                RunStatus::Completed => "completed",
                RunStatus::Stopped => "stopped",
            },
            t_final: tr.summary.t_final,
            stats: tr.summary.stats,
            energy: tr.summary.energy,
            warnings: tr.summary.warnings.clone(),
            n: m,
            model: model.clone(),
            contacts,
            max_penetration: tr.max_penetration,
            max_contacts: tr.max_contacts,
        })
    }

    fn rod_index(&self, rod: &Bound<'_, PyAny>) -> PyResult<usize> {
        crate::simulation::rod_index(&self.model, rod)
    }
}

#[pymethods]
impl Trajectory {
    /// Output times (n_samples,) [s].
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.t.bind(py).clone()
    }

    /// Coordinates (n_samples, n_dof).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.q.bind(py).clone()
    }

    /// Velocities (n_samples, n_dof).
    #[getter]
    fn qdot<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.qdot.bind(py).clone()
    }

    /// Tip position of the first rod (n_samples, 3) [m, world frame].
    #[getter]
    fn tip_position<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.tip_positions
            .bind(py)
            .as_any()
            .get_item((pyo3::types::PySlice::full(py), 0))
    }

    /// Tip rotation matrix of the first rod (n_samples, 3, 3), local → world.
    #[getter]
    fn tip_rotation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.tip_rotations
            .bind(py)
            .as_any()
            .get_item((pyo3::types::PySlice::full(py), 0))
    }

    /// Tip positions of every rod (n_samples, n_rods, 3) [m].
    #[getter]
    fn tip_positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        self.tip_positions.bind(py).clone()
    }

    /// Tip rotations of every rod (n_samples, n_rods, 3, 3).
    #[getter]
    fn tip_rotations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArrayDyn<f64>> {
        self.tip_rotations.bind(py).clone()
    }

    /// Kinetic energy ½ q̇ᵀM q̇ (n_samples,) [J].
    #[getter]
    fn kinetic<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.kinetic.bind(py).clone()
    }

    /// Elastic energy (n_samples,) [J].
    #[getter]
    fn elastic<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.elastic.bind(py).clone()
    }

    /// Gravitational energy (n_samples,) [J] (zero without gravity).
    #[getter]
    fn gravitational<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.gravitational.bind(py).clone()
    }

    /// Total mechanical energy kinetic + elastic + gravitational (n_samples,)
    /// [J]: conserved without damping, drag, actuation and non-conservative
    /// loads.
    #[getter]
    fn energy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (k, e, g) = (
            self.kinetic.bind(py).readonly(),
            self.elastic.bind(py).readonly(),
            self.gravitational.bind(py).readonly(),
        );
        let total: Vec<f64> = k
            .as_slice()?
            .iter()
            .zip(e.as_slice()?)
            .zip(g.as_slice()?)
            .map(|((a, b), c)| a + b + c)
            .collect();
        Ok(PyArray1::from_vec(py, total))
    }

    /// Each cable's tension (n_samples, n_cables) [N]: the input or the
    /// schedule in effect.
    #[getter]
    fn tension<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.tension.bind(py).clone()
    }

    /// The power each cable puts into the rods (n_samples, n_cables) [W]
    /// (D15).
    #[getter]
    fn power<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.power.bind(py).clone()
    }

    /// The prescribed joint coordinates (n_samples, n_prescribed) [rad or
    /// m], in the order of `Simulation.prescribed_names` (D59).
    #[getter]
    fn prescribed<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.prescribed.bind(py).clone()
    }

    /// The generalized force each prescribed drive applies (n_samples,
    /// n_prescribed) [N·m or N] (D60).
    #[getter]
    fn prescribed_force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.prescribed_force.bind(py).clone()
    }

    /// The names of `table`'s columns: those of `trajectory.csv`.
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.columns.clone()
    }

    /// Every number of the run as `softrod run` writes `trajectory.csv`
    /// (n_samples, len(columns)), in its column order.
    #[getter]
    fn table<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.table.bind(py).clone()
    }

    /// "completed", or "stopped" (a controller or callback ended the run).
    #[getter]
    fn status(&self) -> &'static str {
        self.status
    }

    /// Time reached [s].
    #[getter]
    fn t_final(&self) -> f64 {
        self.t_final
    }

    /// The integrator's work: steps, rejected_steps, rhs_evaluations,
    /// jacobian_evaluations, factorizations, lu_solves, newton_iterations.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let s = &self.stats;
        d.set_item("steps", s.steps)?;
        d.set_item("rejected_steps", s.rejected_steps)?;
        d.set_item("rhs_evaluations", s.rhs_evaluations)?;
        d.set_item("jacobian_evaluations", s.jacobian_evaluations)?;
        d.set_item("factorizations", s.factorizations)?;
        d.set_item("lu_solves", s.lu_solves)?;
        d.set_item("newton_iterations", s.newton_iterations)?;
        Ok(d)
    }

    /// The energy balance the run was watched by (the `energy_*` fields of
    /// summary.json): `initial` E(0), `change` E(t_end) − E(0), `work` of
    /// the non-conservative forces, the largest balance `error`
    /// |E(t) − E(0) − W(t)| over the accepted steps and its time `t_worst`,
    /// `relative` = error / `scale` (the energy scale at the end), the
    /// trapezoidal work's uncertainty `quadrature` [J], and whether the
    /// model is `non_conservative`. None for runs that are not watched
    /// (the step API, controller runs).
    #[getter]
    fn energy_balance<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(e) = &self.energy else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("initial", e.initial)?;
        d.set_item("change", e.change)?;
        d.set_item("work", e.work)?;
        d.set_item("error", e.error)?;
        d.set_item("relative", e.relative)?;
        d.set_item("scale", e.scale)?;
        d.set_item("t_worst", e.t_worst)?;
        d.set_item("quadrature", e.quadrature)?;
        d.set_item("non_conservative", e.non_conservative)?;
        Ok(Some(d))
    }

    /// What the run's watch found suspicious but not wrong (an energy drift
    /// beyond a tenth of the tolerance, strains beyond the model's
    /// validity), as summary.json's `warnings`.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// Positions [m, world frame] along rod `rod` (name or index) at sample
    /// `i` (negative counts from the end): at the N + 1 piece boundaries
    /// (shape (N + 1, 3)), or at the abscissae `s` [m] (shape (len(s), 3)).
    #[pyo3(signature = (i = -1, rod = None, s = None))]
    fn shape<'py>(
        &self,
        py: Python<'py>,
        i: isize,
        rod: Option<&Bound<'py, PyAny>>,
        s: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let q = self.q.bind(py).readonly();
        let q = q.as_array();
        let m = q.nrows() as isize;
        let k = if i < 0 { m + i } else { i };
        if !(0..m).contains(&k) {
            return Err(pyo3::exceptions::PyIndexError::new_err(format!(
                "sample {i} out of range for {m} samples"
            )));
        }
        let r = match rod {
            Some(r) => self.rod_index(r)?,
            None => 0,
        };
        let row: Vec<f64> = q.row(k as usize).iter().copied().collect();
        // The world poses at that sample's time (prescribed joints move
        // with it).
        let t = self.t.bind(py).readonly();
        let mut poses = WorldPoses::new(&self.model);
        poses
            .update(&self.model, t.as_slice()?[k as usize], &row)
            .map_err(|e| input(e.report()))?;
        let mut out = Vec::new();
        match s {
            None => {
                for g in poses.boundaries(r) {
                    out.extend_from_slice(g.translation.as_slice());
                }
            }
            Some(s) => {
                let a = array(s, "s")?;
                if a.shape().len() != 1 {
                    return Err(input(format!("s must be 1-D, got shape {:?}", a.shape())));
                }
                for &x in a.slice() {
                    let g = poses
                        .pose_at(&self.model, r, x)
                        .map_err(|e| input(format!("s = {x}: {}", e.report())))?;
                    out.extend_from_slice(g.translation.as_slice());
                }
            }
        }
        let rows = out.len() / 3;
        array_out(py, out, &[rows, 3])
    }

    /// The active contacts at each sample (a list per output time of
    /// `softrod.Contact`, as `softrod run` writes `contacts.csv`), with the
    /// forces of the run's friction state; empty lists for a model without
    /// contact.
    #[getter]
    fn contacts(&self) -> Vec<Vec<crate::contacts::Contact>> {
        self.contacts
            .iter()
            .map(|c| crate::contacts::Contact::list(&self.model, c))
            .collect()
    }

    /// The largest penetration `−gap` over the samples [m] (0 without
    /// contact or when nothing penetrated), summary.json's `max_penetration`.
    #[getter]
    fn max_penetration(&self) -> f64 {
        self.max_penetration
    }

    /// The most contacts active at one sample (summary.json's
    /// `max_contacts`).
    #[getter]
    fn max_contacts(&self) -> usize {
        self.max_contacts
    }

    fn __len__(&self) -> usize {
        self.n
    }

    /// `Trajectory(1001 samples, t = 0 … 1 s, status='completed', 24 DoF,
    /// 62 steps (3 rejected), tip at t_final [0.391, 0, -0.287] m, energy
    /// balance 2.1e-06 relative)`, with the warnings' count when there are
    /// any.
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let t = self.t.bind(py).readonly();
        let t = t.as_slice()?;
        let t0 = t.first().copied().unwrap_or(0.0);
        let mut s = format!(
            "Trajectory({} samples, t = {t0} … {} s, status={:?}, {} DoF, {} steps ({} rejected)",
            self.n,
            self.t_final,
            self.status,
            numpy::PyUntypedArrayMethods::shape(self.q.bind(py))[1],
            self.stats.steps,
            self.stats.rejected_steps,
        );
        let tips = self.tip_positions.bind(py).readonly();
        let tips = tips.as_slice()?;
        if tips.len() >= 3 && self.n > 0 {
            // The first rod's tip at the last sample: [n, n_rods, 3].
            let k = tips.len() / self.n * (self.n - 1);
            s.push_str(&format!(
                ", tip at the end [{:.6}, {:.6}, {:.6}] m",
                tips[k],
                tips[k + 1],
                tips[k + 2]
            ));
        }
        if let Some(e) = &self.energy {
            s.push_str(&format!(", energy balance {:.1e} relative", e.relative));
        }
        if !self.warnings.is_empty() {
            s.push_str(&format!(", warnings={}", self.warnings.len()));
        }
        s.push(')');
        Ok(s)
    }
}

/// The state of the step API: time `t` [s], coordinates `q` and velocities
/// `qdot` (float64 arrays of length n_dof, copied on construction).
#[pyclass(frozen, module = "softrod")]
pub struct State {
    pub(crate) t: f64,
    pub(crate) q: Py<PyArray1<f64>>,
    pub(crate) qdot: Py<PyArray1<f64>>,
}

impl State {
    pub fn from_slices(py: Python<'_>, t: f64, q: &[f64], qd: &[f64]) -> PyResult<Self> {
        Ok(Self {
            t,
            q: frozen(vec_out(py, q))?.unbind(),
            qdot: frozen(vec_out(py, qd))?.unbind(),
        })
    }
}

#[pymethods]
impl State {
    #[new]
    #[pyo3(signature = (t, q, qdot))]
    fn new(
        py: Python<'_>,
        t: f64,
        q: &Bound<'_, PyAny>,
        qdot: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let qa = array(q, "q")?;
        if qa.shape().len() != 1 {
            return Err(input(format!("q must be 1-D, got shape {:?}", qa.shape())));
        }
        let n = qa.slice().len();
        let qd = vector(qdot, "qdot", n)?;
        Self::from_slices(py, t, qa.slice(), qd.slice())
    }

    /// Time [s].
    #[getter]
    fn t(&self) -> f64 {
        self.t
    }

    /// Coordinates (n_dof,), read-only.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.q.bind(py).clone()
    }

    /// Velocities (n_dof,), read-only.
    #[getter]
    fn qdot<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.qdot.bind(py).clone()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!(
            "State(t={:?}, n_dof={})",
            self.t,
            numpy::PyUntypedArrayMethods::len(self.q.bind(py))
        )
    }
}
