//! One evaluation point of a piece linearized in the piece's strain and
//! rate (docs/theory-derivatives.md D39–D41), and the sums of a piece's
//! own points and point loads (D38–D43, D45) that the sweeps close.

use super::piece::PieceWork;
use crate::forces::linearized::dead_load_map;
use crate::kernels::mat6::{mm, tm};
use crate::kernels::piece_derivs::{Coefficients, PieceDerivMaps, lambda};
use crate::model::RodModel;
use crate::model::rod::PieceData;
use softrod_kinematics::Basis;
use softrod_lie::{AdOp, Mat6, PieceMaps, Pose, Vec6, ad, ad_vec, coad, coad_vec};
use softrod_mechanics::LoadFrame;

/// `B` as a zero-padded 6×6 (columns past `k` are zero).
#[inline(always)]
pub(crate) fn basis6(basis: &Basis) -> Mat6 {
    let mut b = Mat6::zeros();
    for c in 0..basis.dof() {
        b.set_column(c, &basis.column(c));
    }
    b
}

/// `diag(d) X`.
#[inline(always)]
pub(crate) fn diag_mul(d: &Vec6, x: &Mat6) -> Mat6 {
    Mat6::from_fn(|i, j| d[i] * x[(i, j)])
}

/// `X diag(d)`.
#[inline(always)]
fn scale_columns(x: &Mat6, d: &Vec6) -> Mat6 {
    Mat6::from_fn(|i, j| x[(i, j)] * d[j])
}

/// `X · Op` for a block operator (dense: nalgebra's unrolled 6×6 product
/// measured cheaper than six 3×3 block products with their copies).
#[inline(always)]
fn mul_op(x: &Mat6, op: &AdOp) -> Mat6 {
    mm(x, &op.to_mat6())
}

/// `Op · X`.
#[inline(always)]
fn op_mul(op: &AdOp, x: &Mat6) -> Mat6 {
    mm(&op.to_mat6(), x)
}

/// `Opᵀ · X`.
#[inline(always)]
fn op_tr_mul(op: &AdOp, x: &Mat6) -> Mat6 {
    tm(&op.to_mat6(), x)
}

/// One evaluation point of a piece, linearized (D39–D41).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointLin {
    pub a: AdOp,
    pub t: AdOp,
    pub eta: Vec6,
    pub etad: Vec6,
    pub h_eta: Mat6,
    pub h_etad: Mat6,
    pub h_vd: Mat6,
    pub co: Coefficients,
}

/// A piece's maps and motion, what linearizing one of its points needs:
/// the maps of its strain ([`PieceMaps`]) and their strain derivatives
/// ([`PieceDerivMaps`], D30–D36), the motion `(η₀, η̇′₀)` of its base frame
/// (gravity in `η̇′₀`) and its strain rates `(ξ̇, ξ̈)`.
#[derive(Clone, Copy)]
pub(crate) struct PieceLin<'a> {
    pub maps: &'a PieceMaps,
    pub dm: &'a PieceDerivMaps,
    pub eta0: &'a Vec6,
    pub etad0: &'a Vec6,
    pub xid: &'a Vec6,
    pub xidd: &'a Vec6,
}

/// The point at local abscissa `x` of the piece `pc`: its local pose and
/// linearization (D39–D41).
#[inline(always)]
pub(crate) fn linearize_point(pc: &PieceLin, x: f64) -> (Pose, PointLin) {
    let PieceLin {
        maps,
        dm,
        eta0,
        etad0,
        xid,
        xidd,
    } = *pc;
    let (g, tm, beta) = maps.eval(x);
    let a = g.ad_inv();
    let t = tm;
    let c = a.mul_vec(eta0);
    let sv = t.mul_vec(xid);
    let eta = c + sv;
    let a0 = a.mul_vec(etad0);
    let etad = a0 + t.mul_vec(xidd) + ad_vec(&c, &sv) + beta;
    let co = Coefficients::at(x, dm.theta);
    let d1 = dm.d_tangent_applied(&co, false);
    let d2 = dm.d_tangent_applied(&co, true);
    let dd = dm.bias_strain_derivative(&co);
    let td = dm.tangent_rate(&co);
    // Products of block operators [[A, 0], [B, A]] in that form (3 instead
    // of 8 3×3 products).
    let adc_op = AdOp::ad(&c);
    let adc_t_op = adc_op * tm;
    let adc_t = adc_t_op.to_mat6();
    // (D39): δη = ad_c Δ + 𝒟_ξ̇ ζ with Δ = T₋ζ.
    let h_eta = adc_t + d1;
    // (D40): δη̇′ = ad_{a₀}Δ − ad_{Tξ̇} ad_c Δ + 𝒟_ξ̈ ζ + ad_c 𝒟_ξ̇ ζ + 𝒟² ζ.
    let h_etad =
        (AdOp::ad(&a0) * tm - AdOp::ad(&sv) * adc_t_op).to_mat6() + d2 + op_mul(&adc_op, &d1) + dd;
    // (D41): ∂η̇′/∂ξ̇ = ad_c T₋ + 𝒟_ξ̇ + Ṫ.
    let h_vd = h_eta + td;
    (
        g,
        PointLin {
            a,
            t,
            eta,
            etad,
            h_eta,
            h_etad,
            h_vd,
            co,
        },
    )
}

/// The own evaluation points and point loads of one piece (D38–D43): every
/// Gauss point linearized in the piece's strain and rate (D39–D41), its
/// force density and linearization summed into the diagonal and
/// transmitted-wrench sums (D42), the composites' own parts and the
/// receivers (D43, D45); point loads likewise, with weight 1. `pose` is the
/// world pose of the piece's base frame; the loads are scaled by `scale`
/// (the evaluation's [`crate::Forces::load_scale`]). With `mass`, also the
/// own points' part of the mass matrix's diagonal block, `Σ w T₋ᵀ𝓜T₋`
/// (D86), for the O(N) products `M v`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn own_points(
    rm: &RodModel,
    pd: &PieceData,
    pc: &PieceLin,
    pose: &Pose,
    drag: Option<&Vec6>,
    scale: f64,
    mass: bool,
    w: &mut PieceWork,
) {
    let (maps, dm) = (pc.maps, pc.dm);
    // Drag or distributed loads make `f` more than the inertial wrench
    // density: then the inertial sums of D85 are summed apart; otherwise
    // they are `tsum`, `wsum` as they stand after the Gauss points.
    let apart = drag.is_some() || !rm.spec.distributed_loads.is_empty();
    for qp in &pd.points {
        let (g, p) = linearize_point(pc, qp.x);
        let m = &qp.inertia;
        let me = m.component_mul(&p.eta);
        let mut f = m.component_mul(&p.etad) + coad_vec(&p.eta, &me);
        if apart {
            let fw = f * qp.w;
            w.tin += p.t.tr_mul_vec(&fw);
            w.win += p.a.tr_mul_vec(&fw);
        }
        // (D38): b = Λ(𝓜η) + ad*_η 𝓜 + C, the velocity part of δf.
        let mut b = lambda(&me) + scale_columns(&coad(&p.eta), m);
        if let Some(c) = drag {
            f += c.component_mul(&p.eta);
            b += Mat6::from_diagonal(c);
        }
        let mut y = Mat6::zeros();
        let mut has_y = false;
        if !rm.spec.distributed_loads.is_empty() {
            let world = pose.compose(&g);
            for dl in &rm.spec.distributed_loads {
                let load = dl.wrench_density(&world) * scale;
                f -= load;
                if dl.frame == LoadFrame::World {
                    y += dead_load_map(&load);
                    has_y = true;
                }
            }
        }
        let wt = qp.w;
        let df_q = (diag_mul(m, &p.h_etad)
            + mm(&b, &p.h_eta)
            + if has_y {
                mul_op(&y, &p.t)
            } else {
                Mat6::zeros()
            })
            * wt;
        let df_v = (diag_mul(m, &p.h_vd) + mul_op(&b, &p.t)) * wt;
        let fw = f * wt;
        w.dq_diag += op_tr_mul(&p.t, &df_q);
        w.dv_diag += op_tr_mul(&p.t, &df_v);
        w.dq_w += op_tr_mul(&p.a, &(mul_op(&lambda(&fw), &p.t) + df_q));
        w.dv_w += op_tr_mul(&p.a, &df_v);
        w.tsum += p.t.tr_mul_vec(&fw);
        w.wsum += p.a.tr_mul_vec(&fw);
        for i in 0..4 {
            w.phi[i] += f * (wt * p.co.d[i]);
            w.chi[i] += f * (wt * p.co.c[i]);
        }
        // (D43): B̄ = b − 𝓜 ad_η.
        let bbar = b - diag_mul(m, &ad(&p.eta));
        let pa = p.a.to_mat6();
        let ma = diag_mul(&(m * wt), &pa);
        let ba = mul_op(&(bbar * wt), &p.a);
        w.mt += op_tr_mul(&p.a, &ma);
        w.bt += op_tr_mul(&p.a, &ba);
        w.rm += op_tr_mul(&p.t, &ma);
        w.rb += op_tr_mul(&p.t, &ba);
        if mass {
            w.mtt += op_tr_mul(&p.t, &diag_mul(&(m * wt), &p.t.to_mat6()));
        }
        if has_y {
            let ya = mul_op(&(y * wt), &p.a);
            w.yt += op_tr_mul(&p.a, &ya);
            w.ry += op_tr_mul(&p.t, &ya);
        }
    }
    if !apart {
        w.tin = w.tsum;
        w.win = w.wsum;
    }
    for pl in &pd.loads {
        let load = &rm.spec.point_loads[pl.index];
        let (g, tm) = maps.exp_and_tangent_minus(pl.x);
        let a = g.ad_inv().to_mat6();
        let t = tm.to_mat6();
        let co = Coefficients::at(pl.x, dm.theta);
        let fp = -(load.wrench(&pose.compose(&g)) * scale);
        let (at, tt) = (a.transpose(), t.transpose());
        let mut dq = lambda(&fp) * t;
        if load.frame == LoadFrame::World {
            let y = dead_load_map(&-fp);
            let yt_ = y * t;
            w.dq_diag += tt * yt_;
            dq += yt_;
            let ya = y * a;
            w.yt += at * ya;
            w.ry += tt * ya;
        }
        w.dq_w += at * dq;
        w.tsum += tt * fp;
        w.wsum += at * fp;
        for i in 0..4 {
            w.phi[i] += fp * co.d[i];
            w.chi[i] += fp * co.c[i];
        }
    }
}
