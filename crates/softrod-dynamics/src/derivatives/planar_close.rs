//! The closes of the inward sweep on planar rods, in se(2)
//! (docs/theory-derivatives.md D99–D100): after the planar outward sweep
//! ([`super::planar::outward`], D97–D98), each piece's composites,
//! diagonal blocks, `𝒬`, transmitted wrench and mass-matrix block on 3×3
//! blocks and `k` columns, and its world-frame pairing quantities as the
//! `P` columns of `Ad` times 3×k, written into the buffers the pairings
//! and the O(N) products read.

use super::piece::{PieceWork, write_piece};
use super::planar::{Place, ad3, lambda3};
use super::point::basis6;
use super::{At, IdDerivatives};
use crate::forces::linearized::has_dead_loads;
use crate::model::planar::PlanarRod;
use crate::model::{Model, RodModel};
use nalgebra::SMatrix;
use softrod_lie::{Mat3, Mat6, Vec3, Vec6};

impl Place {
    /// The `P` rows of a 6×k buffer written by [`Self::sk`] (3×k).
    #[inline(always)]
    pub(crate) fn rows_of(&self, m: &Mat6) -> Mat3 {
        Mat3::from_fn(|r, j| m[(self.idx[r], j)])
    }

    /// The `P` columns of a k×6 buffer written by [`Self::ks`] (k×3).
    #[inline(always)]
    pub(crate) fn cols_of(&self, m: &Mat6) -> Mat3 {
        Mat3::from_fn(|i, c| m[(i, self.idx[c])])
    }

    /// The leading k×k of a buffer written by [`Self::kk`].
    #[inline(always)]
    pub(crate) fn lead(&self, m: &Mat6) -> Mat3 {
        m.fixed_view::<3, 3>(0, 0).into_owned()
    }

    /// `X B` in `P` coordinates (3×k, the basis's columns of `X`).
    #[inline(always)]
    pub(crate) fn right(&self, x: &Mat3) -> Mat3 {
        Mat3::from_fn(|r, j| if j < self.k { x[(r, self.sel[j])] } else { 0.0 })
    }

    /// `Bᵀ X B` in `P` coordinates (k×k).
    #[inline(always)]
    pub(crate) fn both(&self, x: &Mat3) -> Mat3 {
        Mat3::from_fn(|i, j| {
            if i < self.k && j < self.k {
                x[(self.sel[i], self.sel[j])]
            } else {
                0.0
            }
        })
    }
}

/// A 3×k (or k×k) block in the leading part of a 6×6 buffer.
#[inline(always)]
fn lead6(x: &Mat3) -> Mat6 {
    let mut out = Mat6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(x);
    out
}

/// A 6×k block in the leading columns of a 6×6 buffer.
#[inline(always)]
fn cols6(x: &SMatrix<f64, 6, 3>) -> Mat6 {
    let mut out = Mat6::zeros();
    out.fixed_view_mut::<6, 3>(0, 0).copy_from(x);
    out
}

/// A k×6 block in the leading rows of a 6×6 buffer.
#[inline(always)]
fn rows6(x: &SMatrix<f64, 3, 6>) -> Mat6 {
    let mut out = Mat6::zeros();
    out.fixed_view_mut::<3, 6>(0, 0).copy_from(x);
    out
}

/// `𝒬` of (D36) on `P` (D99): the form of
/// [`crate::kernels::piece_derivs::tangent_transpose_form`] from the `P`
/// blocks of the powers `P^i` and the `P` parts of `k̄`, `φ_i`, `χ_i`,
/// every factor block diagonal on `P ⊕ P⊥` (D95).
#[inline(always)]
pub(crate) fn tangent_transpose_form3(
    p: &[Mat3; 4],
    kbar: &Vec3,
    phi: &[Vec3; 4],
    chi: &[Vec3; 4],
) -> Mat3 {
    let mut out = Mat3::zeros();
    for i in 0..4 {
        out += (p[i].tr_mul(&phi[i])) * kbar.transpose();
        let mut fl = chi[i];
        for l in 0..=i {
            let lam = lambda3(&fl);
            let m = i - l;
            if m == 0 {
                out -= lam;
            } else {
                out -= p[m - 1].tr_mul(&lam);
            }
            fl = p[0].tr_mul(&fl);
        }
    }
    out
}

/// [`super::piece::Subtree`] of a planar rod in `P` coordinates (D99):
/// `𝓜ᶜ`, `𝓑ᶜ`, `𝒴ᶜ` restricted to `P` and `W` in `P`.
#[derive(Clone, Copy)]
struct Subtree3 {
    m: Mat3,
    b: Mat3,
    y: Mat3,
    w: Vec3,
}

/// [`super::piece::close_piece`] (and, with `mass`,
/// [`super::piece::close_mass`]) on a planar piece, in `P` coordinates
/// (D99–D100): the composites carried by the planar `Ad⁻¹` of the tip,
/// the diagonal blocks, the transmitted wrench and `𝒬` on 3×3 and `k`
/// columns; the world-frame pairing quantities (D46) as the `P` columns
/// of `Ad_{G_n}` (6×3) times the 3×k blocks, the receivers as k×3 times
/// the `P` rows of `Ad⁻¹_{G_{n−1}}`. Returns what `close_piece` returns
/// (the blocks k×k in the leading part of 6×6, the wrench in six
/// components) and the subtree handed to the base frame.
#[inline(always)]
fn close_piece3(
    w: &mut PieceWork,
    tip: &Subtree3,
    pl: &Place,
    dead: bool,
    mass: bool,
) -> (Mat6, Mat6, Vec6, Subtree3) {
    let (mc, bc, yc, wn) = (&tip.m, &tip.b, &tip.y, &tip.w);
    let al = pl.block(&w.tip.ad_inv().to_mat6());
    let tl = pl.block(&w.tm_tip);
    let tlb = pl.right(&tl);
    let tlbt = tlb.transpose();
    let adeta = ad3(&pl.gather(&w.eta_tip));
    // (D43) on P, `k` columns: u = δη(ℓ), w̄ = δη̇′(ℓ) + ad_η(ℓ) δη(ℓ).
    let uq = pl.rows_of(&w.h_eta);
    let wq = pl.rows_of(&w.h_etad) + adeta * uq;
    let mut dwn_q = mc * wq + bc * uq;
    if dead {
        dwn_q += yc * tlb;
    }
    let wv = pl.rows_of(&w.h_vd) + adeta * tlb;
    let dwn_v = mc * wv + bc * tlb;
    let mut phi = [Vec3::zeros(); 4];
    let mut chi = [Vec3::zeros(); 4];
    let mut powers = [Mat3::zeros(); 4];
    for i in 0..4 {
        phi[i] = pl.gather(&w.phi[i]) + wn * w.co_tip.d[i];
        chi[i] = pl.gather(&w.chi[i]) + wn * w.co_tip.c[i];
        powers[i] = pl.block(&w.powers[i]);
    }
    let qform = pl.both(&tangent_transpose_form3(
        &powers,
        &pl.gather(&w.kbar),
        &phi,
        &chi,
    ));
    let diag_q = pl.lead(&w.dq_diag) + tlbt * dwn_q + qform;
    let diag_v = pl.lead(&w.dv_diag) + tlbt * dwn_v;
    let dw_q = pl.rows_of(&w.dq_w) + al.tr_mul(&(lambda3(wn) * tlb + dwn_q));
    let dw_v = pl.rows_of(&w.dv_w) + al.tr_mul(&dwn_v);
    // World-frame pairing quantities (D46, D100).
    let to_world = w.tip_world.ad().to_mat6();
    let base_inv = w.base_world.ad_inv().to_mat6();
    let aw = SMatrix::<f64, 6, 3>::from_fn(|r, c| to_world[(r, pl.idx[c])]);
    let bi = SMatrix::<f64, 3, 6>::from_fn(|r, c| base_inv[(pl.idx[r], c)]);
    w.s_world = cols6(&(aw * tlb));
    w.src_wq = cols6(&(aw * wq));
    w.src_uq = cols6(&(aw * uq));
    w.src_wv = cols6(&(aw * wv));
    w.src_uv = w.s_world;
    w.dwq_world = cols6(&bi.tr_mul(&dw_q));
    w.dwv_world = cols6(&bi.tr_mul(&dw_v));
    let tmc = tlbt * mc;
    w.rcv_m = rows6(&((pl.cols_of(&w.rm) + tmc * al) * bi));
    w.rcv_b = rows6(&((pl.cols_of(&w.rb) + tlbt * bc * al) * bi));
    if dead {
        w.rcv_y = rows6(&((pl.cols_of(&w.ry) + tlbt * yc * al) * bi));
    }
    if mass {
        w.blk_a = lead6(&(pl.lead(&w.mtt) + tmc * tlb));
    }
    let alt = al.transpose();
    let base = Subtree3 {
        m: pl.block(&w.mt) + alt * mc * al,
        b: pl.block(&w.bt) + alt * bc * al,
        y: if dead {
            pl.block(&w.yt) + alt * yc * al
        } else {
            Mat3::zeros()
        },
        w: pl.gather(&w.wsum) + alt * wn,
    };
    let wrench = pl.v(&(pl.gather(&w.tsum) + tl.tr_mul(wn)));
    (lead6(&diag_q), lead6(&diag_v), wrench, base)
}

/// The inward sweep of [`super::chain::inward`] on a planar rod (D99–D100)
/// after [`super::planar::outward`]: the closes in `P` coordinates, `τ` and the blocks
/// written as for any rod ([`super::piece::write_piece`]). Out of line
/// for the same reason as [`super::planar::outward`].
#[inline(never)]
pub(crate) fn inward(
    model: &Model,
    rm: &RodModel,
    pr: &PlanarRod,
    work: &mut IdDerivatives,
    r: usize,
    at: &At,
) {
    let dead = has_dead_loads(rm);
    let z = Mat3::zeros();
    let mut sub = Subtree3 {
        m: z,
        b: z,
        y: z,
        w: Vec3::zeros(),
    };
    let pieces = rm.spec.geometry.pieces();
    for (n, (piece, pp)) in pieces.iter().zip(&pr.pieces).enumerate().rev() {
        let pl = Place {
            idx: pr.idx,
            sel: pp.sel,
            k: pp.k,
        };
        let (diag_q, diag_v, wrench, base) =
            close_piece3(&mut work.pieces[r][n], &sub, &pl, dead, !at.dense);
        sub = base;
        let bm = basis6(&piece.basis);
        let (bq, bv) = write_piece(model, rm, n, work, at, &bm, (&diag_q, &diag_v, &wrench));
        let w = &mut work.pieces[r][n];
        w.blk_q = bq;
        w.blk_v = bv;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::derivatives::planar::PlanarDerivMaps;
    use crate::kernels::piece_derivs::{PieceDerivMaps, tangent_transpose_form};

    use crate::derivatives::planar::plane_blocks::{IDX, block, scatter};

    /// `𝒬` on `P` (D99) against the P block of the six-direction form
    /// (D36) for P-valued wrench sums, and the six-direction form has no
    /// P–P⊥ coupling then: curvatures zero to large, the three planes.
    #[test]
    fn planar_form_is_the_p_block_of_the_six_direction_form() {
        let xd = Vec3::new(0.3, -0.5, 0.9);
        let xdd = Vec3::new(0.2, 0.7, -0.6);
        let f = |i: usize, s: f64| Vec3::new(0.4 - 0.3 * s * i as f64, 1.1 + s, -0.7 * i as f64);
        for idx in &IDX {
            for kappa in [0.0, 1e-9, 0.8, 40.0] {
                let xi = Vec3::new(kappa, 1.05, 0.2);
                let dm = PlanarDerivMaps::new(&xi, &xd, &xdd);
                let d6 = PieceDerivMaps::new(
                    &scatter(idx, &xi),
                    &scatter(idx, &xd),
                    &scatter(idx, &xdd),
                );
                let phi = [0, 1, 2, 3].map(|i| f(i, 1.0));
                let chi = [0, 1, 2, 3].map(|i| f(i, -0.5));
                let got = tangent_transpose_form3(&dm.p, &dm.kbar(), &phi, &chi);
                let full = tangent_transpose_form(
                    &d6.p,
                    &d6.kbar(),
                    &phi.map(|v| scatter(idx, &v)),
                    &chi.map(|v| scatter(idx, &v)),
                );
                let want = block(idx, &full);
                let err = (got - want).amax();
                assert!(err <= 1e-12 * want.amax(), "{idx:?}, κ {kappa}: {err:e}");
                for r in 0..6 {
                    for c in 0..6 {
                        if idx.contains(&r) != idx.contains(&c) {
                            assert_eq!(full[(r, c)], 0.0, "{idx:?} ({r}, {c})");
                        }
                    }
                }
            }
        }
    }
}
