//! The closes of the inward sweep on planar rods, in se(2)
//! (docs/theory-derivatives.md D99–D100, D107): after the planar outward
//! sweep ([`super::planar::outward`], D97–D98), each piece's composites,
//! diagonal blocks, `𝒬`, transmitted wrench and mass-matrix block on 3×3
//! blocks and `k` columns, and its pairing quantities in the axes of the
//! rod's base frame (3×k), written into the planar buffers
//! ([`PlanarWork`]) the pairings and the O(N) products of planar rods
//! read ([`super::planar_products`]).

use super::planar::{Place, PlanarWork, ad3, lambda3};
use super::{At, IdDerivatives};
use crate::forces::linearized::{cable_terms, has_dead_loads};
use crate::kernels::planar::Pose2;
use crate::model::planar::PlanarRod;
use crate::model::{Model, RodModel};
use softrod_lie::{Mat3, Vec3};

impl Place {
    /// `X B` in `P` coordinates (3×k, the basis's columns of `X`).
    #[inline(always)]
    pub(crate) fn right(&self, x: &Mat3) -> Mat3 {
        Mat3::from_fn(|r, j| if j < self.k { x[(r, self.sel[j])] } else { 0.0 })
    }

    /// `Bᵀ X` in `P` coordinates (k×3, the basis's rows of `X`).
    #[inline(always)]
    pub(crate) fn left(&self, x: &Mat3) -> Mat3 {
        Mat3::from_fn(|i, c| if i < self.k { x[(self.sel[i], c)] } else { 0.0 })
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

/// `Ad_g` on `P` as a matrix, the inverse of [`Pose2::ad_inv`]:
/// `Ad_g η = (ω, R v − ω J p)`, `[[1, 0], [−Jp, R]]`.
#[inline(always)]
pub(crate) fn ad_mat(g: &Pose2) -> Mat3 {
    Mat3::new(1.0, 0.0, 0.0, g.p[1], g.c, -g.s, -g.p[0], g.s, g.c)
}

/// [`super::piece::close_piece`] (and, with `mass`,
/// [`super::piece::close_mass`]) on a planar piece, in `P` coordinates
/// (D99–D100, D107): the composites carried by the planar `Ad⁻¹` of the
/// tip, the diagonal blocks, the transmitted wrench and `𝒬` on 3×3 and
/// `k` columns; the pairing quantities (D46) in the axes of the rod's
/// base frame, `Ad` of the tip relative to it times the 3×k blocks, the
/// receivers times `Ad⁻¹` of the base relative to it. Returns the diagonal
/// blocks (k×k, before the strain-space terms), the wrench `τ_n` projects
/// (before them; in `P`) and the subtree handed to the base frame.
#[inline(always)]
fn close_piece3(
    w: &mut PlanarWork,
    tip: &Subtree3,
    pl: &Place,
    dead: bool,
    mass: bool,
) -> (Mat3, Mat3, Vec3, Subtree3) {
    let (mc, bc, yc, wn) = (&tip.m, &tip.b, &tip.y, &tip.w);
    let s = &w.s;
    let al = w.tip.ad_inv();
    let tl = w.tm_tip;
    let tlb = pl.right(&tl);
    let tlbt = tlb.transpose();
    let adeta = ad3(&w.eta_tip);
    // (D43) on P, `k` columns: u = δη(ℓ), w̄ = δη̇′(ℓ) + ad_η(ℓ) δη(ℓ).
    let uq = w.h_eta;
    let wq = w.h_etad + adeta * uq;
    let mut dwn_q = mc * wq + bc * uq;
    if dead {
        dwn_q += yc * tlb;
    }
    let wv = w.h_vd + adeta * tlb;
    let dwn_v = mc * wv + bc * tlb;
    let mut phi = [Vec3::zeros(); 4];
    let mut chi = [Vec3::zeros(); 4];
    for i in 0..4 {
        phi[i] = s.phi[i] + wn * w.co_tip.d[i];
        chi[i] = s.chi[i] + wn * w.co_tip.c[i];
    }
    let qform = pl.both(&tangent_transpose_form3(&w.powers, &w.kbar, &phi, &chi));
    let diag_q = pl.both(&s.dq_diag) + tlbt * dwn_q + qform;
    let diag_v = pl.both(&s.dv_diag) + tlbt * dwn_v;
    let dw_q = pl.right(&s.dq_w) + al.tr_mul(&(lambda3(wn) * tlb + dwn_q));
    let dw_v = pl.right(&s.dv_w) + al.tr_mul(&dwn_v);
    // Pairing quantities (D46) in the rod base frame's axes (D107).
    let aw = ad_mat(&w.tip_rel);
    let bi = w.base_rel.ad_inv();
    w.s_rod = aw * tlb;
    w.src_wq = aw * wq;
    w.src_uq = aw * uq;
    w.src_wv = aw * wv;
    w.dwq = bi.tr_mul(&dw_q);
    w.dwv = bi.tr_mul(&dw_v);
    let tmc = tlbt * mc;
    w.rcv_m = (pl.left(&s.rm) + tmc * al) * bi;
    w.rcv_b = (pl.left(&s.rb) + tlbt * bc * al) * bi;
    if dead {
        w.rcv_y = (pl.left(&s.ry) + tlbt * yc * al) * bi;
    }
    if mass {
        w.blk_a = pl.both(&s.mtt) + tmc * tlb;
    }
    let alt = al.transpose();
    let base = Subtree3 {
        m: s.mt + alt * mc * al,
        b: s.bt + alt * bc * al,
        y: if dead {
            s.yt + alt * yc * al
        } else {
            Mat3::zeros()
        },
        w: s.wsum + alt * wn,
    };
    (diag_q, diag_v, s.tsum + tl.tr_mul(wn), base)
}

/// [`super::piece::write_piece`] on a planar piece: `τ_n` and the
/// diagonal blocks (k×k) with the strain-space terms (D13, D15, D47),
/// from [`close_piece3`]'s blocks and wrench (in `P`); the blocks go into
/// the dense matrices too when the evaluation forms them.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn write_piece3(
    model: &Model,
    rm: &RodModel,
    pl: &Place,
    n: usize,
    work: &mut IdDerivatives,
    at: &At,
    (diag_q, diag_v, wrench): (Mat3, Mat3, Vec3),
) -> (Mat3, Mat3) {
    let At { t, q, qd, .. } = *at;
    let piece = &rm.spec.geometry.pieces()[n];
    let pd = &rm.pieces[n];
    let k = pl.k;
    let o = rm.dof_offset + piece.dof_offset;
    let (mut dq, mut dv) = (diag_q, diag_v);
    // The basis's column `i` is the unit direction `idx[sel[i]]`.
    let mut inert = Vec3::from_fn(|i, _| if i < k { wrench[pl.sel[i]] } else { 0.0 });
    if !rm.spec.cables.is_empty() {
        let xi = piece.strain(&q[rm.dofs()]);
        let (force, hess) = cable_terms(
            model,
            rm,
            (n, &q[rm.dofs()]),
            &xi,
            t,
            at.forces.load_scale,
            work.tensions.as_ref(),
        );
        for i in 0..k {
            let fi = pl.idx[pl.sel[i]];
            inert[i] += force[fi];
            for j in 0..k {
                dq[(i, j)] += hess[(fi, pl.idx[pl.sel[j]])];
            }
        }
    }
    for i in 0..k {
        let mut tau = inert[i] + pd.offset6[i];
        for j in 0..k {
            tau += pd.stiffness[(i, j)] * q[o + j] + pd.damping[(i, j)] * qd[o + j];
            dq[(i, j)] += pd.stiffness[(i, j)];
            dv[(i, j)] += pd.damping[(i, j)];
        }
        work.tau[o + i] = tau;
    }
    if at.dense {
        for i in 0..k {
            for j in 0..k {
                work.dtau_dq[(o + i, o + j)] = dq[(i, j)];
                work.dtau_dqd[(o + i, o + j)] = dv[(i, j)];
            }
        }
    }
    (dq, dv)
}

/// The inward sweep of [`super::chain::inward`] on a planar rod (D99–D100,
/// D107) after [`super::planar::outward`]: the closes in `P` coordinates,
/// `τ` and the blocks. Out of line for the same reason as
/// [`super::planar::outward`].
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
    for (n, pp) in pr.pieces.iter().enumerate().rev() {
        let pl = Place {
            idx: pr.idx,
            sel: pp.sel,
            k: pp.k,
        };
        let (diag_q, diag_v, wrench, base) =
            close_piece3(&mut work.planar[r][n], &sub, &pl, dead, !at.dense);
        sub = base;
        let (bq, bv) = write_piece3(model, rm, &pl, n, work, at, (diag_q, diag_v, wrench));
        let w = &mut work.planar[r][n];
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

    /// `Ad_g` on `P` (D107) is the inverse of the planar `Ad⁻¹_g` and the
    /// `P` block of the six-direction `Ad` of the embedded pose, for the
    /// three bending planes.
    #[test]
    fn planar_ad_is_the_p_block_of_ad() {
        use crate::model::planar::PlanarRod;
        let g = Pose2 {
            c: 0.6_f64.cos(),
            s: 0.6_f64.sin(),
            p: crate::kernels::planar::V2::new(0.3, -1.7),
        };
        let err = (ad_mat(&g) * g.ad_inv() - Mat3::identity()).amax();
        assert!(err < 1e-15, "{err:e}");
        for (axis, idx) in IDX.iter().enumerate() {
            let pr = PlanarRod {
                idx: *idx,
                axis,
                pieces: Vec::new(),
            };
            let full = pr.embed(&g).ad().to_mat6();
            let err = (ad_mat(&g) - block(idx, &full)).amax();
            assert!(err < 1e-15, "axis {axis}: {err:e}");
        }
    }
}
