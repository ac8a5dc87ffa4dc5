//! Slow, simple reference projections of loads onto the generalized
//! coordinates, built directly on [`RodKinematics`] (`pose_at`, `jacobian_at`).
//! Enabled by the `reference` feature (test support, off by default).
//!
//! They allocate and recompute everything per call; they exist as an
//! independent check for the crate's own tests and for the dynamics layer's
//! recursive implementation. All return the generalized force on the
//! right-hand side of `M q̈ + … = τ` (positive = pushes `q` up).
//!
//! # Panics
//! On invalid input (wrong `q` length, non-finite values, abscissae outside
//! the rod) — these are test helpers.

use crate::body::RodProperties;
use crate::loads::{LoadFrame, PointLoad};
use nalgebra::{DVector, Matrix6xX};
use softrod_kinematics::{Frame, GaussLegendre, RodGeometry, RodKinematics};
use softrod_lie::{Pose, Twist, Vec3, Wrench};

/// Body wrench density of gravity (D14) `𝓕_g = 𝓜 Ad⁻¹_g 𝒢 = (0; ρA Rᵀ g_w)`
/// [N/m] for mass per length `ρA` [kg/m], the section's world pose
/// `g = (R, p)` and the world acceleration `g_w` [m/s²]. Conservative,
/// potential density `−ρA g_w·p`.
pub fn gravity_wrench_density(mass_per_length: f64, pose: &Pose, gravity: &Vec3) -> Wrench {
    let f = pose.rotation.tr_mul(gravity) * mass_per_length;
    Wrench::new(0.0, 0.0, 0.0, f[0], f[1], f[2])
}

fn kinematics(rod: &RodGeometry, q: &[f64], qd: Option<&[f64]>) -> RodKinematics {
    let mut k = RodKinematics::new(rod);
    k.update(rod, q, qd, None)
        .expect("valid coordinates for the reference projection");
    k
}

/// `Σ_n Σ_g w_g f(s_g)` over the Gauss nodes of every piece.
fn for_each_node(rod: &RodGeometry, quadrature: &GaussLegendre, mut f: impl FnMut(f64, f64)) {
    for p in rod.pieces() {
        for (x, w) in quadrature.on_interval(p.length) {
            f(p.start + x, w);
        }
    }
}

/// `∫ J(s)ᵀ 𝓕(s) ds` for a body wrench density given by `wrench(s, kin)`.
fn project_density(
    rod: &RodGeometry,
    kin: &RodKinematics,
    quadrature: &GaussLegendre,
    mut wrench: impl FnMut(f64, &RodKinematics) -> Wrench,
) -> DVector<f64> {
    let mut j = Matrix6xX::zeros(rod.n_dof());
    let mut out = DVector::zeros(rod.n_dof());
    for_each_node(rod, quadrature, |s, w| {
        kin.jacobian_at(rod, s, Frame::Body, &mut j)
            .expect("s inside the rod");
        let f = wrench(s, kin);
        out += j.tr_mul(&f) * w;
    });
    out
}

/// Generalized gravity force `−G(q) = ∫₀ᴸ J(s)ᵀ 𝓕_g(s) ds` (D14),
/// `𝓕_g = (0; ρA(s) R(s)ᵀ g_w)` ([`gravity_wrench_density`]), by Gauss
/// quadrature on each piece with the body-frame Jacobian. Equals `−∂V_g/∂q`
/// for [`gravity_potential`] with the same rule. Units: N·m or N per
/// coordinate unit.
pub fn generalized_gravity_by_jacobian(
    rod: &RodGeometry,
    body: &RodProperties,
    gravity: &Vec3,
    q: &[f64],
    quadrature: &GaussLegendre,
) -> DVector<f64> {
    line_load_force_by_jacobian(rod, q, None, quadrature, |s, pose, _| {
        gravity_wrench_density(body.mass_per_length(s), pose, gravity)
    })
}

/// Generalized force `∫ J(s)ᵀ 𝓕(s) ds` of any distributed term (gravity,
/// distributed load, drag) at `(q, q̇)`; `qd = None` means at rest. The
/// body wrench density is `density(s, g(s), η(s))` (world pose, body
/// velocity).
pub fn line_load_force_by_jacobian(
    rod: &RodGeometry,
    q: &[f64],
    qd: Option<&[f64]>,
    quadrature: &GaussLegendre,
    mut density: impl FnMut(f64, &Pose, &Twist) -> Wrench,
) -> DVector<f64> {
    let kin = kinematics(rod, q, qd);
    project_density(rod, &kin, quadrature, |s, k| {
        let pose = k.pose_at(rod, s).expect("s inside the rod");
        let eta = k
            .velocity_at(rod, s, Frame::Body)
            .expect("s inside the rod");
        density(s, &pose, &eta)
    })
}

/// Gravitational potential energy (§7) `V_g = −∫₀ᴸ ρA(s) g_w·p(s) ds` \[J\],
/// `p(s)` the world position of the section centre, by Gauss quadrature on
/// each piece.
pub fn gravity_potential(
    rod: &RodGeometry,
    body: &RodProperties,
    gravity: &Vec3,
    q: &[f64],
    quadrature: &GaussLegendre,
) -> f64 {
    let kin = kinematics(rod, q, None);
    let mut v = 0.0;
    for_each_node(rod, quadrature, |s, w| {
        let p = kin.pose_at(rod, s).expect("s inside the rod").translation;
        v -= w * body.mass_per_length(s) * gravity.dot(&p);
    });
    v
}

/// Generalized force of a point load, `J(s̄)ᵀ 𝓕_p` (D14), with the body-frame
/// Jacobian at `s̄ = load.s` and the applied wrench of [`PointLoad::wrench`].
pub fn point_load_force_by_jacobian(
    rod: &RodGeometry,
    load: &PointLoad,
    q: &[f64],
) -> DVector<f64> {
    let kin = kinematics(rod, q, None);
    let mut j = Matrix6xX::zeros(rod.n_dof());
    kin.jacobian_at(rod, load.s, Frame::Body, &mut j)
        .expect("point load inside the rod");
    let pose = kin.pose_at(rod, load.s).expect("point load inside the rod");
    j.tr_mul(&load.wrench(&pose))
}

/// Potential of a dead point force, `V = −f_w·p(s̄)` \[J\].
///
/// Only the force enters: a dead (world-fixed) moment is not conservative in
/// 3D, so this is the potential of the load only when `moment = 0`.
///
/// # Panics
/// If the load is a follower load (`LoadFrame::Body`), which has no potential.
pub fn dead_load_potential(rod: &RodGeometry, load: &PointLoad, q: &[f64]) -> f64 {
    assert_eq!(
        load.frame,
        LoadFrame::World,
        "only dead (world-frame) point forces have a potential"
    );
    let kin = kinematics(rod, q, None);
    let p = kin
        .pose_at(rod, load.s)
        .expect("point load inside the rod")
        .translation;
    -load.force.dot(&p)
}
