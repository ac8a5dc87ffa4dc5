//! Kinematic queries: world poses and geometric Jacobians along a rod, one
//! abscissa or many, at the configuration `q` and the time `t` of the
//! prescribed joints. Every pose comes from the facade's `WorldPoses`.

use nalgebra::Matrix6xX;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use softrod::kinematics::Frame;
use softrod::record::WorldPoses;

use super::{Simulation, rod_index};
use crate::convert::{array, array_out, pose_into, vector};
use crate::errors::{input, to_py};

/// The frame named `name` ("body" or "world").
fn frame(name: &str) -> PyResult<Frame> {
    match name {
        "body" => Ok(Frame::Body),
        "world" | "spatial" => Ok(Frame::Spatial),
        other => Err(input(format!(
            "frame must be \"body\" or \"world\", got {other:?}"
        ))),
    }
}

/// The abscissae of `s`: one number (`true`) or a 1-D array.
fn abscissae(s: &Bound<'_, PyAny>) -> PyResult<(Vec<f64>, bool)> {
    match s.extract::<f64>() {
        Ok(x) => Ok((vec![x], true)),
        Err(_) => {
            let a = array(s, "s")?;
            if a.shape().len() != 1 {
                return Err(input(format!(
                    "s must be a number or 1-D, got shape {:?}",
                    a.shape()
                )));
            }
            Ok((a.slice().to_vec(), false))
        }
    }
}

/// What `along` evaluates at one abscissa: `f(sim, poses, rod, s, out)`.
type AtPoint<'a> = dyn Fn(&Simulation, &WorldPoses, usize, f64, &mut [f64]) -> PyResult<()> + 'a;

impl Simulation {
    /// Every world pose at `(t, q)`.
    pub(super) fn world_poses(&mut self, t: f64, q: &Bound<'_, PyAny>) -> PyResult<WorldPoses> {
        check_time(t)?;
        let q = vector(q, "q", self.n())?;
        self.sim.set_time(t);
        self.sim.world_poses(q.slice()).map_err(to_py)
    }

    /// Evaluates `f(poses, rod, s, out)` at one `s` (a number: shape
    /// `item`) or many (a 1-D array: shape `(len(s),) + item`).
    #[allow(clippy::too_many_arguments)]
    fn along<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        item: &[usize],
        f: &AtPoint<'_>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let poses = self.world_poses(t, q)?;
        let i = rod_index(self.sim.model(), rod)?;
        let (points, scalar) = abscissae(s)?;
        let size: usize = item.iter().product();
        let mut out = vec![0.0; size * points.len()];
        for (k, &x) in points.iter().enumerate() {
            f(self, &poses, i, x, &mut out[k * size..(k + 1) * size])?;
        }
        let mut shape = Vec::with_capacity(item.len() + 1);
        if !scalar {
            shape.push(points.len());
        }
        shape.extend_from_slice(item);
        array_out(py, out, &shape)
    }

    pub(super) fn pose_py<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        self.along(py, t, rod, s, q, &[4, 4], &|sim, poses, i, x, out| {
            let g = poses
                .pose_at(sim.sim.model(), i, x)
                .map_err(|e| input(format!("s = {x}: {}", e.report())))?;
            pose_into(&g, out);
            Ok(())
        })
    }

    pub(super) fn jacobian_py<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        rod: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
        q: &Bound<'py, PyAny>,
        frame_name: &str,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let f = frame(frame_name)?;
        let n = self.n();
        let qv = vector(q, "q", n)?.slice().to_vec();
        self.along(py, t, rod, s, q, &[6, n], &|sim, poses, i, x, out| {
            let model = sim.sim.model();
            let rm = &model.rods()[i];
            if model.is_articulated() {
                // Joints and ancestors move the section too.
                let j = sim
                    .sim
                    .jacobian(i, x, &qv, f)
                    .map_err(|e| input(format!("s = {x}: {}", e.report())))?;
                for row in 0..6 {
                    for c in 0..n {
                        out[row * n + c] = j[(row, c)];
                    }
                }
                return Ok(());
            }
            let mut local = Matrix6xX::zeros(rm.n_dof());
            poses
                .kinematics(i)
                .jacobian_at(&rm.spec.geometry, x, f, &mut local)
                .map_err(|e| input(format!("s = {x}: {e}")))?;
            for row in 0..6 {
                for c in 0..rm.n_dof() {
                    out[row * n + rm.dof_offset + c] = local[(row, c)];
                }
            }
            Ok(())
        })
    }
}

/// `t` must be finite.
pub(super) fn check_time(t: f64) -> PyResult<()> {
    if t.is_finite() {
        Ok(())
    } else {
        Err(input(format!("t must be finite, got {t}")))
    }
}
