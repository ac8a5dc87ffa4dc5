//! Dynamics evaluations with longer bodies: those that take cable tensions
//! `u` besides the schedules (evaluated on the model with tension inputs,
//! `crate::control`), and the Coriolis force.

use nalgebra::DVector;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use softrod::dynamics::coriolis_matrix;

use super::Simulation;
use crate::convert::{mat_out, vec_out, vector};
use crate::errors::{dynamics, guard, to_py};

/// `(A, B)` of a linearization.
type StateSpace<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

impl Simulation {
    pub(super) fn forward_dynamics_impl<'py>(
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
                inputs.joint_forces = None;
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

    pub(super) fn inverse_dynamics_impl<'py>(
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
                inputs.joint_forces = None;
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

    pub(super) fn linearize_impl<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        q: &Bound<'py, PyAny>,
        qdot: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<StateSpace<'py>> {
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

    pub(super) fn coriolis_force_impl<'py>(
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
}
