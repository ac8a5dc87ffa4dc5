//! Aliases used across softrod, so signatures say what they hold.
//!
//! All 6-vectors are ordered **angular first**: `(ω, v)`, `(k, q)`, `(M, N)`.

use nalgebra as na;

/// A 3-vector (m, rad, N, N·m … depending on context).
pub type Vec3 = na::Vector3<f64>;
/// A 6-vector, angular part first.
pub type Vec6 = na::Vector6<f64>;
/// A 3×3 matrix.
pub type Mat3 = na::Matrix3<f64>;
/// A 6×6 matrix (acting on angular-first 6-vectors).
pub type Mat6 = na::Matrix6<f64>;
/// A 4×4 homogeneous matrix.
pub type Mat4 = na::Matrix4<f64>;
/// A twist `(ω, v)`: body velocity [rad/s, m/s], or a strain `ξ = (k, q)`
/// [rad/m, 1] (the strain is the twist per unit arc length).
pub type Twist = Vec6;
/// A wrench `(M, N)`: moment [N·m] then force \[N\], or densities per unit length.
pub type Wrench = Vec6;

/// Index of the angular block in a 6-vector (`v.fixed_rows::<3>(ANGULAR)`).
pub const ANGULAR: usize = 0;
/// Index of the linear block in a 6-vector (`v.fixed_rows::<3>(LINEAR)`).
pub const LINEAR: usize = 3;

/// Angular part (first three components) of a twist or wrench.
#[inline(always)]
pub fn angular(v: &Vec6) -> Vec3 {
    Vec3::new(v[0], v[1], v[2])
}

/// Linear part (last three components) of a twist or wrench.
#[inline(always)]
pub fn linear(v: &Vec6) -> Vec3 {
    Vec3::new(v[3], v[4], v[5])
}

/// Builds a 6-vector from its angular and linear parts.
#[inline(always)]
pub fn join(angular: &Vec3, linear: &Vec3) -> Vec6 {
    Vec6::new(
        angular[0], angular[1], angular[2], linear[0], linear[1], linear[2],
    )
}
