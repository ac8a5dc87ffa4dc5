//! Contacts as Python sees them (docs/theory-contact.md; scene-format.md,
//! "Contact"): one `softrod.Contact` per active contact point, the
//! entries of `statics --json`'s `contacts` and of `contacts.csv`.

use numpy::PyArray1;
use pyo3::prelude::*;
use softrod::dynamics::Model;
use softrod::mechanics::{ContactPoint, Contactee};

use crate::convert::vec_out;

/// One contact at a state (world frame, SI): rod `rod` (its name; index
/// `rod_index`) at arc length `s` [m] touches `other` — an obstacle (its
/// name; `other_kind` "obstacle", `other_s` None) or a rod (`other_kind`
/// "rod", `other_s` its arc length [m]); `other_index` indexes the
/// simulation's obstacles or rods. `point` [m]: the contact point on the
/// rod's surface; `normal`: unit, from `other` to the rod; `gap` [m]: the
/// distance between the surfaces (negative: penetration); `force` [N]: the
/// force on the rod (`other` feels its opposite); `sticking`: friction
/// holds (False: it slides, or the contact is frictionless), `state`
/// "stick" or "slip" as in `contacts.csv`.
#[pyclass(frozen, module = "softrod")]
pub struct Contact {
    #[pyo3(get)]
    rod: String,
    #[pyo3(get)]
    rod_index: usize,
    #[pyo3(get)]
    s: f64,
    #[pyo3(get)]
    other: String,
    #[pyo3(get)]
    other_kind: &'static str,
    #[pyo3(get)]
    other_index: usize,
    #[pyo3(get)]
    other_s: Option<f64>,
    point: [f64; 3],
    normal: [f64; 3],
    #[pyo3(get)]
    gap: f64,
    force: [f64; 3],
    #[pyo3(get)]
    sticking: bool,
}

impl Contact {
    /// The Python view of contact `c` of `model`.
    pub fn new(model: &Model, c: &ContactPoint) -> Self {
        let v3 = |v: &softrod::lie::Vec3| [v[0], v[1], v[2]];
        let (other, other_kind, other_index, other_s) = match c.b {
            Contactee::Obstacle(k) => (model.obstacles()[k].name.clone(), "obstacle", k, None),
            Contactee::Rod { rod, s } => (model.rods()[rod].spec.name.clone(), "rod", rod, Some(s)),
        };
        Self {
            rod: model.rods()[c.a].spec.name.clone(),
            rod_index: c.a,
            s: c.s,
            other,
            other_kind,
            other_index,
            other_s,
            point: v3(&c.point),
            normal: v3(&c.normal),
            gap: c.gap,
            force: v3(&c.force),
            sticking: c.sticking,
        }
    }

    /// The list of a state's contacts.
    pub fn list(model: &Model, contacts: &[ContactPoint]) -> Vec<Self> {
        contacts.iter().map(|c| Self::new(model, c)).collect()
    }
}

#[pymethods]
impl Contact {
    /// The contact point on the rod's surface (3,) [m, world].
    #[getter]
    fn point<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_out(py, &self.point)
    }

    /// The unit normal from `other` to the rod (3,) [world].
    #[getter]
    fn normal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_out(py, &self.normal)
    }

    /// The force on the rod (3,) [N, world].
    #[getter]
    fn force<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec_out(py, &self.force)
    }

    /// "stick" or "slip" (the `state` column of contacts.csv).
    #[getter]
    fn state(&self) -> &'static str {
        if self.sticking { "stick" } else { "slip" }
    }

    fn __repr__(&self) -> String {
        let other = match self.other_s {
            Some(s) => format!("{:?} at s={s:.6}", self.other),
            None => format!("{:?}", self.other),
        };
        format!(
            "Contact(rod={:?}, s={:.6}, other={other}, gap={:.3e}, force=[{:.6e}, {:.6e}, {:.6e}], \
             state={:?})",
            self.rod,
            self.s,
            self.gap,
            self.force[0],
            self.force[1],
            self.force[2],
            self.state()
        )
    }
}
