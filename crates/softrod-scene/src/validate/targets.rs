//! `[[target]]` (where `softrod inverse` should bring a rod section or a
//! body's frame) and
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
    /// `target[j]`: a rod of the scene with `s` in `[0, L]` (default the
    /// tip), or a `[[body]]` (its frame; `s` is an error there), a
    /// position, a rotation (row-major, orthonormal like a box's) or both,
    /// a positive weight (default 1).
    pub(super) fn target(
        &self,
        j: usize,
        t: RawTarget,
        rods: &[Rod],
        robot: &Robot,
    ) -> Result<Target> {
        let p = format!("target[{j}]");
        let path = |k: &str| format!("{p}.{k}");
        let body = robot.bodies.iter().position(|b| b.name == t.element);
        let (rod, s) = match body {
            Some(_) => {
                if let Some(s) = t.s {
                    return Err(self.r.invalid(
                        &path("s"),
                        format!(
                            "{:?} is a body: its target is the body's frame, which has no arc \
                             length (remove `s = {s}`)",
                            t.element
                        ),
                    ));
                }
                (0, 0.0)
            }
            None if rods.iter().any(|r| r.name == t.element) => {
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
                (rod, s)
            }
            None => {
                let known: Vec<&str> = rods
                    .iter()
                    .map(|r| r.name.as_str())
                    .chain(robot.bodies.iter().map(|b| b.name.as_str()))
                    .collect();
                return Err(self.r.invalid(
                    &path("element"),
                    format!(
                        "{:?} is no rod or body of the scene (rods and bodies: {})",
                        t.element,
                        known.join(", ")
                    ),
                ));
            }
        };
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
            body,
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
