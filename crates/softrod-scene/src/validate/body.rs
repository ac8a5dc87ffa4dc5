//! `rod[i].section`, `.material`, `.drag`: the file's keys into the
//! library's `Section`, `Material` and `Drag` (which check the values).

use softrod_mechanics::{Drag, Material, Section};

use super::{Ctx, Result};
use crate::keys;
use crate::raw::{RawDrag, RawMaterial, RawSection};

impl Ctx<'_> {
    /// The shape and the keys that apply to it.
    pub(super) fn section(&self, p: &str, s: RawSection) -> Result<Section> {
        let given = [
            ("radius", s.radius),
            ("radius_base", s.radius_base),
            ("radius_tip", s.radius_tip),
            ("inner_radius", s.inner_radius),
            ("width", s.width),
            ("height", s.height),
        ];
        let (allowed, keys): (&[&str], &str) = match s.shape.as_str() {
            "circle" => (
                &["radius", "radius_base", "radius_tip"],
                "radius, or radius_base and radius_tip",
            ),
            "tube" => (&["radius", "inner_radius"], "radius and inner_radius"),
            "rectangle" => (&["width", "height"], "width and height"),
            other => {
                return Err(self.r.unknown_name(
                    &format!("{p}.shape"),
                    other,
                    &["circle", "tube", "rectangle"],
                ));
            }
        };
        for (k, v) in given {
            if v.is_some() && !allowed.contains(&k) {
                return Err(self.r.invalid(
                    &format!("{p}.{k}"),
                    format!(
                        "key {k:?} does not apply to shape {:?} (it takes {keys})",
                        s.shape
                    ),
                ));
            }
        }
        let path = |k: &str| format!("{p}.{k}");
        let required = |k: &str, v: Option<f64>| v.ok_or_else(|| self.r.missing(&path(k), ""));
        match s.shape.as_str() {
            "circle" => match (s.radius, s.radius_base, s.radius_tip) {
                (Some(radius), None, None) => Ok(Section::Circle { radius }),
                (None, Some(radius_base), Some(radius_tip)) => Ok(Section::TaperedCircle {
                    radius_base,
                    radius_tip,
                }),
                (None, None, None) => Err(self
                    .r
                    .missing(&path("radius"), " (or radius_base and radius_tip)")),
                (None, Some(_), None) => Err(self.r.missing(
                    &path("radius_tip"),
                    " (a tapered circle needs radius_base and radius_tip)",
                )),
                (None, None, Some(_)) => Err(self.r.missing(
                    &path("radius_base"),
                    " (a tapered circle needs radius_base and radius_tip)",
                )),
                (Some(_), _, _) => Err(self.r.invalid(
                    &path("radius"),
                    "give either radius or radius_base and radius_tip, not both",
                )),
            },
            "tube" => Ok(Section::Tube {
                radius: required("radius", s.radius)?,
                inner_radius: required("inner_radius", s.inner_radius)?,
            }),
            _ => Ok(Section::Rectangle {
                width: required("width", s.width)?,
                height: required("height", s.height)?,
            }),
        }
    }

    /// `owner.material` through the library's builder.
    pub(super) fn material(&self, owner: &str, m: RawMaterial) -> Result<Material> {
        let mut b = Material::builder().density(m.density).young(m.young);
        if let Some(nu) = m.poisson {
            b = b.poisson(nu);
        }
        if let Some(g) = m.shear_modulus {
            b = b.shear_modulus(g);
        }
        if let Some(mu) = m.viscosity {
            b = b.viscosity(mu);
        }
        b.build()
            .map_err(|e| keys::mechanics(&self.r, owner, f64::NAN, e))
    }
}

/// The drag term, only when a coefficient is non-zero (a model holds only
/// the terms a scene has).
pub(super) fn drag(d: Option<RawDrag>) -> Option<Drag> {
    let d = d?;
    let drag = Drag {
        translational: d.translational.unwrap_or(0.0),
        rotational: d.rotational.unwrap_or(0.0),
    };
    (drag.translational != 0.0 || drag.rotational != 0.0).then_some(drag)
}
