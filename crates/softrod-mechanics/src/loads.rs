//! External loads: point loads, distributed loads, viscous drag (D14).
//! Gravity is a base acceleration of the dynamics layer (`Model::gravity`).
//!
//! Every load returns a body-frame wrench `(M, N)` at the section it acts on
//! (moment first). Densities are per unit undeformed length [N·m/m, N/m];
//! point loads are in N·m and N. The dynamics layer projects them with `Jᵀ`.
//! All hot functions are `#[inline]`, allocation-free and cost a few 3×3
//! products at most.

use crate::error::{MechanicsError, Quantity, finite3, non_negative};
use softrod_lie::{Pose, Twist, Vec3, Wrench, angular, join, linear};
use std::fmt;
use std::str::FromStr;

/// The frame a load's components are given in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LoadFrame {
    /// World axes: a dead load, fixed in direction as the rod moves
    /// (rotated into the body frame by `R(s)ᵀ`).
    World,
    /// Body (section) axes: a follower load that turns with the section.
    Body,
}

impl LoadFrame {
    /// The scene-file name (`"world"`, `"body"`).
    pub fn name(self) -> &'static str {
        match self {
            LoadFrame::World => "world",
            LoadFrame::Body => "body",
        }
    }

    /// Body-frame components of a vector `v` given in this frame at a section
    /// with pose `pose`: `Rᵀ v` (World) or `v` (Body).
    #[inline]
    pub fn to_body(self, pose: &Pose, v: &Vec3) -> Vec3 {
        match self {
            LoadFrame::World => pose.rotation.tr_mul(v),
            LoadFrame::Body => *v,
        }
    }
}

impl fmt::Display for LoadFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for LoadFrame {
    type Err = MechanicsError;

    /// `"world"` or `"body"`; anything else is [`MechanicsError::UnknownLoadFrame`].
    fn from_str(name: &str) -> Result<Self, Self::Err> {
        match name {
            "world" => Ok(LoadFrame::World),
            "body" => Ok(LoadFrame::Body),
            _ => Err(MechanicsError::UnknownLoadFrame {
                name: name.to_owned(),
            }),
        }
    }
}

/// A concentrated force `f` \[N\] and moment `m` [N·m] applied at abscissa `s` \[m\].
///
/// `frame = World`: dead load (fixed world direction); `Body`: follower load.
/// Dead forces are conservative (`V = −f·p(s)`); dead moments in 3D and all
/// follower loads are not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLoad {
    /// Material abscissa of the point of application \[m\], in `[0, L]`.
    pub s: f64,
    /// Force \[N\], components in `frame`.
    pub force: Vec3,
    /// Moment [N·m], components in `frame`.
    pub moment: Vec3,
    /// Frame of `force` and `moment`.
    pub frame: LoadFrame,
}

impl PointLoad {
    /// Checks `0 ≤ s ≤ L` (to 1e-12·L) and finite force and moment.
    pub fn validate(&self, rod_length: f64) -> Result<(), MechanicsError> {
        let tol = 1e-12 * rod_length;
        if !(self.s >= -tol && self.s <= rod_length + tol) {
            return Err(MechanicsError::OutOfRod {
                quantity: Quantity::LoadPosition,
                s: self.s,
                length: rod_length,
            });
        }
        finite3(Quantity::Force, &self.force)?;
        finite3(Quantity::Moment, &self.moment)
    }

    /// Applied body wrench at `s` (D14): `(Rᵀ m_w; Rᵀ f_w)` for a dead load,
    /// `(m; f)` for a follower load [N·m; N]. `pose` is the world pose `g(s)`.
    #[inline]
    pub fn wrench(&self, pose: &Pose) -> Wrench {
        join(
            &self.frame.to_body(pose, &self.moment),
            &self.frame.to_body(pose, &self.force),
        )
    }
}

/// A load uniformly distributed along the rod: force density [N/m] and
/// moment density [N·m/m] per unit undeformed length, components in `frame`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistributedLoad {
    /// Force per unit length [N/m].
    pub force: Vec3,
    /// Moment per unit length [N·m/m].
    pub moment: Vec3,
    /// Frame of the components (World: dead; Body: follower).
    pub frame: LoadFrame,
}

impl DistributedLoad {
    /// Checks finite force and moment densities.
    pub fn validate(&self) -> Result<(), MechanicsError> {
        finite3(Quantity::ForceDensity, &self.force)?;
        finite3(Quantity::MomentDensity, &self.moment)
    }

    /// Body wrench density (D14): `(Rᵀ m; Rᵀ f)` (World) or `(m; f)` (Body).
    #[inline]
    pub fn wrench_density(&self, pose: &Pose) -> Wrench {
        join(
            &self.frame.to_body(pose, &self.moment),
            &self.frame.to_body(pose, &self.force),
        )
    }
}

/// Linear viscous drag of the surrounding medium, per unit length:
/// `−c_t v` on the body linear velocity and `−c_r ω` on the body angular
/// velocity. Dissipative: power `−c_t|v|² − c_r|ω|²` per unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drag {
    /// Translational coefficient `c_t` [N·s/m²].
    pub translational: f64,
    /// Rotational coefficient `c_r` [N·m·s/m].
    pub rotational: f64,
}

impl Drag {
    /// Checks `c_t, c_r ≥ 0`, finite.
    pub fn validate(&self) -> Result<(), MechanicsError> {
        non_negative(Quantity::TranslationalDrag, self.translational)?;
        non_negative(Quantity::RotationalDrag, self.rotational)
    }

    /// Body wrench density `(−c_r ω; −c_t v)` for the body velocity `η = (ω, v)`.
    #[inline]
    pub fn wrench_density(&self, eta: &Twist) -> Wrench {
        join(
            &(angular(eta) * -self.rotational),
            &(linear(eta) * -self.translational),
        )
    }
}
