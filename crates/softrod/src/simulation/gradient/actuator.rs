//! The derivatives with respect to a joint actuator's force values
//! (docs/theory-control.md G29).
//!
//! An actuator adds `+f(t)` to its joint's generalized forces (IS14), so
//! the inverse dynamics is affine in its values: `∂ID/∂xᵢ = −e_j wᵢ(t)`,
//! `j` the coordinate and `wᵢ(t)` the weight of value `i` in `f_j(t)` (1
//! for a constant; a table's piecewise-linear hat). Nothing to linearize:
//! the adjoint's product is `z_j wᵢ(t)`, a forward sensitivity's column
//! `M⁻¹ e_j wᵢ(t)` (a closed model: `P M⁻¹`, G22).

use softrod_dynamics::{JointForce, Model};

use super::params::{bad, element_index};
use crate::error::Result;

/// The element `element` of `model` whose joint carries an actuator: its
/// index and its gradient length (one entry per coordinate for a constant
/// force, per row and coordinate for a table, in the scene's `values`
/// order). Errors name `name`.
pub(crate) fn parse(model: &Model, name: &str, element: &str) -> Result<(usize, usize)> {
    let e = element_index(model, name, element)?;
    let info = &model.elements()[e];
    let Some(actuator) = &info.attachment.joint.actuator else {
        return Err(bad(
            name,
            format!(
                "the joint of '{element}' has no actuator (give it `actuator = {{ force = … }}`)"
            ),
        ));
    };
    let k = info.joint_dofs.len();
    let len = match &actuator.force {
        JointForce::Constant(_) => k,
        JointForce::Table { times, .. } => times.len() * k,
    };
    Ok((e, len))
}

/// One `ELEMENT.actuator` parameter.
#[derive(Debug)]
pub(crate) struct ActuatorParam {
    /// The first slot among the system's parameters; entry `(i, c)` (row
    /// `i`, coordinate `c`) is `slot + i·k + c`.
    slot: usize,
    /// The joint's first coordinate in `q` and its count `k`.
    first: usize,
    k: usize,
    /// A table's times (empty for a constant force).
    times: Vec<f64>,
}

impl ActuatorParam {
    /// The actuator of element `element` (checked by [`parse`]) at `slot`.
    pub(crate) fn new(model: &Model, element: usize, slot: usize) -> Self {
        let info = &model.elements()[element];
        let times = match &info.attachment.joint.actuator {
            Some(a) => match &a.force {
                JointForce::Constant(_) => Vec::new(),
                JointForce::Table { times, .. } => times.clone(),
            },
            None => unreachable!("checked by parse"),
        };
        Self {
            slot,
            first: info.joint_dofs.start,
            k: info.joint_dofs.len(),
            times,
        }
    }

    /// The slots of every entry.
    pub(crate) fn slots(&self) -> std::ops::Range<usize> {
        self.slot..self.slot + self.k * self.times.len().max(1)
    }

    /// Every entry whose weight at `t` is not zero: its slot, its
    /// coordinate in `q` and the weight `wᵢ(t) = ∂f_j(t)/∂xᵢ` (the linear
    /// interpolation of [`JointForce::at`], held outside the table).
    pub(crate) fn weights(&self, t: f64) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let rows: [(usize, f64); 2] = if self.times.is_empty() {
            [(0, 1.0), (0, 0.0)]
        } else {
            let last = self.times.len() - 1;
            if t <= self.times[0] {
                [(0, 1.0), (0, 0.0)]
            } else if t >= self.times[last] {
                [(last, 1.0), (last, 0.0)]
            } else {
                let i = self.times.partition_point(|&x| x <= t);
                let (t0, t1) = (self.times[i - 1], self.times[i]);
                let w = (t - t0) / (t1 - t0);
                [(i - 1, 1.0 - w), (i, w)]
            }
        };
        rows.into_iter()
            .filter(|&(_, w)| w != 0.0)
            .flat_map(move |(i, w)| {
                (0..self.k).map(move |c| (self.slot + i * self.k + c, self.first + c, w))
            })
    }
}
