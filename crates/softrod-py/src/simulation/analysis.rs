//! Statics and modes from Python (the GIL released while they run).

use pyo3::prelude::*;
use softrod::Equilibrium;

use super::Simulation;
use crate::convert::{vec_out, vector};
use crate::errors::{guard_detached, to_py};
use crate::results::{Modes, Statics, modes_py};

impl Simulation {
    pub(super) fn statics_impl(&mut self, py: Python<'_>) -> PyResult<Statics> {
        let sim = &mut self.sim;
        let r = guard_detached(py, || sim.statics().map_err(to_py))?;
        Ok(Statics {
            q: vec_out(py, r.q.as_slice()).unbind(),
            iterations: r.iterations,
            residual: r.residual,
            load_steps: r.load_steps,
            warnings: r.warnings,
        })
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
