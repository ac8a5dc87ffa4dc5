//! One evaluation point of a piece linearized in the piece's strain and
//! rate (docs/theory-derivatives.md D39–D41), and the sums of a piece's
//! own points and point loads (D38–D43, D45) that the sweeps close.

use super::piece::PieceWork;
use crate::forces::linearized::dead_load_map;
use crate::kernels::mat6::{Cols, mm, mmk, tmk};
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

/// `diag(d) X` on the leading `K` columns of `X` (the rest zero).
#[inline(always)]
fn diag_mul_k<const K: usize>(d: &Vec6, x: &Mat6) -> Mat6 {
    let mut out = Mat6::zeros();
    for j in 0..K {
        for i in 0..6 {
            out[(i, j)] = d[i] * x[(i, j)];
        }
    }
    out
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

/// One evaluation point of a piece, linearized (D39–D41) in the piece's
/// basis directions (D90): `H_η B`, `H_η̇ B`, `H_v̇ B`, `T₋ B` (six rows,
/// the basis's `k` leading columns, the rest zero).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointLin {
    pub a: AdOp,
    pub t: AdOp,
    pub tb: Mat6,
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
/// (gravity in `η̇′₀`), its strain rates `(ξ̇, ξ̈)` and its basis `B`
/// ([`Cols`]: the strain directions the linearization carries, D90).
#[derive(Clone, Copy)]
pub(crate) struct PieceLin<'a> {
    pub maps: &'a PieceMaps,
    pub dm: &'a PieceDerivMaps,
    pub eta0: &'a Vec6,
    pub etad0: &'a Vec6,
    pub xid: &'a Vec6,
    pub xidd: &'a Vec6,
    pub cols: &'a Cols,
}

/// The point at local abscissa `x` of the piece `pc`: its local pose and
/// linearization (D39–D41) in the basis directions (D90).
#[inline(always)]
pub(crate) fn linearize_point(pc: &PieceLin, x: f64) -> (Pose, PointLin) {
    match pc.cols.k {
        0..=3 => linearize::<3>(pc, x),
        4 => linearize::<4>(pc, x),
        _ => linearize::<6>(pc, x),
    }
}

/// [`linearize_point`] with at most `K ≥ k` columns (the products' sizes
/// known at compile time; the columns past `k` are zero).
#[inline(always)]
fn linearize<const K: usize>(pc: &PieceLin, x: f64) -> (Pose, PointLin) {
    let PieceLin {
        maps,
        dm,
        eta0,
        etad0,
        xid,
        xidd,
        cols,
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
    let d1 = cols.right(&dm.d_tangent_applied(&co, false));
    let d2 = dm.d_tangent_applied(&co, true);
    let dd = dm.bias_strain_derivative(&co);
    let td = dm.tangent_rate(&co);
    // Products of block operators [[A, 0], [B, A]] in that form (3 instead
    // of 8 3×3 products).
    let adc_op = AdOp::ad(&c);
    let adc_t_op = adc_op * tm;
    // Every block is needed on the basis's columns only (D90): `X B` is a
    // gather for the selection bases, and the one 6×6 product, `ad_c 𝒟_ξ̇`,
    // runs over `k` columns.
    // (D39): δη = ad_c Δ + 𝒟_ξ̇ ζ with Δ = T₋ζ.
    let h_eta = cols.right(&adc_t_op.to_mat6()) + d1;
    // (D40): δη̇′ = ad_{a₀}Δ − ad_{Tξ̇} ad_c Δ + 𝒟_ξ̈ ζ + ad_c 𝒟_ξ̇ ζ + 𝒟² ζ.
    let h_etad = cols.right(&((AdOp::ad(&a0) * tm - AdOp::ad(&sv) * adc_t_op).to_mat6() + d2))
        + mmk::<6, K>(&adc_op.to_mat6(), &d1)
        + cols.right(&dd);
    // (D41): ∂η̇′/∂ξ̇ = ad_c T₋ + 𝒟_ξ̇ + Ṫ.
    let h_vd = h_eta + cols.right(&td);
    (
        g,
        PointLin {
            a,
            t,
            tb: cols.right(&t.to_mat6()),
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
/// (D86), for the O(N) products `M v`. Every sum with a strain direction
/// is summed in the basis's `k` directions (D90): `Bᵀ(·)B` for the
/// diagonal sums, `(·)B` for the wrench's, `Bᵀ(·)` for the receivers.
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
    match pc.cols.k {
        0..=3 => own_points_k::<3>(rm, pd, pc, pose, drag, scale, mass, w),
        4 => own_points_k::<4>(rm, pd, pc, pose, drag, scale, mass, w),
        _ => own_points_k::<6>(rm, pd, pc, pose, drag, scale, mass, w),
    }
}

/// [`own_points`] with at most `K ≥ k` strain directions (as [`linearize`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn own_points_k<const K: usize>(
    rm: &RodModel,
    pd: &PieceData,
    pc: &PieceLin,
    pose: &Pose,
    drag: Option<&Vec6>,
    scale: f64,
    mass: bool,
    w: &mut PieceWork,
) {
    let (maps, dm, cols) = (pc.maps, pc.dm, pc.cols);
    // Drag or distributed loads make `f` more than the inertial wrench
    // density: then the inertial sums of D85 are summed apart; otherwise
    // they are `tsum`, `wsum` as they stand after the Gauss points.
    let apart = drag.is_some() || !rm.spec.distributed_loads.is_empty();
    for qp in &pd.points {
        let (g, p) = linearize::<K>(pc, qp.x);
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
        // Every product with a strain direction runs over the basis's `k`
        // columns (or rows) (D90): `df_q`, `df_v` are `δf B`.
        let tb = &p.tb;
        let df_q = (diag_mul_k::<K>(m, &p.h_etad)
            + mmk::<6, K>(&b, &p.h_eta)
            + if has_y {
                mmk::<6, K>(&y, tb)
            } else {
                Mat6::zeros()
            })
            * wt;
        let df_v = (diag_mul_k::<K>(m, &p.h_vd) + mmk::<6, K>(&b, tb)) * wt;
        let fw = f * wt;
        let pa = p.a.to_mat6();
        w.dq_diag += tmk::<K, K>(tb, &df_q);
        w.dv_diag += tmk::<K, K>(tb, &df_v);
        w.dq_w += tmk::<6, K>(&pa, &(mmk::<6, K>(&lambda(&fw), tb) + df_q));
        w.dv_w += tmk::<6, K>(&pa, &df_v);
        w.tsum += p.t.tr_mul_vec(&fw);
        w.wsum += p.a.tr_mul_vec(&fw);
        for i in 0..4 {
            w.phi[i] += f * (wt * p.co.d[i]);
            w.chi[i] += f * (wt * p.co.c[i]);
        }
        // (D43): B̄ = b − 𝓜 ad_η.
        let bbar = b - diag_mul(m, &ad(&p.eta));
        let ma = diag_mul(&(m * wt), &pa);
        let ba = mul_op(&(bbar * wt), &p.a);
        w.mt += tmk::<6, 6>(&pa, &ma);
        w.bt += tmk::<6, 6>(&pa, &ba);
        w.rm += tmk::<K, 6>(tb, &ma);
        w.rb += tmk::<K, 6>(tb, &ba);
        if mass {
            w.mtt += tmk::<K, K>(tb, &diag_mul_k::<K>(&(m * wt), tb));
        }
        if has_y {
            let ya = mul_op(&(y * wt), &p.a);
            w.yt += tmk::<6, 6>(&pa, &ya);
            w.ry += tmk::<K, 6>(tb, &ya);
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
        let tb = cols.right(&t);
        let co = Coefficients::at(pl.x, dm.theta);
        let fp = -(load.wrench(&pose.compose(&g)) * scale);
        let mut dq = mmk::<6, K>(&lambda(&fp), &tb);
        if load.frame == LoadFrame::World {
            let y = dead_load_map(&-fp);
            let yt_ = mmk::<6, K>(&y, &tb);
            w.dq_diag += tmk::<K, K>(&tb, &yt_);
            dq += yt_;
            let ya = y * a;
            w.yt += a.transpose() * ya;
            w.ry += tmk::<K, 6>(&tb, &ya);
        }
        w.dq_w += tmk::<6, K>(&a, &dq);
        w.tsum += t.transpose() * fp;
        w.wsum += a.transpose() * fp;
        for i in 0..4 {
            w.phi[i] += fp * co.d[i];
            w.chi[i] += fp * co.c[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use softrod_kinematics::Strain;

    /// The linearization in a basis's `k` directions (D90) against the six
    /// directions (`B = I`) projected afterwards, `H B`: equal bit for bit
    /// for the selection bases (gathers of the same numbers), to round-off
    /// for a general `B` (the products associated differently).
    #[test]
    fn basis_directions_equal_six_directions_projected() {
        let xi = Vec6::new(0.7, -1.3, 0.4, 1.05, 0.2, -0.1);
        let xid = Vec6::new(0.2, 0.1, -0.4, 0.3, -0.5, 0.9);
        let xidd = Vec6::new(-1.0, 0.4, 0.3, 0.2, 0.7, -0.6);
        let eta0 = Vec6::new(0.3, -0.8, 0.5, -0.2, 0.4, 0.1);
        let etad0 = Vec6::new(-0.4, 0.6, 0.2, 0.8, 0.1, -9.81);
        let maps = PieceMaps::new(&xi, Some(&xid));
        let dm = PieceDerivMaps::new(&xi, &xid, &xidd);
        let lin = |bm: &Mat6, x: f64| {
            let cols = Cols::of(bm);
            let pc = PieceLin {
                maps: &maps,
                dm: &dm,
                eta0: &eta0,
                etad0: &etad0,
                xid: &xid,
                xidd: &xidd,
                cols: &cols,
            };
            linearize_point(&pc, x).1
        };
        let general = Mat6::from_fn(|i, j| {
            if j < 4 {
                ((i * 4 + j) as f64 * 0.9 + 0.3).sin() + if i == j { 1.5 } else { 0.0 }
            } else {
                0.0
            }
        });
        let bases = [
            (
                basis6(&Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap()),
                true,
            ),
            (basis6(&Basis::select(&[Strain::Kz]).unwrap()), true),
            (basis6(&Basis::kirchhoff()), true),
            (
                basis6(
                    &Basis::select(&[Strain::Qz, Strain::Kx, Strain::Qx, Strain::Kz, Strain::Ky])
                        .unwrap(),
                ),
                true,
            ),
            (general, false),
        ];
        for x in [0.0, 0.13, 0.5] {
            let six = lin(&Mat6::identity(), x);
            for (bm, exact) in &bases {
                let p = lin(bm, x);
                for (got, full) in [
                    (p.h_eta, six.h_eta),
                    (p.h_etad, six.h_etad),
                    (p.h_vd, six.h_vd),
                    (p.tb, six.t.to_mat6()),
                ] {
                    let want = full * bm;
                    if *exact {
                        assert_eq!(got, want, "x = {x}, B = {bm}");
                    } else {
                        let err = (got - want).amax();
                        assert!(err <= 1e-14 * (1.0 + want.amax()), "x = {x}: {err:e}");
                    }
                }
                assert_eq!(p.eta, six.eta);
                assert_eq!(p.etad, six.etad);
            }
        }
    }
}
