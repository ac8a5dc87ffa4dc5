//! Statics and modes from Python (the GIL released while they run).

use numpy::PyArrayDyn;
use pyo3::prelude::*;
use softrod::Equilibrium;

use super::{Simulation, rod_index};
use crate::control::check_tensions;
use crate::convert::{array_out, pose_into, vec_out, vector};
use crate::errors::{guard_detached, input, to_py};
use crate::model::PointLoad;
use crate::results::{Modes, Statics, modes_py};

impl Simulation {
    pub(super) fn statics_impl(
        &mut self,
        py: Python<'_>,
        tensions: Option<&Bound<'_, PyAny>>,
        loads: Option<&Bound<'_, PyAny>>,
        joint_forces: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Statics> {
        let jf = match joint_forces {
            Some(f) => Some(self.joint_forces(f)?),
            None => None,
        };
        let n_cables = self.sim.n_cables();
        let u = match tensions {
            Some(t) => {
                let u = vector(t, "tensions", n_cables)?.slice().to_vec();
                check_tensions(n_cables, "tensions", &u).map_err(input)?;
                Some(u)
            }
            None => None,
        };
        // Extra point loads make a variant of the model for this solve only
        // (the model is immutable; the simulation keeps its own).
        let mut variant = match loads {
            Some(l) => self.with_loads(l)?,
            None => None,
        };
        let sim = variant.as_mut().unwrap_or(&mut self.sim);
        let out = guard_detached(py, || {
            let previous = sim.cable_tensions().map(<[f64]>::to_vec);
            let previous_joints = sim.joint_forces().map(<[f64]>::to_vec);
            if let Some(u) = &u {
                sim.set_cable_tensions(Some(u)).map_err(to_py)?;
            }
            if let Some(f) = &jf {
                sim.set_joint_forces(Some(f)).map_err(to_py)?;
            }
            let result = solve(sim);
            if u.is_some() {
                sim.set_cable_tensions(previous.as_deref()).map_err(to_py)?;
            }
            if jf.is_some() {
                sim.set_joint_forces(previous_joints.as_deref())
                    .map_err(to_py)?;
            }
            result
        })?;
        // What `statics --json` lists (its `contacts`, `max_penetration`),
        // with the contact stiffness the solve raised (CT15).
        let zero = vec![0.0; out.q.len()];
        let found = sim
            .contacts(0.0, &out.q, &zero)
            .map_err(crate::errors::to_py)?;
        let model = sim.model();
        let max_penetration = found.iter().fold(0.0, |m, c| f64::max(m, -c.gap));
        let contacts = crate::contacts::Contact::list(model, &found)
            .into_iter()
            .map(|c| Py::new(py, c))
            .collect::<PyResult<Vec<_>>>()?;
        let pose = |g: &softrod::lie::Pose| -> PyResult<Py<PyArrayDyn<f64>>> {
            let mut m = vec![0.0; 16];
            pose_into(g, &mut m);
            Ok(array_out(py, m, &[4, 4])?.unbind())
        };
        let tips = model
            .rods()
            .iter()
            .enumerate()
            .map(|(i, r)| Ok((r.spec.name.clone(), pose(out.poses.tip(i))?)))
            .collect::<PyResult<Vec<_>>>()?;
        let bodies = model
            .bodies()
            .iter()
            .zip(out.poses.bodies())
            .map(|(b, g)| Ok((b.spec.name.clone(), pose(g)?)))
            .collect::<PyResult<Vec<_>>>()?;
        Ok(Statics {
            q: vec_out(py, &out.q).unbind(),
            converged: true,
            iterations: out.iterations,
            residual: out.residual,
            load_steps: out.load_steps,
            stable: out.stable,
            tip: pose(out.poses.tip(0))?,
            tips,
            bodies,
            closures: out.closures.into_iter().collect(),
            warnings: out.warnings,
            contacts,
            max_penetration,
        })
    }

    /// The simulation with `loads`, a list of `(rod, softrod.PointLoad)`
    /// pairs, added to its model (same initial state and limits); `None`
    /// for an empty list.
    fn with_loads(&self, loads: &Bound<'_, PyAny>) -> PyResult<Option<softrod::Simulation>> {
        let mut model = self.sim.model().clone();
        let mut any = false;
        for (k, item) in loads.try_iter()?.enumerate() {
            let item = item?;
            let (rod, load): (Bound<'_, PyAny>, PyRef<'_, PointLoad>) =
                item.extract().map_err(|_| {
                    input(format!(
                        "loads[{k}] must be a (rod, softrod.PointLoad) pair, rod a name or an index"
                    ))
                })?;
            let i = rod_index(&model, &rod)?;
            model = model
                .with_point_loads(i, vec![load.inner])
                .map_err(|e| input(format!("loads[{k}]: {e}")))?;
            any = true;
        }
        if !any {
            return Ok(None);
        }
        let mut sim = softrod::Simulation::new(model);
        let (q0, qd0) = self.sim.initial_state();
        sim.set_initial_state(q0.as_slice(), qd0.as_slice())
            .map_err(to_py)?;
        sim.set_limits(*self.sim.limits());
        Ok(Some(sim))
    }

    pub(super) fn modes_impl(&mut self, py: Python<'_>) -> PyResult<Modes> {
        let sim = &mut self.sim;
        let m = guard_detached(py, || sim.modes().map_err(to_py))?;
        let (eq, q) = match &m.equilibrium {
            Equilibrium::Rest => ("rest", vec![0.0; self.n()]),
            Equilibrium::Statics(q) => ("statics", q.as_slice().to_vec()),
        };
        Ok(modes_py(py, &m.modes, eq, &q, m.warnings.clone()))
    }

    pub(super) fn lowest_modes_impl(&mut self, py: Python<'_>, count: usize) -> PyResult<Modes> {
        let sim = &mut self.sim;
        let m = guard_detached(py, || sim.lowest_modes(count).map_err(to_py))?;
        let (eq, q) = match &m.equilibrium {
            Equilibrium::Rest => ("rest", vec![0.0; self.n()]),
            Equilibrium::Statics(q) => ("statics", q.as_slice().to_vec()),
        };
        Ok(modes_py(py, &m.modes, eq, &q, m.warnings.clone()))
    }

    pub(super) fn modes_about_impl(
        &mut self,
        py: Python<'_>,
        q: &Bound<'_, PyAny>,
    ) -> PyResult<Modes> {
        let qv = vector(q, "q", self.n())?.slice().to_vec();
        let sim = &mut self.sim;
        let m = guard_detached(py, || sim.modes_about(&qv).map_err(to_py))?;
        Ok(modes_py(py, &m, "given", &qv, Vec::new()))
    }
}

/// Largest model whose equilibrium `statics()` checks for stability with a
/// modal analysis (dense eigenproblem), as `softrod statics` does.
const STABILITY_CHECK_MAX_DOF: usize = 600;

/// A solved equilibrium with what is reported beside it.
struct Solved {
    q: Vec<f64>,
    iterations: usize,
    residual: f64,
    load_steps: usize,
    stable: Option<bool>,
    poses: softrod::record::WorldPoses,
    closures: Vec<(String, f64)>,
    warnings: Vec<String>,
}

/// Statics at t = 0, then the stability, poses and closure residuals of
/// the equilibrium (what `softrod statics --json` reports).
fn solve(sim: &mut softrod::Simulation) -> PyResult<Solved> {
    sim.set_time(0.0);
    let result = sim.statics().map_err(to_py)?;
    let q = result.q.as_slice();
    // Newton finds equilibria, stable or not (a soft rod under gravity has
    // an unstable upright one): check the lowest linearized mode when that
    // is affordable (O(n_dof³)).
    // Rigid (zero) modes are neutral, not unstable (docs/theory.md E7).
    let modes = (sim.n_dof() <= STABILITY_CHECK_MAX_DOF)
        .then(|| sim.modes_about(q))
        .and_then(Result::ok);
    let mut warnings = result.warnings.clone();
    if let Some(m) = modes.as_ref().filter(|m| m.n_unstable() > 0) {
        let w = m.omega.min();
        warnings.push(format!(
            "this equilibrium is unstable (lowest linearized ω² = {:.3e} rad²/s²); a stable \
             one may exist nearby: start statics from another initial q",
            -w * w
        ));
    }
    Ok(Solved {
        stable: modes.as_ref().map(|m| m.n_unstable() == 0),
        poses: sim.world_poses(q).map_err(to_py)?,
        closures: sim.closure_residuals(q).map_err(to_py)?,
        warnings,
        q: q.to_vec(),
        iterations: result.iterations,
        residual: result.residual,
        load_steps: result.load_steps,
    })
}
