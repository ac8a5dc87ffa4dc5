//! `[[target]]` (where `softrod inverse` should bring a rod section) and
//! `[[cable]] max_tension` (the bound of its tension there).

use softrod_dynamics::Rod;
use softrod_lie::{Mat3, Vec3};

use super::{Ctx, Result};
use crate::robot::Robot;
use crate::scene::Target;

/// A `[[target]]` table as written.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTarget {
    pub element: String,
    pub s: Option<f64>,
    pub position: Option<[f64; 3]>,
    pub rotation: Option<[[f64; 3]; 3]>,
    pub weight: Option<f64>,
}

impl Ctx<'_> {
    /// `target[j]`: a rod of the scene (bodies are not targets yet), `s`
    /// in `[0, L]` (default the tip), a position, a rotation (row-major,
    /// orthonormal like a box's) or both, a positive weight (default 1).
    pub(super) fn target(
        &self,
        j: usize,
        t: RawTarget,
        rods: &[Rod],
        robot: &Robot,
    ) -> Result<Target> {
        let p = format!("target[{j}]");
        let path = |k: &str| format!("{p}.{k}");
        if robot.bodies.iter().any(|b| b.name == t.element) {
            return Err(self.r.invalid(
                &path("element"),
                format!(
                    "{:?} is a body: targets on bodies are not supported yet (name a rod)",
                    t.element
                ),
            ));
        }
        let rod = self.rod_ref(&path("element"), &t.element, rods)?;
        let length = rods[rod].properties.length();
        let s = t.s.unwrap_or(length);
        if !(0.0..=length).contains(&s) {
            return Err(self.r.out_of_range(
                &path("s"),
                s,
                format!("in [0, {length}] (the rod's length)"),
            ));
        }
        if t.position.is_none() && t.rotation.is_none() {
            return Err(self.r.missing(&path("position"), " (or rotation, or both)"));
        }
        let rotation = match t.rotation {
            Some(r) => Some(self.box_rotation(&path("rotation"), Some(r))?),
            None => None,
        };
        let weight = match t.weight {
            Some(w) => self.positive(&path("weight"), w)?,
            None => 1.0,
        };
        Ok(Target {
            element: t.element,
            rod,
            s,
            position: t.position.map(Vec3::from),
            rotation: rotation.map(|r: Mat3| r),
            weight,
        })
    }

    /// `cable[j].max_tension`: `≥ 0` N when given.
    pub(super) fn max_tension(&self, j: usize, v: Option<f64>) -> Result<Option<f64>> {
        match v {
            Some(m) if m < 0.0 => {
                Err(self
                    .r
                    .out_of_range(&format!("cable[{j}].max_tension"), m, "≥ 0 (N)"))
            }
            other => Ok(other),
        }
    }
}
