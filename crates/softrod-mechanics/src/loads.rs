//! External loads: gravity, point loads, distributed loads, viscous drag (D14).
//!
//! Every load returns a body-frame wrench `(M, N)` at the section it acts on
//! (moment first). Densities are per unit undeformed length [N·m/m, N/m];
//! point loads are in N·m and N. The dynamics layer projects them with `Jᵀ`.
//! All hot functions are `#[inline]`, allocation-free and cost a few 3×3
//! products at most.

use crate::error::{MechanicsError, finite, non_negative};
use softrod_lie::{Pose, Twist, Vec3, Wrench, angular, join, linear};

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

/// Uniform gravity field: world acceleration `g_w` [m/s²], any direction
/// (e.g. `(0, 0, −9.81)`); the seed's `𝒢 = (0; g_w)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gravity {
    /// World-frame gravitational acceleration `g_w` [m/s²].
    pub acceleration: Vec3,
}

fn finite3(what: &str, v: &Vec3) -> Result<(), MechanicsError> {
    for (c, x) in ["x", "y", "z"].iter().zip(v.iter()) {
        finite(&format!("{what} {c}"), *x)?;
    }
    Ok(())
}

impl Gravity {
    /// Checks that the acceleration is finite.
    pub fn validate(&self) -> Result<(), MechanicsError> {
        finite3("gravity [m/s^2]", &self.acceleration)
    }

    /// Body wrench density (D14) `𝓕_g = 𝓜 Ad⁻¹_g 𝒢 = (0; ρA Rᵀ g_w)` [N/m],
    /// for mass per length `ρA` [kg/m] and the section's world pose `g = (R, p)`.
    /// Conservative, potential density `−ρA g_w·p`.
    #[inline]
    pub fn wrench_density(&self, mass_per_length: f64, pose: &Pose) -> Wrench {
        let f = pose.rotation.tr_mul(&self.acceleration) * mass_per_length;
        Wrench::new(0.0, 0.0, 0.0, f[0], f[1], f[2])
    }
}

/// A concentrated force `f` [N] and moment `m` [N·m] applied at abscissa `s` [m].
///
/// `frame = World`: dead load (fixed world direction); `Body`: follower load.
/// Dead forces are conservative (`V = −f·p(s)`); dead moments in 3D and all
/// follower loads are not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLoad {
    /// Material abscissa of the point of application [m], in `[0, L]`.
    pub s: f64,
    /// Force [N], components in `frame`.
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
                what: "point load".into(),
                s: self.s,
                length: rod_length,
            });
        }
        finite3("point load force [N]", &self.force)?;
        finite3("point load moment [N m]", &self.moment)
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
        finite3("distributed force [N/m]", &self.force)?;
        finite3("distributed moment [N m/m]", &self.moment)
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
        non_negative(
            "translational drag coefficient [N s/m^2]",
            self.translational,
        )?;
        non_negative("rotational drag coefficient [N m s/m]", self.rotational)
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

/// The distributed (per-unit-length) terms behind one interface, so a model
/// can hold a `Vec<LineLoad>` of exactly the terms its scene has and evaluate
/// them without trait objects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LineLoad {
    /// Gravity (needs the pose and `ρA`).
    Gravity(Gravity),
    /// A uniformly distributed force/moment (needs the pose if World).
    Distributed(DistributedLoad),
    /// Viscous drag (needs the velocity).
    Drag(Drag),
}

impl LineLoad {
    /// Body wrench density at a section with mass per length `ρA` [kg/m],
    /// world pose `pose` and body velocity `eta` (D14); dispatches to the
    /// variant's `wrench_density`.
    #[inline]
    pub fn wrench_density(&self, mass_per_length: f64, pose: &Pose, eta: &Twist) -> Wrench {
        match self {
            LineLoad::Gravity(g) => g.wrench_density(mass_per_length, pose),
            LineLoad::Distributed(d) => d.wrench_density(pose),
            LineLoad::Drag(d) => d.wrench_density(eta),
        }
    }

    /// True if the wrench depends on the velocity (it then belongs to the
    /// velocity-dependent part of the dynamics and to `∂/∂q̇` in implicit solvers).
    #[inline]
    pub fn depends_on_velocity(&self) -> bool {
        matches!(self, LineLoad::Drag(_))
    }

    /// True if the load derives from a potential (gravity; a world-frame
    /// distributed force with zero moment).
    pub fn is_conservative(&self) -> bool {
        match self {
            LineLoad::Gravity(_) => true,
            LineLoad::Distributed(d) => d.frame == LoadFrame::World && d.moment == Vec3::zeros(),
            LineLoad::Drag(_) => false,
        }
    }
}
