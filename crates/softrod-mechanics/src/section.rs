//! Cross-sections: area and second moments, possibly varying along the rod.

use crate::error::{MechanicsError, Quantity, non_negative, positive};
use std::f64::consts::PI;

/// A rod cross-section in the local `(y, z)` plane (local x is the tangent).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Section {
    /// Solid circle of radius `radius` \[m\].
    Circle {
        /// Radius \[m\].
        radius: f64,
    },
    /// Hollow circle (tube): outer `radius`, `inner_radius` ∈ [0, radius) \[m\].
    Tube {
        /// Outer radius \[m\].
        radius: f64,
        /// Inner radius \[m\].
        inner_radius: f64,
    },
    /// Solid rectangle: `width` along local y, `height` along local z \[m\].
    Rectangle {
        /// Extent along local y \[m\].
        width: f64,
        /// Extent along local z \[m\].
        height: f64,
    },
    /// Solid circle whose radius varies linearly from `radius_base` at `s = 0`
    /// to `radius_tip` at `s = L`: `r(u) = r_b + (r_t − r_b) u`, `u = s/L`.
    TaperedCircle {
        /// Radius at the base \[m\].
        radius_base: f64,
        /// Radius at the tip \[m\].
        radius_tip: f64,
    },
}

/// Geometric properties of a section: area `A` \[m²\], second moments
/// `Jy = ∫z² dA`, `Jz = ∫y² dA` and `Jx = Jy + Jz` \[m⁴\].
///
/// `Jx` is the polar moment, the model's convention (docs/theory.md §0.5: torsional
/// stiffness `G·Jx`); for non-circular sections it is not the Saint-Venant
/// torsion constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionProperties {
    /// Area `A` \[m²\].
    pub area: f64,
    /// Second moment about local y, `∫ z² dA` \[m⁴\] (bending `ky`).
    pub jy: f64,
    /// Second moment about local z, `∫ y² dA` \[m⁴\] (bending `kz`).
    pub jz: f64,
    /// Polar moment `Jx = Jy + Jz` \[m⁴\] (torsion `kx`).
    pub jx: f64,
}

impl SectionProperties {
    fn circle(r: f64) -> Self {
        let j = PI * r.powi(4) / 4.0;
        Self {
            area: PI * r * r,
            jy: j,
            jz: j,
            jx: 2.0 * j,
        }
    }
}

impl Section {
    /// Checks that every dimension is positive and finite and that a tube's
    /// inner radius lies in `[0, radius)`.
    pub fn validate(&self) -> Result<(), MechanicsError> {
        match *self {
            Section::Circle { radius } => positive(Quantity::Radius, radius),
            Section::Tube {
                radius,
                inner_radius,
            } => {
                positive(Quantity::Radius, radius)?;
                non_negative(Quantity::InnerRadius, inner_radius)?;
                if inner_radius >= radius {
                    return Err(MechanicsError::InnerRadius {
                        inner: inner_radius,
                        outer: radius,
                    });
                }
                Ok(())
            }
            Section::Rectangle { width, height } => {
                positive(Quantity::Width, width)?;
                positive(Quantity::Height, height)
            }
            Section::TaperedCircle {
                radius_base,
                radius_tip,
            } => {
                positive(Quantity::BaseRadius, radius_base)?;
                positive(Quantity::TipRadius, radius_tip)
            }
        }
    }

    /// Properties at `u = s/L` (clamped to `[0, 1]`; only the taper depends on it).
    ///
    /// - circle: `A = πr²`, `Jy = Jz = πr⁴/4`;
    /// - tube: `A = π(R² − r²)`, `Jy = Jz = π(R⁴ − r⁴)/4`;
    /// - rectangle (`w` along y, `h` along z): `A = wh`, `Jy = wh³/12`, `Jz = hw³/12`;
    /// - taper: the circle at `r(u) = r_b + (r_t − r_b)u`;
    ///
    /// and `Jx = Jy + Jz` for all.
    #[inline]
    pub fn properties(&self, s_over_length: f64) -> SectionProperties {
        match *self {
            Section::Circle { radius } => SectionProperties::circle(radius),
            Section::Tube {
                radius,
                inner_radius,
            } => {
                let (r2, i2) = (radius * radius, inner_radius * inner_radius);
                let j = PI * (r2 * r2 - i2 * i2) / 4.0;
                SectionProperties {
                    area: PI * (r2 - i2),
                    jy: j,
                    jz: j,
                    jx: 2.0 * j,
                }
            }
            Section::Rectangle { width, height } => {
                let jy = width * height.powi(3) / 12.0;
                let jz = height * width.powi(3) / 12.0;
                SectionProperties {
                    area: width * height,
                    jy,
                    jz,
                    jx: jy + jz,
                }
            }
            Section::TaperedCircle { .. } => {
                SectionProperties::circle(self.outer_radius(s_over_length))
            }
        }
    }

    /// True when the properties do not depend on `s` (every section but the taper,
    /// and a taper with equal end radii). Uniform sections give constant
    /// per-piece `K_n`, `D_n` without quadrature (D13).
    #[inline]
    pub fn is_uniform(&self) -> bool {
        match *self {
            Section::TaperedCircle {
                radius_base,
                radius_tip,
            } => radius_base == radius_tip,
            _ => true,
        }
    }

    /// Radius of the smallest centred circle containing the section at `u = s/L`
    /// \[m\]: `r`, the outer radius, `½√(w² + h²)`, or `r(u)`.
    #[inline]
    pub fn outer_radius(&self, u: f64) -> f64 {
        match *self {
            Section::Rectangle { width, height } => 0.5 * width.hypot(height),
            _ => self.half_size(u),
        }
    }

    /// Half the largest extent of the section at `u = s/L` \[m\]: the (outer)
    /// radius of a circle, tube or taper, half the longer side of a
    /// rectangle. The size scale a rod's pieces should be long against.
    #[inline]
    pub fn half_size(&self, u: f64) -> f64 {
        match *self {
            Section::Circle { radius } | Section::Tube { radius, .. } => radius,
            Section::Rectangle { width, height } => 0.5 * width.max(height),
            Section::TaperedCircle {
                radius_base,
                radius_tip,
            } => {
                let u = u.clamp(0.0, 1.0);
                radius_base + (radius_tip - radius_base) * u
            }
        }
    }

    /// Whether the point `(y, z)` \[m\] of the section plane at `u = s/L` lies
    /// inside the section's outer boundary (boundary included). A tube's
    /// bore counts as inside (a cable may run in the lumen).
    pub fn contains(&self, u: f64, y: f64, z: f64) -> bool {
        match *self {
            Section::Rectangle { width, height } => {
                y.abs() <= 0.5 * width && z.abs() <= 0.5 * height
            }
            _ => y.hypot(z) <= self.half_size(u),
        }
    }
}
