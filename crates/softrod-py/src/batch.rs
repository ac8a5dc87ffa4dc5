//! `softrod.BatchStepper`: many copies of a model stepped over one control
//! period in one call, on a pool of Rust threads with the GIL released —
//! the physics of the vectorized learning environments
//! (`softrod.envs.BatchedVectorEnv`).
//!
//! Each copy steps exactly as `Simulation.step(state, dt, u)` does (the
//! same [`step`] on a [`CableInputs`] with the same settings and exact
//! Jacobian choice, `τ_extra` none), so a batch equals the copies stepped
//! one by one bit for bit: the copies share nothing, the work of one copy
//! runs on one thread from start to end, and the dynamics' kernels do not
//! depend on which thread runs them. The pool is rayon's (already a
//! dependency of this crate, for `simulate_many`), built once per stepper
//! so a step pays no thread start-up.
//!
//! A copy whose step fails (the integrator gives up, a non-finite state)
//! does not stop the batch: its row of the result is its input state,
//! unchanged, and its entry of `errors` holds the message
//! `Simulation.step` would have raised. Bad input (shapes, negative or
//! non-finite tensions) raises `softrod.InputError` before any copy moves.

use nalgebra::DVector;
use numpy::{PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyList;
use rayon::prelude::*;

use crate::control::{CableInputs, check_joint_forces, check_substeps, check_tensions, step};
use crate::convert::{array, shaped};
use crate::errors::{dynamics, guard, input};
use crate::simulation::Simulation;

/// One copy: its model with the cables as inputs, and its run settings.
struct Copy {
    inputs: CableInputs,
    settings: softrod::Settings,
    /// The scene's prescribed curves (what `reset_prescribed` restores).
    scene_curves: Vec<softrod::dynamics::Curve>,
    /// The transitions of the last commanded targets (reused buffer).
    transitions: Vec<softrod::control::Transition>,
}

/// What one copy's step gave: the new `(q, q̇)`, or why it failed.
type Outcome = Result<(DVector<f64>, DVector<f64>), String>;

/// Many copies of cable-driven models stepped together.
///
/// `BatchStepper(sims, *, threads=None)`: one copy of each
/// `softrod.Simulation` in `sims` (its model and run settings, taken at
/// construction; the originals are not touched). All copies must have the
/// same `n_dof`, `n_cables` and `n_joint_inputs`. `threads`: the pool size (default: the
/// machine's cores).
///
/// `step(t, q, qdot, u, dt, active=None)` integrates every active copy
/// `dt` seconds from time `t` (a number or (n,)), coordinates `q` and
/// velocities `qdot` (n, n_dof) under cable tensions `u` (n, n_cables) [N,
/// finite and ≥ 0] held over the step (zero-order hold), with its
/// settings' integrator started afresh: row i equals
/// `sims[i].step(State(t_i, q_i, qdot_i), dt, u_i)` bit for bit (with
/// contact: when both carry the same contact state — a copy starts fresh,
/// keeps what its steps commit, and `reset_contact(i)` starts it over).
/// Returns
/// `(q, qdot, errors)`: the new states (n, n_dof) and a list of n
/// entries, None for a copy that stepped, else the message of its failure
/// (then its rows are its input state). `active` (n bools): copies to
/// step; the others are returned unchanged with error None. `substeps`:
/// as for `Simulation.step` (k fixed steps per call instead of adaptive
/// ones). `joint_forces` (n, n_joint_inputs) [N or N·m, finite]: the
/// joint actuators' forces held over the step, as `Simulation.step`'s
/// `joint_forces` (None: the actuators' schedules). The GIL is released
/// while the copies step.
///
/// `prescribed_targets` (n, n_prescribed) [rad or m]: the prescribed
/// joints' targets for `t + dt`, as `Simulation.step`'s
/// `prescribed_targets` (each copy's joints follow the cubic from their
/// position and rate at `t` under the motion in force on that copy to the
/// target at rest at `t + dt`; docs/envs.md). Each copy keeps its own
/// transitions from step to step (it starts with those of its
/// Simulation); `reset_prescribed(i)` puts the scene's curves back.
#[pyclass(module = "softrod")]
pub struct BatchStepper {
    copies: Vec<Copy>,
    n_dof: usize,
    n_cables: usize,
    n_joint_inputs: usize,
    n_prescribed: usize,
    /// Names of the actuated and prescribed coordinates (of copy 0), for
    /// messages.
    joint_input_names: Vec<String>,
    prescribed_names: Vec<String>,
    pool: rayon::ThreadPool,
}

impl BatchStepper {
    /// `(n,)` times from a number or a 1-D array.
    fn times(&self, t: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
        let n = self.copies.len();
        let ts = match t.extract::<f64>() {
            Ok(x) => vec![x; n],
            Err(_) => shaped(t, "t", &[n])?.slice().to_vec(),
        };
        if let Some((i, v)) = ts.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(input(format!("t[{i}] = {v}: times must be finite")));
        }
        Ok(ts)
    }
}

#[pymethods]
impl BatchStepper {
    #[new]
    #[pyo3(signature = (sims, *, threads = None))]
    fn new(sims: &Bound<'_, PyAny>, threads: Option<usize>) -> PyResult<Self> {
        guard(|| {
            let list = sims
                .cast::<PyList>()
                .map_err(|_| input("sims must be a list of softrod.Simulation"))?;
            if list.is_empty() {
                return Err(input("sims must hold at least one Simulation"));
            }
            let mut copies = Vec::with_capacity(list.len());
            let mut shape = None;
            let mut names = (Vec::new(), Vec::new());
            for (i, s) in list.iter().enumerate() {
                let s = s
                    .cast::<Simulation>()
                    .map_err(|_| input(format!("sims[{i}] is not a softrod.Simulation")))?;
                let s = s.borrow();
                let model = s.sim.model();
                let this = (
                    s.sim.n_dof(),
                    model.n_cables(),
                    model.n_joint_inputs(),
                    model.n_prescribed(),
                );
                let first = *shape.get_or_insert(this);
                if this != first {
                    return Err(input(format!(
                        "sims[{i}] has n_dof = {}, n_cables = {}, n_joint_inputs = {}, \
                         n_prescribed = {}, sims[0] {}, {}, {}, {}: a batch's copies must have \
                         the same sizes",
                        this.0, this.1, this.2, this.3, first.0, first.1, first.2, first.3
                    )));
                }
                if i == 0 {
                    names = (s.sim.joint_input_names(), s.sim.prescribed_names());
                }
                let settings = s.sim.settings().clone();
                // The model with the prescribed curves in force on the
                // simulation (a transition it was commanded included).
                let mut inputs = CableInputs::new(model).map_err(dynamics)?;
                inputs.sys.jacobian = settings.stiff_jacobian();
                inputs.tau_extra = None;
                copies.push(Copy {
                    inputs,
                    settings,
                    scene_curves: s.sim.scene_prescribed_curves(),
                    transitions: s.sim.prescribed_transitions().to_vec(),
                });
            }
            let (n_dof, n_cables, n_joint_inputs, n_prescribed) = shape.expect("at least one copy");
            let (joint_input_names, prescribed_names) = names;
            if threads == Some(0) {
                return Err(input("threads must be at least 1"));
            }
            let threads = threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| input(format!("cannot start {threads} threads: {e}")))?;
            Ok(Self {
                copies,
                n_dof,
                n_cables,
                n_joint_inputs,
                n_prescribed,
                joint_input_names,
                prescribed_names,
                pool,
            })
        })
    }

    /// Forgets the contact state of copy `i` (None: of every copy): the
    /// friction anchors and raised stiffnesses (docs/theory-contact.md CT5,
    /// CT15) its steps committed. Each copy carries its own contact state
    /// from step to step, as `Simulation.step` does; an episode that starts
    /// over on a copy (a vector env's reset or autoreset) calls this for
    /// it. Raises InputError for an index out of range.
    #[pyo3(signature = (i = None))]
    fn reset_contact(&mut self, i: Option<usize>) -> PyResult<()> {
        match i {
            None => self
                .copies
                .iter_mut()
                .for_each(|c| c.inputs.sys.data.reset_contact()),
            Some(i) => {
                let n = self.copies.len();
                let c = self.copies.get_mut(i).ok_or_else(|| {
                    input(format!(
                        "i = {i} is out of range: this stepper has {n} copies"
                    ))
                })?;
                c.inputs.sys.data.reset_contact();
            }
        }
        Ok(())
    }

    /// Puts the scene's prescribed curves back in force on copy `i` (None:
    /// on every copy) after `prescribed_targets` commanded others, as
    /// `Simulation.reset_prescribed` does: an episode that starts over on
    /// a copy calls this for it. Raises InputError for an index out of
    /// range.
    #[pyo3(signature = (i = None))]
    fn reset_prescribed(&mut self, i: Option<usize>) -> PyResult<()> {
        let n = self.copies.len();
        let range = match i {
            None => 0..n,
            Some(i) if i < n => i..i + 1,
            Some(i) => {
                return Err(input(format!(
                    "i = {i} is out of range: this stepper has {n} copies"
                )));
            }
        };
        for c in &mut self.copies[range] {
            for (k, curve) in c.scene_curves.iter().enumerate() {
                c.inputs
                    .sys
                    .model
                    .set_prescribed_curve(k, curve.clone())
                    .map_err(dynamics)?;
            }
            c.transitions.clear();
        }
        Ok(())
    }

    /// The targets in force on each copy (n, n_prescribed) [rad or m], NaN
    /// in the rows of copies still on the scene's curves.
    #[getter]
    fn prescribed_targets<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let (n, np) = (self.copies.len(), self.n_prescribed);
        let out = PyArray2::<f64>::zeros(py, [n, np], false);
        {
            let mut w = out.readwrite();
            let s = w.as_slice_mut().expect("new arrays are contiguous");
            for (i, c) in self.copies.iter().enumerate() {
                for k in 0..np {
                    s[i * np + k] = c.transitions.get(k).map_or(f64::NAN, |t| t.x1);
                }
            }
        }
        out
    }

    /// Prescribed joint coordinates of each copy.
    #[getter]
    fn n_prescribed(&self) -> usize {
        self.n_prescribed
    }

    /// Number of copies.
    fn __len__(&self) -> usize {
        self.copies.len()
    }

    /// Generalized coordinates of each copy.
    #[getter]
    fn n_dof(&self) -> usize {
        self.n_dof
    }

    /// Cables (tension inputs) of each copy.
    #[getter]
    fn n_cables(&self) -> usize {
        self.n_cables
    }

    /// Actuated joint coordinates (joint force inputs) of each copy.
    #[getter]
    fn n_joint_inputs(&self) -> usize {
        self.n_joint_inputs
    }

    /// Threads of the pool.
    #[getter]
    fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Steps every active copy `dt` seconds (see the class documentation).
    #[pyo3(signature = (t, q, qdot, u, dt, active = None, *, substeps = None, joint_forces = None,
                        prescribed_targets = None))]
    #[allow(clippy::type_complexity, clippy::too_many_arguments)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        t: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
        dt: f64,
        active: Option<Vec<bool>>,
        substeps: Option<usize>,
        joint_forces: Option<&Bound<'py, PyAny>>,
        prescribed_targets: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
        Vec<Option<String>>,
    )> {
        let (n, nd, nc) = (self.copies.len(), self.n_dof, self.n_cables);
        let ts = self.times(t)?;
        let q = shaped(q, "q", &[n, nd])?;
        let qd = shaped(qdot, "qdot", &[n, nd])?;
        let u = array(u, "u")?;
        if u.shape() != [n, nc] {
            return Err(input(format!(
                "u must have shape ({n}, {nc}) (one tension per cable and copy), got {:?}",
                u.shape()
            )));
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(input(format!("dt must be positive and finite, got {dt}")));
        }
        if let Some(k) = substeps {
            check_substeps(k).map_err(input)?;
        }
        let active = match active {
            Some(a) if a.len() != n => {
                return Err(input(format!(
                    "active must have {n} entries (one per copy), got {}",
                    a.len()
                )));
            }
            Some(a) => a,
            None => vec![true; n],
        };
        let us: Vec<&[f64]> = if nc == 0 {
            vec![&[][..]; n]
        } else {
            u.slice().chunks(nc).collect()
        };
        for (i, row) in us.iter().enumerate() {
            if active[i] {
                check_tensions(nc, &format!("u[{i}]"), row).map_err(input)?;
            }
        }
        let nj = self.n_joint_inputs;
        let fs: Option<Vec<Vec<f64>>> = match joint_forces {
            None => None,
            Some(f) => {
                let f = array(f, "joint_forces")?;
                if f.shape() != [n, nj] {
                    return Err(input(format!(
                        "joint_forces must have shape ({n}, {nj}) (one force per actuated \
                         joint coordinate and copy), got {:?}",
                        f.shape()
                    )));
                }
                let rows: Vec<Vec<f64>> = if nj == 0 {
                    vec![Vec::new(); n]
                } else {
                    f.slice().chunks(nj).map(<[f64]>::to_vec).collect()
                };
                for (i, row) in rows.iter().enumerate() {
                    if active[i] {
                        check_joint_forces(
                            &self.joint_input_names,
                            &format!("joint_forces[{i}]"),
                            row,
                        )
                        .map_err(input)?;
                    }
                }
                Some(rows)
            }
        };
        let np = self.n_prescribed;
        let ps: Option<Vec<Vec<f64>>> = match prescribed_targets {
            None => None,
            Some(_) if np == 0 => {
                return Err(input(
                    "prescribed_targets: these simulations have no prescribed joint (a scene \
                     joint with `prescribed = { times, values, bounds }`)",
                ));
            }
            Some(p) => {
                let p = array(p, "prescribed_targets")?;
                if p.shape() != [n, np] {
                    return Err(input(format!(
                        "prescribed_targets must have shape ({n}, {np}) (one target per \
                         prescribed joint coordinate {:?} and copy), got {:?}",
                        self.prescribed_names,
                        p.shape()
                    )));
                }
                let rows: Vec<Vec<f64>> = p.slice().chunks(np).map(<[f64]>::to_vec).collect();
                for (i, row) in rows.iter().enumerate() {
                    if active[i] {
                        softrod::control::targets::check_prescribed_targets(
                            &self.copies[i].inputs.sys.model,
                            &self.prescribed_names,
                            &format!("prescribed_targets[{i}]"),
                            row,
                        )
                        .map_err(crate::errors::to_py)?;
                    }
                }
                Some(rows)
            }
        };
        let prescribed_names = &self.prescribed_names;
        let rows = |a: &[f64]| -> Vec<DVector<f64>> {
            if nd == 0 {
                vec![DVector::zeros(0); n]
            } else {
                a.chunks(nd).map(DVector::from_column_slice).collect()
            }
        };
        let (q_in, qd_in) = (rows(q.slice()), rows(qd.slice()));
        let copies = &mut self.copies;
        let pool = &self.pool;
        let outcomes: Vec<Option<Outcome>> = py.detach(|| {
            pool.install(|| {
                copies
                    .par_iter_mut()
                    .enumerate()
                    .map(|(i, c)| {
                        if !active[i] {
                            return None;
                        }
                        c.inputs.u.clear();
                        c.inputs.u.extend_from_slice(us[i]);
                        match (&fs, &mut c.inputs.joint_forces) {
                            (None, jf) => *jf = None,
                            (Some(f), Some(jf)) => jf.copy_from_slice(&f[i]),
                            (Some(f), jf) => *jf = Some(f[i].clone()),
                        }
                        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                            if let Some(p) = &ps {
                                softrod::control::targets::command_prescribed_targets(
                                    &mut c.inputs.sys.model,
                                    prescribed_names,
                                    ts[i],
                                    dt,
                                    &p[i],
                                    &mut c.transitions,
                                )?;
                            }
                            step(
                                &mut c.inputs,
                                &c.settings,
                                ts[i],
                                dt,
                                &q_in[i],
                                &qd_in[i],
                                substeps,
                            )
                        }));
                        Some(match r {
                            Ok(Ok(state)) => Ok(state),
                            Ok(Err(e)) => Err(e.report()),
                            Err(_) => Err(format!(
                                "internal error in softrod (a Rust panic in copy {i} of a \
                                 BatchStepper step, please report it)"
                            )),
                        })
                    })
                    .collect()
            })
        });
        let q_out = PyArray2::<f64>::zeros(py, [n, nd], false);
        let qd_out = PyArray2::<f64>::zeros(py, [n, nd], false);
        let mut errors = vec![None; n];
        {
            let mut qw = q_out.readwrite();
            let mut qdw = qd_out.readwrite();
            let qs = qw.as_slice_mut().expect("new arrays are contiguous");
            let qds = qdw.as_slice_mut().expect("new arrays are contiguous");
            for (i, o) in outcomes.into_iter().enumerate() {
                let (a, b) = match &o {
                    Some(Ok((a, b))) => (a.as_slice(), b.as_slice()),
                    _ => (q_in[i].as_slice(), qd_in[i].as_slice()),
                };
                qs[i * nd..(i + 1) * nd].copy_from_slice(a);
                qds[i * nd..(i + 1) * nd].copy_from_slice(b);
                if let Some(Err(m)) = o {
                    errors[i] = Some(m);
                }
            }
        }
        Ok((q_out, qd_out, errors))
    }

    fn __repr__(&self) -> String {
        format!(
            "BatchStepper(copies={}, n_dof={}, n_cables={}, n_joint_inputs={}, threads={})",
            self.copies.len(),
            self.n_dof,
            self.n_cables,
            self.n_joint_inputs,
            self.pool.current_num_threads()
        )
    }
}
