//! `Simulation.solve_actuation`: inverse statics (the facade's
//! `Simulation::solve_actuation`, docs/theory-control.md IS1–IS12) with
//! Python targets in and a dict out.

use numpy::PyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use softrod::control::{ActuationOptions, Target, UnknownLoad};

use super::{Simulation, rod_index};
use crate::convert::{array_out, mat3, vec_out, vec3, vector};
use crate::errors::{guard_detached, input, simulation, to_py};

/// The keyword arguments of `solve_actuation` besides the targets.
pub(super) struct Settings<'a, 'py> {
    pub max_tension: Option<&'a Bound<'py, PyAny>>,
    pub effort_weight: f64,
    pub reach_tolerance: f64,
    pub max_iterations: usize,
    pub warm_start: Option<&'a Bound<'py, PyDict>>,
    pub t: f64,
    pub unknown_loads: Option<&'a Bound<'py, PyAny>>,
}

impl Simulation {
    pub(super) fn solve_actuation_impl<'py>(
        &mut self,
        py: Python<'py>,
        targets: &Bound<'py, PyAny>,
        settings: Settings<'_, 'py>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let model = self.sim.model();
        let nc = model.n_cables();
        let list = targets
            .cast::<PyList>()
            .map_err(|_| input("targets must be a list of dicts"))?;
        let mut parsed = Vec::with_capacity(list.len());
        for (i, item) in list.iter().enumerate() {
            let key = |k: &str| format!("targets[{i}].{k}");
            let d = item
                .cast::<PyDict>()
                .map_err(|_| input(format!("targets[{i}] must be a dict")))?;
            for k in d.keys() {
                let k: String = k.extract()?;
                if !["rod", "s", "body", "position", "rotation", "weight"].contains(&k.as_str()) {
                    return Err(input(format!(
                        "targets[{i}]: unknown key {k:?} (rod, s, body, position, rotation, weight)"
                    )));
                }
            }
            // A body's target is its frame (IS11): no rod, no arc length.
            let body = match d.get_item("body")? {
                Some(b) => {
                    for k in ["rod", "s"] {
                        if d.contains(k)? {
                            return Err(input(format!(
                                "{}: a target on a body takes no {k:?} (its frame is the target)",
                                key(k)
                            )));
                        }
                    }
                    Some(
                        body_index(model, &b)
                            .map_err(|e| input(format!("{}: {}", key("body"), e.value(py))))?,
                    )
                }
                None => None,
            };
            let rod = match d.get_item("rod")? {
                Some(r) => rod_index(model, &r)
                    .map_err(|e| input(format!("{}: {}", key("rod"), e.value(py))))?,
                None => 0,
            };
            let length = match body {
                Some(_) => 0.0,
                None => model.rods()[rod].spec.geometry.length(),
            };
            let s = match d.get_item("s")? {
                Some(v) => v
                    .extract::<f64>()
                    .map_err(|_| input(format!("{} must be a number", key("s"))))?,
                None => length,
            };
            let position = match d.get_item("position")? {
                Some(p) => Some(vec3(&p, &key("position"))?.into()),
                None => None,
            };
            let rotation = match d.get_item("rotation")? {
                Some(r) => Some(mat3(&r, &key("rotation"))?),
                None => None,
            };
            let weight = match d.get_item("weight")? {
                Some(w) => w
                    .extract::<f64>()
                    .map_err(|_| input(format!("{} must be a number", key("weight"))))?,
                None => 1.0,
            };
            parsed.push(Target {
                rod,
                s,
                body,
                position,
                rotation,
                weight,
            });
        }
        let max_tension = match settings.max_tension {
            None => Vec::new(),
            Some(m) => match m.extract::<f64>() {
                Ok(v) => vec![v; nc],
                Err(_) => vector(m, "max_tension", nc)?.slice().to_vec(),
            },
        };
        let unknown_loads = match settings.unknown_loads {
            None => self.sim.scene_unknown_loads().to_vec(),
            Some(v) => unknown_loads(model, v)?,
        };
        let nu = unknown_loads.len();
        let nj = model.n_joint_inputs();
        let (initial_tensions, initial_q, initial_forces, initial_joint_forces) =
            match settings.warm_start {
                None => (None, None, None, None),
                Some(w) => {
                    let get = |k: &str, n: usize| -> PyResult<Vec<f64>> {
                        let v = w.get_item(k)?.ok_or_else(|| {
                            input(format!("warm_start must be a previous result (no {k:?})"))
                        })?;
                        Ok(vector(&v, &format!("warm_start[{k:?}]"), n)?
                            .slice()
                            .to_vec())
                    };
                    // A previous result of the same problem has them; one
                    // of another (or a hand-made dict) may not: start those
                    // from the defaults.
                    let forces = match w.get_item("forces")? {
                        Some(f) if nu > 0 => Some(
                            vector(
                                &f.call_method0("flatten")?,
                                "warm_start[\"forces\"]",
                                3 * nu,
                            )?
                            .slice()
                            .chunks_exact(3)
                            .map(|c| [c[0], c[1], c[2]])
                            .collect::<Vec<_>>(),
                        ),
                        _ => None,
                    };
                    let joints = match w.get_item("joint_forces")? {
                        Some(f) => Some(
                            vector(&f, "warm_start[\"joint_forces\"]", nj)?
                                .slice()
                                .to_vec(),
                        ),
                        None => None,
                    };
                    (
                        Some(get("tensions", nc)?),
                        Some(get("q", model.n_dof())?),
                        forces,
                        joints,
                    )
                }
            };
        let options = ActuationOptions {
            max_tension,
            effort_weight: settings.effort_weight,
            reach_tolerance: settings.reach_tolerance,
            max_iterations: settings.max_iterations,
            initial_tensions,
            initial_q,
            initial_forces,
            initial_joint_forces,
            unknown_loads,
            time: settings.t,
            ..ActuationOptions::default()
        };
        // Errors in the library's words, with the Python argument names.
        let sim = &mut self.sim;
        let a = guard_detached(py, || {
            sim.solve_actuation(&parsed, &options).map_err(|e| {
                let text = e.report().replace("target[", "targets[");
                if e.is_input() { input(text) } else { to_py(e) }
            })
        })?;
        if !a.converged {
            return Err(simulation(
                format!(
                    "solve_actuation: {} (tensions {:?})",
                    a.message,
                    a.tensions.as_slice()
                ),
                None,
            ));
        }
        let out = PyDict::new(py);
        out.set_item("converged", a.converged)?;
        out.set_item("reached", a.reached)?;
        out.set_item("message", &a.message)?;
        out.set_item("tensions", vec_out(py, a.tensions.as_slice()))?;
        out.set_item("q", vec_out(py, a.q.as_slice()))?;
        out.set_item("iterations", a.iterations)?;
        out.set_item("statics_iterations", a.statics_iterations)?;
        out.set_item("residual", a.target_error)?;
        out.set_item("cost", a.cost)?;
        out.set_item("effort_weight", a.effort_weight)?;
        let bounds: Vec<&str> = a.bounds.iter().map(|b| b.name()).collect();
        out.set_item("bounds", bounds)?;
        let forces: Vec<f64> = a.forces.iter().flat_map(|f| f.iter().copied()).collect();
        let forces: Bound<'_, PyArrayDyn<f64>> = array_out(py, forces, &[a.forces.len(), 3])?;
        out.set_item("forces", forces)?;
        let force_bounds: Vec<Vec<&str>> = a
            .force_bounds
            .iter()
            .map(|b| b.iter().map(|x| x.name()).collect())
            .collect();
        out.set_item("force_bounds", force_bounds)?;
        out.set_item("joint_forces", vec_out(py, &a.joint_forces))?;
        let joint_bounds: Vec<&str> = a.joint_force_bounds.iter().map(|b| b.name()).collect();
        out.set_item("joint_force_bounds", joint_bounds)?;
        let per = PyList::empty(py);
        for r in &a.residuals {
            let d = PyDict::new(py);
            d.set_item("position", vec_out(py, r.position.as_slice()))?;
            let rot: Vec<f64> = (0..3)
                .flat_map(|i| (0..3).map(move |j| (i, j)))
                .map(|(i, j)| r.rotation[(i, j)])
                .collect();
            let m: Bound<'_, PyArrayDyn<f64>> = array_out(py, rot, &[3, 3])?;
            d.set_item("rotation", m)?;
            d.set_item("position_error", r.position_error)?;
            d.set_item("rotation_error", r.rotation_error)?;
            per.append(d)?;
        }
        out.set_item("targets", per)?;
        Ok(out)
    }
}

/// `unknown_loads=`: a list of dicts `{"rod": name or index, "s": arc
/// length [m] (default the tip), "max_force": a number or three (default
/// none)}`.
fn unknown_loads(
    model: &softrod::dynamics::Model,
    v: &Bound<'_, PyAny>,
) -> PyResult<Vec<UnknownLoad>> {
    let py = v.py();
    let list = v
        .cast::<PyList>()
        .map_err(|_| input("unknown_loads must be a list of dicts"))?;
    let mut out = Vec::with_capacity(list.len());
    for (i, item) in list.iter().enumerate() {
        let key = |k: &str| format!("unknown_loads[{i}].{k}");
        let d = item
            .cast::<PyDict>()
            .map_err(|_| input(format!("unknown_loads[{i}] must be a dict")))?;
        for k in d.keys() {
            let k: String = k.extract()?;
            if !["rod", "s", "max_force"].contains(&k.as_str()) {
                return Err(input(format!(
                    "unknown_loads[{i}]: unknown key {k:?} (rod, s, max_force)"
                )));
            }
        }
        let rod = match d.get_item("rod")? {
            Some(r) => rod_index(model, &r)
                .map_err(|e| input(format!("{}: {}", key("rod"), e.value(py))))?,
            None => 0,
        };
        let s = match d.get_item("s")? {
            Some(v) => v
                .extract::<f64>()
                .map_err(|_| input(format!("{} must be a number", key("s"))))?,
            None => model.rods()[rod].spec.geometry.length(),
        };
        let max = match d.get_item("max_force")? {
            None => [f64::INFINITY; 3],
            Some(m) => match m.extract::<f64>() {
                Ok(x) => [x; 3],
                Err(_) => vec3(&m, &key("max_force"))?,
            },
        };
        if let Some(k) = (0..3).find(|&k| max[k].is_nan() || max[k] < 0.0) {
            return Err(input(format!(
                "{}[{k}] must be >= 0, got {}",
                key("max_force"),
                max[k]
            )));
        }
        out.push(UnknownLoad {
            rod,
            s,
            min: max.map(|m| -m),
            max,
        });
    }
    Ok(out)
}

/// The index of a body given by name or index (negative from the end) in
/// [`softrod::dynamics::Model::bodies`].
fn body_index(model: &softrod::dynamics::Model, body: &Bound<'_, PyAny>) -> PyResult<usize> {
    let n = model.bodies().len();
    if let Ok(name) = body.cast::<pyo3::types::PyString>() {
        let name = name.to_str()?;
        return model
            .bodies()
            .iter()
            .position(|b| b.spec.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = model
                    .bodies()
                    .iter()
                    .map(|b| b.spec.name.as_str())
                    .collect();
                input(format!("no body {name:?} (bodies: {names:?})"))
            });
    }
    let i: isize = body
        .extract()
        .map_err(|_| input("body must be a body name or an index"))?;
    let k = if i < 0 { i + n as isize } else { i };
    if !(0..n as isize).contains(&k) {
        return Err(input(format!("body index {i} out of range for {n} bodies")));
    }
    Ok(k as usize)
}
