//! The external forces of the sweeps: gravity as a base acceleration
//! (docs/theory.md §4) and the distributed wrench density of drag and
//! distributed loads at an evaluation point.

use crate::model::{Model, RodModel};
use softrod_lie::{Pose, Vec6};

/// Base acceleration that stands for gravity (docs/theory.md §4): the rod is
/// accelerated upward by `−g` in every section, `η̇(L₀) = −Ad⁻¹_{g_r}𝒢 =
/// (0; −R_rᵀ g_w)`, so no gravity wrench is computed per point.
#[inline]
pub(crate) fn gravity_base_acceleration(model: &Model, rm: &RodModel, scale: f64) -> Vec6 {
    match model.gravity {
        Some(g) => {
            let r = rm.spec.geometry.base().rotation;
            let a = -(r.tr_mul(&g)) * scale;
            Vec6::new(0.0, 0.0, 0.0, a[0], a[1], a[2])
        }
        None => Vec6::zeros(),
    }
}

/// The acceleration standing for gravity, world axes: the world frame is
/// accelerated by `−g` (docs/theory.md §4), so every node, body and point sees
/// gravity without a per-point wrench.
pub(crate) fn world_acceleration(model: &Model, scale: f64) -> Vec6 {
    match model.gravity {
        Some(g) => {
            let a = -g * scale;
            Vec6::new(0.0, 0.0, 0.0, a[0], a[1], a[2])
        }
        None => Vec6::zeros(),
    }
}

/// External distributed wrench density at a point (body frame, applied):
/// drag on the body velocity plus distributed loads.
#[inline]
pub(crate) fn external_density(rm: &RodModel, scale: f64, world: &Pose, eta: &Vec6) -> Vec6 {
    let mut f = Vec6::zeros();
    if let Some(d) = &rm.spec.drag {
        f += d.wrench_density(eta);
    }
    for dl in &rm.spec.distributed_loads {
        f += dl.wrench_density(world) * scale;
    }
    f
}
