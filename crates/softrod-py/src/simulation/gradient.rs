//! `Simulation.value_and_gradient`: exact trajectory gradients (the
//! facade's `Simulation::value_and_gradient`, docs/theory-control.md
//! G1–G9) with Python losses in and `(value, {param: gradient})` out.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use softrod::{GradientOptions, LossTerm};

use super::Simulation;
use crate::convert::{array, mat_out, vec_out, vector};
use crate::errors::{input, to_py};

/// The times of a loss term (`key` names it in errors).
fn times(obj: Option<Bound<'_, PyAny>>, key: &str) -> PyResult<Vec<f64>> {
    let obj = obj.ok_or_else(|| input(format!("{key} is missing")))?;
    let a = array(&obj, key)?;
    if a.shape().len() != 1 {
        return Err(input(format!("{key} must be a 1-D list of times")));
    }
    Ok(a.slice().to_vec())
}

/// A Python `ℓ(t, q, qdot) -> (value, dl_dq, dl_dqdot)` as a loss function.
fn callable<'py>(py: Python<'py>, f: Bound<'py, PyAny>, n: usize) -> Box<softrod::LossFn<'py>> {
    Box::new(move |t, q, qd| {
        let out = f
            .call1((t, vec_out(py, q), vec_out(py, qd)))
            .map_err(|e| format!("the loss function raised {e}"))?;
        let tuple = out
            .cast::<PyTuple>()
            .map_err(|_| "the loss function must return (value, dl_dq, dl_dqdot)".to_string())?;
        if tuple.len() != 3 {
            return Err("the loss function must return (value, dl_dq, dl_dqdot)".into());
        }
        let value: f64 = tuple
            .get_item(0)
            .and_then(|v| v.extract())
            .map_err(|_| "its value must be a number".to_string())?;
        let grad = |i: usize, name: &str| -> Result<Vec<f64>, String> {
            let item = tuple.get_item(i).map_err(|e| e.to_string())?;
            Ok(vector(&item, name, n)
                .map_err(|e| e.value(py).to_string())?
                .slice()
                .to_vec())
        };
        Ok((value, grad(1, "dl_dq")?, grad(2, "dl_dqdot")?))
    })
}

impl Simulation {
    pub(super) fn value_and_gradient_impl<'py>(
        &mut self,
        py: Python<'py>,
        loss: &Bound<'py, PyAny>,
        params: Vec<String>,
        duration: Option<f64>,
        loss_times: Option<Bound<'py, PyAny>>,
        options: GradientOptions,
    ) -> PyResult<(f64, Bound<'py, PyDict>)> {
        let n = self.sim.n_dof();
        let duration = duration.unwrap_or(self.sim.settings().duration);
        let items: Vec<Bound<'py, PyAny>> = match loss.cast::<PyList>() {
            Ok(list) => list.iter().collect(),
            Err(_) => vec![loss.clone()],
        };
        let mut terms = Vec::with_capacity(items.len());
        for (i, item) in items.into_iter().enumerate() {
            let key = |k: &str| format!("loss[{i}].{k}");
            if item.is_callable() {
                let t = times(loss_times.clone(), "times")?;
                terms.push(LossTerm::Custom {
                    times: t,
                    f: callable(py, item, n),
                });
                continue;
            }
            let d = item.cast::<PyDict>().map_err(|_| {
                input(format!(
                    "loss[{i}] must be a dict ({{\"type\": \"position\" | \"quadratic\", …}}) or a \
                     callable l(t, q, qdot) -> (value, dl_dq, dl_dqdot)"
                ))
            })?;
            let kind: String = d
                .get_item("type")?
                .ok_or_else(|| input(format!("{} is missing", key("type"))))?
                .extract()
                .map_err(|_| input(format!("{} must be a string", key("type"))))?;
            let allowed: &[&str] = match kind.as_str() {
                "position" => &["type", "rod", "s", "times", "targets", "weight"],
                "quadratic" => &["type", "times", "q_weights", "qdot_weights", "q_ref"],
                other => {
                    return Err(input(format!(
                        "{}: unknown loss {other:?} (position, quadratic)",
                        key("type")
                    )));
                }
            };
            for k in d.keys() {
                let k: String = k.extract()?;
                if !allowed.contains(&k.as_str()) {
                    return Err(input(format!(
                        "loss[{i}]: unknown key {k:?} ({})",
                        allowed.join(", ")
                    )));
                }
            }
            let t = times(d.get_item("times")?, &key("times"))?;
            let float = |k: &str, default: f64| -> PyResult<f64> {
                match d.get_item(k)? {
                    Some(v) => v
                        .extract::<f64>()
                        .map_err(|_| input(format!("{} must be a number", key(k)))),
                    None => Ok(default),
                }
            };
            let weights = |k: &str, default: f64| -> PyResult<Vec<f64>> {
                match d.get_item(k)? {
                    Some(v) => match v.extract::<f64>() {
                        Ok(x) => Ok(vec![x; n]),
                        Err(_) => Ok(vector(&v, &key(k), n)?.slice().to_vec()),
                    },
                    None => Ok(vec![default; n]),
                }
            };
            terms.push(match kind.as_str() {
                "position" => {
                    let rod = match d.get_item("rod")? {
                        Some(r) => match r.extract::<usize>() {
                            Ok(i) => self
                                .sim
                                .model()
                                .rods()
                                .get(i)
                                .map(|r| r.spec.name.clone())
                                .ok_or_else(|| input(format!("{}: no rod {i}", key("rod"))))?,
                            Err(_) => r
                                .extract::<String>()
                                .map_err(|_| input(format!("{} must be a name", key("rod"))))?,
                        },
                        None => self.sim.model().rods()[0].spec.name.clone(),
                    };
                    let s = match d.get_item("s")? {
                        Some(v) => Some(
                            v.extract::<f64>()
                                .map_err(|_| input(format!("{} must be a number", key("s"))))?,
                        ),
                        None => None,
                    };
                    let targets = d
                        .get_item("targets")?
                        .ok_or_else(|| input(format!("{} is missing", key("targets"))))?;
                    let a = crate::convert::shaped(&targets, &key("targets"), &[t.len(), 3])?;
                    let targets = a.slice().chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
                    LossTerm::Position {
                        rod,
                        s,
                        times: t,
                        targets,
                        weight: float("weight", 1.0)?,
                    }
                }
                _ => LossTerm::Quadratic {
                    times: t,
                    q_weights: weights("q_weights", 0.0)?,
                    qdot_weights: weights("qdot_weights", 0.0)?,
                    q_ref: match d.get_item("q_ref")? {
                        Some(v) => Some(vector(&v, &key("q_ref"), n)?.slice().to_vec()),
                        None => None,
                    },
                },
            });
        }
        let names: Vec<&str> = params.iter().map(String::as_str).collect();
        // The GIL stays held: a callable loss is called during the run.
        let g = self
            .sim
            .value_and_gradient(&mut terms, &names, duration, &options)
            .map_err(|e| {
                if e.is_input() {
                    input(e.report())
                } else {
                    to_py(e)
                }
            })?;
        let out = PyDict::new(py);
        for (name, v) in &g.gradients {
            // Material constants and masses as floats; the initial state and
            // the tension tables as arrays (whatever their length); a
            // prescribed joint's samples in the shape of its `values`: one
            // row per sample, one column per coordinate when it has more
            // than one.
            if let Some(element) = name.strip_suffix(".prescribed") {
                let dof = self
                    .sim
                    .model()
                    .elements()
                    .iter()
                    .find(|e| e.name == element)
                    .map_or(1, |e| e.attachment.joint.kind.dof());
                if dof > 1 {
                    let m = nalgebra::DMatrix::from_row_slice(v.len() / dof, dof, v);
                    out.set_item(name, mat_out(py, &m))?;
                } else {
                    out.set_item(name, vec_out(py, v))?;
                }
                continue;
            }
            // A joint actuator's force values (G29): a table in the shape
            // of its `values` (one row per time, one column per coordinate
            // when it has more than one), a constant as one value per
            // coordinate.
            if let Some(element) = name.strip_suffix(".actuator") {
                let joint = self
                    .sim
                    .model()
                    .elements()
                    .iter()
                    .find(|e| e.name == element)
                    .map(|e| &e.attachment.joint);
                let dof = joint.map_or(1, |j| j.kind.dof());
                let table = joint.and_then(|j| j.actuator.as_ref()).is_some_and(|a| {
                    matches!(a.force, softrod::dynamics::JointForce::Table { .. })
                });
                if table && dof > 1 {
                    let m = nalgebra::DMatrix::from_row_slice(v.len() / dof, dof, v);
                    out.set_item(name, mat_out(py, &m))?;
                } else {
                    out.set_item(name, vec_out(py, v))?;
                }
                continue;
            }
            let array = name == "q0" || name == "qdot0" || name.ends_with(".tension");
            if array {
                out.set_item(name, vec_out(py, v))?;
            } else {
                out.set_item(name, v[0])?;
            }
        }
        Ok((g.value, out))
    }
}
