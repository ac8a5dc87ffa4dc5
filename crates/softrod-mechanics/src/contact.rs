//! Contact descriptions: the rigid obstacles rods cannot enter and the
//! settings of rod–rod and self contact (scene contract, section "Contact").
//!
//! This module describes; it does not compute forces. A rod's contact
//! surface is the swept sphere of its centreline (radius
//! [`contact_radius`]); an obstacle is one of the analytic [`Shape`]s, given
//! in its parent's frame (the world, or a body that carries it). The force
//! law, its derivatives and the friction state live with the dynamics
//! (`docs/theory-contact.md`).

use softrod_lie::{Mat3, Vec3};

use crate::section::Section;

/// The geometry of an obstacle, in its parent's frame \[m\].
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Half-space `{x : (x − point)·normal ≥ 0}` is free; rods stay on the
    /// side `normal` points to. `normal` is a unit vector.
    Plane {
        /// A point of the plane.
        point: Vec3,
        /// Unit outward normal.
        normal: Vec3,
    },
    /// A ball.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius, > 0.
        radius: f64,
    },
    /// An infinite round cylinder whose axis passes through `point`.
    Cylinder {
        /// A point of the axis.
        point: Vec3,
        /// Unit axis direction.
        axis: Vec3,
        /// Radius, > 0.
        radius: f64,
    },
    /// The points within `radius` of the segment of `length` along `axis`
    /// centred at `center`.
    Capsule {
        /// Centre of the segment.
        center: Vec3,
        /// Unit axis direction.
        axis: Vec3,
        /// Length of the segment (0: a sphere), ≥ 0.
        length: f64,
        /// Radius, > 0.
        radius: f64,
    },
    /// A box `{center + rotation · y : |y_i| ≤ half_extents_i}`.
    Box {
        /// Centre.
        center: Vec3,
        /// Rotation from the box's axes to the parent frame (orthonormal,
        /// determinant +1).
        rotation: Mat3,
        /// Half extents along the box's axes, each > 0.
        half_extents: Vec3,
    },
}

impl Shape {
    /// The contract's name of the shape (`"plane"`, `"sphere"`, …).
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Plane { .. } => "plane",
            Shape::Sphere { .. } => "sphere",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Capsule { .. } => "capsule",
            Shape::Box { .. } => "box",
        }
    }

    /// Checks the description: finite numbers, positive radii and extents,
    /// non-negative capsule length, unit (within 1e-9) normals and axes,
    /// an orthonormal right-handed rotation (within 1e-9).
    ///
    /// Zero vectors are errors, not normalized: a direction of length 0
    /// has no meaning. Callers that accept unnormalized directions
    /// normalize them first with [`unit()`].
    pub fn validate(&self) -> Result<(), ObstacleError> {
        let finite = |what: &'static str, v: &Vec3| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(ObstacleError::NotFinite { what })
            }
        };
        let positive = |what: &'static str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(ObstacleError::NotPositive { what, value: x })
            }
        };
        let unit_vector = |what: &'static str, v: &Vec3| {
            finite(what, v)?;
            if (v.norm() - 1.0).abs() <= 1e-9 {
                Ok(())
            } else {
                Err(ObstacleError::NotUnit {
                    what,
                    norm: v.norm(),
                })
            }
        };
        match self {
            Shape::Plane { point, normal } => {
                finite("position", point)?;
                unit_vector("normal", normal)
            }
            Shape::Sphere { center, radius } => {
                finite("position", center)?;
                positive("radius", *radius)
            }
            Shape::Cylinder {
                point,
                axis,
                radius,
            } => {
                finite("position", point)?;
                unit_vector("axis", axis)?;
                positive("radius", *radius)
            }
            Shape::Capsule {
                center,
                axis,
                length,
                radius,
            } => {
                finite("position", center)?;
                unit_vector("axis", axis)?;
                if !(length.is_finite() && *length >= 0.0) {
                    return Err(ObstacleError::Negative {
                        what: "length",
                        value: *length,
                    });
                }
                positive("radius", *radius)
            }
            Shape::Box {
                center,
                rotation,
                half_extents,
            } => {
                finite("position", center)?;
                if !rotation.iter().all(|x| x.is_finite()) {
                    return Err(ObstacleError::NotFinite { what: "rotation" });
                }
                let error = (rotation.transpose() * rotation - Mat3::identity())
                    .abs()
                    .max();
                if error > 1e-9 || rotation.determinant() < 0.0 {
                    return Err(ObstacleError::NotRotation { error });
                }
                for i in 0..3 {
                    positive("half_extents", half_extents[i])?;
                }
                Ok(())
            }
        }
    }
}

/// `v / |v|`, or an error naming `what` if `v` is zero or not finite.
pub fn unit(what: &'static str, v: Vec3) -> Result<Vec3, ObstacleError> {
    let n = v.norm();
    if !n.is_finite() {
        return Err(ObstacleError::NotFinite { what });
    }
    if n == 0.0 {
        return Err(ObstacleError::ZeroVector { what });
    }
    Ok(v / n)
}

/// A rigid obstacle (scene `[[obstacle]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    /// Name, for messages and outputs.
    pub name: String,
    /// Geometry in the parent's frame.
    pub shape: Shape,
    /// Name of the body that carries it; `None`: fixed in the world.
    pub parent: Option<String>,
    /// Coulomb coefficient with rods, ≥ 0.
    pub friction: f64,
    /// Coefficient of restitution of normal impacts, in `[0, 1]`.
    pub restitution: f64,
}

impl Obstacle {
    /// A frictionless, inelastic obstacle fixed in the world.
    pub fn new(name: impl Into<String>, shape: Shape) -> Self {
        Self {
            name: name.into(),
            shape,
            parent: None,
            friction: 0.0,
            restitution: 0.0,
        }
    }

    /// Carried by the body `parent`.
    pub fn on(mut self, parent: impl Into<String>) -> Self {
        self.parent = Some(parent.into());
        self
    }

    /// With Coulomb coefficient `mu`.
    pub fn friction(mut self, mu: f64) -> Self {
        self.friction = mu;
        self
    }

    /// With coefficient of restitution `e`.
    pub fn restitution(mut self, e: f64) -> Self {
        self.restitution = e;
        self
    }

    /// Checks the shape and the coefficients.
    pub fn validate(&self) -> Result<(), ObstacleError> {
        self.shape.validate()?;
        coefficients(self.friction, self.restitution)
    }
}

/// Contact of rods with rods (scene `[contact]`). The default: none.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactSettings {
    /// Different rods touch each other.
    pub rods: bool,
    /// A rod touches itself (pieces a joint or an attachment holds
    /// together excepted).
    pub self_contact: bool,
    /// Coulomb coefficient between rods, ≥ 0.
    pub friction: f64,
    /// Coefficient of restitution between rods, in `[0, 1]`.
    pub restitution: f64,
}

impl ContactSettings {
    /// True if any rod–rod or self contact is on.
    pub fn any(&self) -> bool {
        self.rods || self.self_contact
    }

    /// Checks the coefficients.
    pub fn validate(&self) -> Result<(), ObstacleError> {
        coefficients(self.friction, self.restitution)
    }
}

fn coefficients(friction: f64, restitution: f64) -> Result<(), ObstacleError> {
    if !(friction.is_finite() && friction >= 0.0) {
        return Err(ObstacleError::Negative {
            what: "friction",
            value: friction,
        });
    }
    if !(restitution.is_finite() && (0.0..=1.0).contains(&restitution)) {
        return Err(ObstacleError::Restitution { value: restitution });
    }
    Ok(())
}

/// The radius of a rod's contact surface at arc length `s` \[m\]: the
/// outer radius of a circle or tube, a taper's local radius, half the
/// diagonal of a rectangle (the contract's default; a scene may set
/// `contact_radius` instead).
pub fn contact_radius(section: &Section, s: f64, length: f64) -> f64 {
    match *section {
        Section::Circle { radius } => radius,
        Section::Tube { radius, .. } => radius,
        Section::Rectangle { width, height } => 0.5 * (width * width + height * height).sqrt(),
        Section::TaperedCircle {
            radius_base,
            radius_tip,
        } => {
            let x = if length > 0.0 {
                (s / length).clamp(0.0, 1.0)
            } else {
                0.0
            };
            radius_base + (radius_tip - radius_base) * x
        }
    }
}

/// What a rod touches at a [`ContactPoint`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Contactee {
    /// The obstacle of this index (in the model's obstacle list).
    Obstacle(usize),
    /// Rod `rod` (index in the model's rods) at its arc length `s` \[m\].
    Rod {
        /// The other rod's index.
        rod: usize,
        /// Arc length on it \[m\].
        s: f64,
    },
}

/// One resolved contact at a state: pure data for outputs (scene contract,
/// "Contact", the `contacts` entries). World frame, SI units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactPoint {
    /// Index of the rod `a` that is touched (in the model's rods).
    pub a: usize,
    /// Material arc length on rod `a` \[m\].
    pub s: f64,
    /// What touches it.
    pub b: Contactee,
    /// The contact point on `a`'s surface (its centreline point less the
    /// contact radius along `normal`), world \[m\].
    pub point: Vec3,
    /// Unit normal from `b` to `a`, world.
    pub normal: Vec3,
    /// Distance between the two surfaces \[m\]; negative: penetration.
    pub gap: f64,
    /// Force on `a`, world \[N\] (`b` feels its opposite).
    pub force: Vec3,
    /// Friction sticks (`true`) or slides (`false`; also for frictionless
    /// contacts).
    pub sticking: bool,
}

/// What is wrong with an obstacle or the contact settings. `what` is the
/// contract's key (`radius`, `normal`, `axis`, `half_extents`, `length`,
/// `friction`, `position`, `rotation`), so a scene loader can point at it.
#[non_exhaustive]
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ObstacleError {
    /// A quantity that must be positive and finite is not.
    #[error("{what} must be positive and finite, got {value}")]
    NotPositive {
        /// The key.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// A quantity that must be non-negative and finite is not.
    #[error("{what} must be non-negative and finite, got {value}")]
    Negative {
        /// The key.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// NaN or infinity.
    #[error("{what} is not finite")]
    NotFinite {
        /// The key.
        what: &'static str,
    },
    /// A zero direction.
    #[error("{what} is the zero vector: it has no direction")]
    ZeroVector {
        /// The key.
        what: &'static str,
    },
    /// A direction that should be a unit vector is not.
    #[error("{what} must be a unit vector, its length is {norm}")]
    NotUnit {
        /// The key.
        what: &'static str,
        /// Its length.
        norm: f64,
    },
    /// A box rotation that is not orthonormal and right-handed.
    #[error(
        "rotation is not a rotation matrix (RᵀR − I reaches {error:.3e}, or det R < 0): give an \
         orthonormal right-handed matrix"
    )]
    NotRotation {
        /// Largest entry of |RᵀR − I|.
        error: f64,
    },
    /// A restitution outside `[0, 1]`.
    #[error("restitution must lie in [0, 1], got {value}")]
    Restitution {
        /// The value.
        value: f64,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_checked() {
        let z = Vec3::z();
        assert!(
            Shape::Plane {
                point: Vec3::zeros(),
                normal: z
            }
            .validate()
            .is_ok()
        );
        assert_eq!(
            Shape::Plane {
                point: Vec3::zeros(),
                normal: 2.0 * z
            }
            .validate(),
            Err(ObstacleError::NotUnit {
                what: "normal",
                norm: 2.0
            })
        );
        assert!(matches!(
            Shape::Sphere {
                center: Vec3::zeros(),
                radius: 0.0
            }
            .validate(),
            Err(ObstacleError::NotPositive { what: "radius", .. })
        ));
        let skew = Mat3::new(1.0, 0.1, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(matches!(
            Shape::Box {
                center: Vec3::zeros(),
                rotation: skew,
                half_extents: Vec3::repeat(1.0)
            }
            .validate(),
            Err(ObstacleError::NotRotation { .. })
        ));
        let mirror = Mat3::from_diagonal(&Vec3::new(1.0, 1.0, -1.0));
        assert!(
            Shape::Box {
                center: Vec3::zeros(),
                rotation: mirror,
                half_extents: Vec3::repeat(1.0)
            }
            .validate()
            .is_err()
        );
        assert_eq!(
            unit("axis", Vec3::zeros()),
            Err(ObstacleError::ZeroVector { what: "axis" })
        );
        assert_eq!(unit("axis", 3.0 * z), Ok(z));
    }

    #[test]
    fn coefficients_are_checked() {
        let table = Obstacle::new(
            "t",
            Shape::Plane {
                point: Vec3::zeros(),
                normal: Vec3::z(),
            },
        );
        assert!(
            table
                .clone()
                .friction(0.5)
                .restitution(1.0)
                .validate()
                .is_ok()
        );
        assert!(table.clone().friction(-0.1).validate().is_err());
        assert!(table.restitution(1.5).validate().is_err());
    }

    #[test]
    fn contact_radius_follows_the_section() {
        let rect = Section::Rectangle {
            width: 0.06,
            height: 0.08,
        };
        assert!((contact_radius(&rect, 0.0, 1.0) - 0.05).abs() < 1e-15);
        let taper = Section::TaperedCircle {
            radius_base: 0.02,
            radius_tip: 0.01,
        };
        assert!((contact_radius(&taper, 0.5, 1.0) - 0.015).abs() < 1e-15);
    }
}
