//! The force terms' linearizations for the derivative sweeps
//! (docs/theory-derivatives.md D38, D47): the map `Y` of a dead
//! (world-fixed) wrench, the drag as the diagonal `C`, the cables' force
//! and strain Hessian.

use crate::model::data::cable_tension;
use crate::model::{Model, RodModel};
use nalgebra::DVector;
use softrod_lie::{Mat3, Mat6, Vec6, angular, linear, skew};
use softrod_mechanics::LoadFrame;

/// The body-frame linearization `Y` of a dead (world-fixed) wrench `(m, f)`
/// (body components) with respect to a body-frame perturbation `Δ = (ω, v)`
/// of the section it acts on (D38): the net force density `−F` changes by
/// `(ω × m; ω × f) = Y Δ`, `Y = [[−m̃, 0], [−f̃, 0]]`.
#[inline(always)]
pub(crate) fn dead_load_map(w: &Vec6) -> Mat6 {
    let mut y = Mat6::zeros();
    y.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(-skew(&angular(w))));
    y.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(-skew(&linear(w))));
    y
}

/// The drag coefficients of a rod as the diagonal `C` of (D38).
pub(crate) fn drag_diagonal(rm: &RodModel) -> Option<Vec6> {
    rm.spec.drag.map(|d| {
        Vec6::new(
            d.rotational,
            d.rotational,
            d.rotational,
            d.translational,
            d.translational,
            d.translational,
        )
    })
}

/// Whether a rod carries dead (world-frame) point or distributed loads, the
/// only terms with a nonzero `Y` (D38).
pub(crate) fn has_dead_loads(rm: &RodModel) -> bool {
    rm.spec
        .point_loads
        .iter()
        .any(|l| l.frame == LoadFrame::World)
        || rm
            .spec
            .distributed_loads
            .iter()
            .any(|l| l.frame == LoadFrame::World)
}

/// Cable terms of one piece (D47): the sum over cables of `λT ∫ w ds` with
/// `w = (d × t̂; t̂)` (the part `+λT ∫ w` of `τ = … − τ_c`), and of
/// `λT ∫ H P Hᵀ/|v| ds` (its strain derivative), `H = [d̃; I]`,
/// `P = I − t̂t̂ᵀ`. A cable with friction weighs each node by its decayed
/// tension `e^{−μφ(s)}` (D15f) and the decay itself is held fixed (its
/// derivative through `φ` couples every piece to those before it, which
/// the O(N) solves do not carry): Newton on such cables converges
/// linearly, not quadratically.
#[inline(always)]
pub(crate) fn cable_terms(
    model: &Model,
    rm: &RodModel,
    (n, q_rod): (usize, &[f64]),
    xi: &Vec6,
    t: f64,
    scale: f64,
    tensions: Option<&DVector<f64>>,
) -> (Vec6, Mat6) {
    let mut force = Vec6::zeros();
    let mut hess = Mat6::zeros();
    let (k, qv) = (angular(xi), linear(xi));
    for (c, cable) in rm.spec.cables.iter().enumerate() {
        let tension = cable_tension(tensions, rm, c, t) * scale;
        if tension == 0.0 {
            continue;
        }
        let rod = &rm.spec.geometry;
        cable.for_each_weighted_node(rod, q_rod, n, &model.quadrature, |s, w| {
            let (d, dp) = cable.offset(s);
            let v = qv + k.cross(&d) + dp;
            let nv = v.norm();
            if nv == 0.0 {
                return;
            }
            let th = v / nv;
            force += softrod_lie::join(&d.cross(&th), &th) * (w * tension);
            let p = (Mat3::identity() - th * th.transpose()) * (w * tension / nv);
            let dt = skew(&d);
            // H P Hᵀ = [[d̃Pd̃ᵀ, d̃P], [Pd̃ᵀ, P]].
            let dp_ = dt * p;
            let mut h = Mat6::zeros();
            h.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(dp_ * dt.transpose()));
            h.fixed_view_mut::<3, 3>(0, 3).copy_from(&dp_);
            h.fixed_view_mut::<3, 3>(3, 0).copy_from(&dp_.transpose());
            h.fixed_view_mut::<3, 3>(3, 3).copy_from(&p);
            hess += h;
        });
    }
    (force, hess)
}
