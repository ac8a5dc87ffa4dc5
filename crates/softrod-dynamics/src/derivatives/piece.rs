//! What the inward sweeps carry per piece (docs/theory-derivatives.md
//! D42–D47): the per-piece buffers, what a subtree hands to the frame it
//! hangs from, the closing of one piece (its diagonal blocks, transmitted
//! wrench and world-frame pairing quantities) and the writing of its `τ`
//! and blocks with the strain-space terms.

use super::point::PointLin;
use super::{At, IdDerivatives};
use crate::forces::linearized::cable_terms;
use crate::kernels::mat6::{Cols, mm_part, mm3};
use crate::kernels::piece_derivs::{
    Coefficients, PieceDerivMaps, lambda, tangent_transpose_form_basis,
};
use crate::model::{Model, RodModel};
use softrod_lie::{Mat6, Pose, Vec6, ad};

/// Per-piece buffers of the derivative sweeps (all fixed-size; `k_n`-sized
/// quantities in the leading columns / rows of 6×6).
#[derive(Clone, Debug)]
pub(crate) struct PieceWork {
    /// World poses of the piece base `G_{n−1}` and tip `G_n`; local tip pose.
    pub(crate) base_world: Pose,
    pub(crate) tip_world: Pose,
    pub(crate) tip: Pose,
    /// `T₋(ℓ)`, `η(ℓ)` and the tip linearizations `H_η B`, `H_η̇ B`, `H_v̇ B`
    /// (D39–D41, `k` columns, D90).
    pub(crate) tm_tip: Mat6,
    pub(crate) eta_tip: Vec6,
    pub(crate) etad_tip: Vec6,
    pub(crate) h_eta: Mat6,
    pub(crate) h_etad: Mat6,
    pub(crate) h_vd: Mat6,
    pub(crate) co_tip: Coefficients,
    /// Own-point sums (frame `L_{n−1}`): `𝓜ᵗ`, `𝓑ᵗ`, `𝒴ᵗ` (D43) and the
    /// receivers `Σ w BᵀT₋ᵀ X A` for `X = 𝓜, 𝓑̄, 𝒴` (D45; `k` rows, D90).
    pub(crate) mt: Mat6,
    pub(crate) bt: Mat6,
    pub(crate) yt: Mat6,
    pub(crate) rm: Mat6,
    pub(crate) rb: Mat6,
    pub(crate) ry: Mat6,
    /// The own points' (and inside subtrees') part of the mass matrix's
    /// diagonal block in strain space, `Σ w BᵀT₋ᵀ𝓜T₋B` (D86, k×k; summed
    /// only by the linearization without the dense matrices).
    pub(crate) mtt: Mat6,
    /// `Σ w T₋ᵀ f`, `Σ w Aᵀ f` (D17–D18 sums).
    pub(crate) tsum: Vec6,
    pub(crate) wsum: Vec6,
    /// The same sums of the own Gauss points' inertial wrench densities
    /// alone, `f = 𝓜η̇′ + ad*_η 𝓜η` (gravity in `η̇′`; no drag, loads or
    /// inside subtrees): linear in the density, for the inertia products
    /// of [`super::vjp::inverse_dynamics_inertia_vjp`] (D85).
    pub(crate) tin: Vec6,
    pub(crate) win: Vec6,
    /// Own-point derivative sums (D42) in the basis directions (D90): the
    /// diagonal ones `Bᵀ(·)B` (k×k), the wrench's `(·)B` (6×k).
    pub(crate) dq_diag: Mat6,
    pub(crate) dv_diag: Mat6,
    pub(crate) dq_w: Mat6,
    pub(crate) dv_w: Mat6,
    /// `φ_i`, `χ_i` of (D36).
    pub(crate) phi: [Vec6; 4],
    pub(crate) chi: [Vec6; 4],
    /// `P^i = ad_ξ^i` and `k̄ = (k; 0)` for 𝒬 (D36).
    pub(crate) powers: [Mat6; 4],
    pub(crate) kbar: Vec6,
    /// Pairing quantities in the world frame (D46), `k` columns (or rows).
    pub(crate) s_world: Mat6,
    pub(crate) dwq_world: Mat6,
    pub(crate) dwv_world: Mat6,
    pub(crate) src_wq: Mat6,
    pub(crate) src_uq: Mat6,
    pub(crate) src_wv: Mat6,
    pub(crate) src_uv: Mat6,
    pub(crate) rcv_m: Mat6,
    pub(crate) rcv_b: Mat6,
    pub(crate) rcv_y: Mat6,
    /// The piece's (or joint's) diagonal blocks `∂τ_n/∂q_n`, `∂τ_n/∂q̇_n`
    /// with the strain-space terms (k×k in the leading part), kept for the
    /// products of [`super::vjp`].
    pub(crate) blk_q: Mat6,
    pub(crate) blk_v: Mat6,
    /// The diagonal block of `M` (k×k in the leading part), D86.
    pub(crate) blk_a: Mat6,
}

impl PieceWork {
    pub(crate) fn new() -> Self {
        let z = Mat6::zeros();
        Self {
            base_world: Pose::identity(),
            tip_world: Pose::identity(),
            tip: Pose::identity(),
            tm_tip: z,
            eta_tip: Vec6::zeros(),
            etad_tip: Vec6::zeros(),
            h_eta: z,
            h_etad: z,
            h_vd: z,
            co_tip: Coefficients {
                c: [0.0; 4],
                d: [0.0; 4],
                h: [0.0; 4],
            },
            mt: z,
            bt: z,
            yt: z,
            rm: z,
            rb: z,
            ry: z,
            mtt: z,
            tsum: Vec6::zeros(),
            wsum: Vec6::zeros(),
            tin: Vec6::zeros(),
            win: Vec6::zeros(),
            dq_diag: z,
            dv_diag: z,
            dq_w: z,
            dv_w: z,
            phi: [Vec6::zeros(); 4],
            chi: [Vec6::zeros(); 4],
            powers: [z; 4],
            kbar: Vec6::zeros(),
            s_world: z,
            dwq_world: z,
            dwv_world: z,
            src_wq: z,
            src_uq: z,
            src_wv: z,
            src_uv: z,
            rcv_m: z,
            rcv_b: z,
            rcv_y: z,
            blk_q: z,
            blk_v: z,
            blk_a: z,
        }
    }

    /// The tip of the piece (or joint) from its linearization at `x = ℓ`
    /// (`base_world` already set; `H` in the basis directions, D90).
    pub(crate) fn set_tip(&mut self, g: Pose, p: &PointLin, dm: &PieceDerivMaps) {
        self.tip = g;
        self.tm_tip = p.t.to_mat6();
        self.eta_tip = p.eta;
        self.etad_tip = p.etad;
        self.h_eta = p.h_eta;
        self.h_etad = p.h_etad;
        self.h_vd = p.h_vd;
        self.co_tip = p.co;
        self.powers = dm.p;
        self.kbar = dm.kbar();
        self.tip_world = self.base_world.compose(&g);
    }

    pub(crate) fn reset_sums(&mut self) {
        let z = Mat6::zeros();
        self.mt = z;
        self.bt = z;
        self.yt = z;
        self.rm = z;
        self.rb = z;
        self.ry = z;
        self.mtt = z;
        self.tsum = Vec6::zeros();
        self.wsum = Vec6::zeros();
        self.tin = Vec6::zeros();
        self.win = Vec6::zeros();
        self.dq_diag = z;
        self.dv_diag = z;
        self.dq_w = z;
        self.dv_w = z;
        self.phi = [Vec6::zeros(); 4];
        self.chi = [Vec6::zeros(); 4];
    }
}

/// What a subtree hands to the frame it hangs from (D43): the composite
/// inertia, velocity-product and dead-load operators `𝓜ᶜ`, `𝓑ᶜ`, `𝒴ᶜ` and
/// the transmitted wrench `W`, all in that frame's axes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Subtree {
    pub m: Mat6,
    pub b: Mat6,
    pub y: Mat6,
    pub w: Vec6,
}

impl Subtree {
    pub(crate) fn zero() -> Self {
        Self {
            m: Mat6::zeros(),
            b: Mat6::zeros(),
            y: Mat6::zeros(),
            w: Vec6::zeros(),
        }
    }

    /// The same subtree in the axes of a frame from which twists reach
    /// this one's by `η = a η′` (a rigid map): `aᵀ X a`, `aᵀ W`.
    pub(crate) fn through(&self, a: &Mat6, dead: bool) -> Self {
        let at = a.transpose();
        Self {
            m: mm3(&at, &self.m, a),
            b: mm3(&at, &self.b, a),
            y: if dead {
                mm3(&at, &self.y, a)
            } else {
                Mat6::zeros()
            },
            w: at * self.w,
        }
    }

    pub(crate) fn add(&mut self, o: &Self) {
        self.m += o.m;
        self.b += o.b;
        self.y += o.y;
        self.w += o.w;
    }
}

/// One piece of the inward sweep (D43–D46) given what its subtree hands to
/// its tip frame (`tip`): writes the piece's world-frame pairing quantities
/// into `w` and returns its diagonal blocks in strain space (6×6, before
/// `Bᵀ · B` and the strain-space terms of (D47)), the wrench it projects on
/// its coordinates (`τ_n = Bᵀ(·)` before those terms) and what it hands to
/// its base frame.
#[inline(always)]
pub(crate) fn close_piece(
    w: &mut PieceWork,
    tip: &Subtree,
    bm: &Mat6,
    dead: bool,
) -> (Mat6, Mat6, Vec6, Subtree) {
    let (mc, bc, yc, wn) = (&tip.m, &tip.b, &tip.y, &tip.w);
    let al = w.tip.ad_inv().to_mat6();
    let tl = w.tm_tip;
    let adeta = ad(&w.eta_tip);
    // Everything with a strain-direction index `ζ` is needed only on the
    // basis's `k` directions (its columns `ζ = B eᵢ`, or rows of `Bᵀ`):
    // carried as `X B` (docs/theory-derivatives.md D87), the tip's `H` and
    // the own-point sums since the points (D90).
    let c = Cols::of(bm);
    let k = c.k;
    let tlb = c.right(&tl);
    // (D43): the subtree's wrench at L_n changes by
    // 𝓜ᶜ w̄ + 𝓑ᶜ u + 𝒴ᶜ Δ, with u = δη(ℓ), w̄ = δη̇′(ℓ) + ad_η(ℓ) δη(ℓ).
    let uq = w.h_eta;
    let wq = w.h_etad + mm_part(&adeta, &uq, 6, k);
    let mut dwn_q = mm_part(mc, &wq, 6, k) + mm_part(bc, &uq, 6, k);
    if dead {
        dwn_q += mm_part(yc, &tlb, 6, k);
    }
    let wv = w.h_vd + mm_part(&adeta, &tlb, 6, k);
    let dwn_v = mm_part(mc, &wv, 6, k) + mm_part(bc, &tlb, 6, k);
    let (mut phi, mut chi) = (w.phi, w.chi);
    for i in 0..4 {
        phi[i] += wn * w.co_tip.d[i];
        chi[i] += wn * w.co_tip.c[i];
    }
    let qform = tangent_transpose_form_basis(&w.powers, &w.kbar, &phi, &chi, &c);
    let tlbt = tlb.transpose();
    let diag_q = w.dq_diag + mm_part(&tlbt, &dwn_q, k, k) + qform;
    let diag_v = w.dv_diag + mm_part(&tlbt, &dwn_v, k, k);
    let alt = al.transpose();
    let dw_q = w.dq_w + mm_part(&alt, &(mm_part(&lambda(wn), &tlb, 6, k) + dwn_q), 6, k);
    let dw_v = w.dv_w + mm_part(&alt, &dwn_v, 6, k);
    // World-frame pairing quantities (D46).
    let to_world_tip = w.tip_world.ad().to_mat6();
    let base_inv = w.base_world.ad_inv().to_mat6();
    w.s_world = mm_part(&to_world_tip, &tlb, 6, k);
    w.src_wq = mm_part(&to_world_tip, &wq, 6, k);
    w.src_uq = mm_part(&to_world_tip, &uq, 6, k);
    w.src_wv = mm_part(&to_world_tip, &wv, 6, k);
    w.src_uv = w.s_world;
    let bit = base_inv.transpose();
    w.dwq_world = mm_part(&bit, &dw_q, 6, k);
    w.dwv_world = mm_part(&bit, &dw_v, 6, k);
    // `Bᵀ(X + T₋(ℓ)ᵀ 𝓒 A)` then `· Ad⁻¹`: `k` rows.
    let tmc = mm_part(&tlbt, mc, k, 6);
    w.rcv_m = mm_part(&(w.rm + mm_part(&tmc, &al, k, 6)), &base_inv, k, 6);
    let tbc = mm_part(&tlbt, bc, k, 6);
    w.rcv_b = mm_part(&(w.rb + mm_part(&tbc, &al, k, 6)), &base_inv, k, 6);
    if dead {
        let tyc = mm_part(&tlbt, yc, k, 6);
        w.rcv_y = mm_part(&(w.ry + mm_part(&tyc, &al, k, 6)), &base_inv, k, 6);
    }
    // Composites carried to L_{n−1} (D43), and τ_n's wrench (D18).
    let base = Subtree {
        m: w.mt + mm3(&alt, mc, &al),
        b: w.bt + mm3(&alt, bc, &al),
        y: if dead {
            w.yt + mm3(&alt, yc, &al)
        } else {
            Mat6::zeros()
        },
        w: w.wsum + alt * wn,
    };
    (diag_q, diag_v, w.tsum + tl.transpose() * wn, base)
}

/// The diagonal block of the mass matrix of a closed piece or joint (D86):
/// `Bᵀ(Σ w T₋ᵀ𝓜T₋ + T₋(ℓ)ᵀ 𝓜ᶜ T₋(ℓ))B`, the own points' (and inside
/// subtrees') inertia and the composite `mc` at the tip, each moved by the
/// piece's acceleration `T₋ B q̈_n`.
#[inline(always)]
pub(crate) fn close_mass(w: &mut PieceWork, mc: &Mat6, bm: &Mat6) {
    let tl = w.tm_tip;
    let c = Cols::of(bm);
    let k = c.k;
    let tlb = c.right(&tl);
    let tlbt = tlb.transpose();
    w.blk_a = w.mtt + mm_part(&mm_part(&tlbt, mc, k, 6), &tlb, k, k);
}

/// Writes a piece's `τ_n` and returns its diagonal blocks (k×k in the
/// leading part of 6×6), adding the strain-space terms (D13, D15, D47):
/// `K_n q_n + D_n q̇_n`, the elastic offset and the cables' force and
/// strain Hessian; the blocks go into the dense matrices too when the
/// evaluation forms them (`at.dense`). `bm`: the piece's basis
/// ([`super::point::basis6`]); `diag_q`, `diag_v`, `wrench` are [`close_piece`]'s.
#[inline(always)]
pub(crate) fn write_piece(
    model: &Model,
    rm: &RodModel,
    n: usize,
    work: &mut IdDerivatives,
    at: &At,
    bm: &Mat6,
    (diag_q, diag_v, wrench): (&Mat6, &Mat6, &Vec6),
) -> (Mat6, Mat6) {
    let At { t, q, qd, .. } = *at;
    let scale = at.forces.load_scale;
    let piece = &rm.spec.geometry.pieces()[n];
    let pd = &rm.pieces[n];
    let k = piece.basis.dof();
    let o = rm.dof_offset + piece.dof_offset;
    let xi = piece.strain(&q[rm.dofs()]);
    let (cable_force, cable_hess) = cable_terms(
        model,
        rm,
        (n, &q[rm.dofs()]),
        &xi,
        t,
        scale,
        work.tensions.as_ref(),
    );
    let mut dq6 = diag_q + Cols::of(bm).both(&cable_hess);
    let mut dv6 = *diag_v;
    let inert = wrench + cable_force;
    for i in 0..k {
        let mut tau = piece.basis.column(i).dot(&inert) + pd.offset6[i];
        for j in 0..k {
            tau += pd.stiffness[(i, j)] * q[o + j] + pd.damping[(i, j)] * qd[o + j];
            dq6[(i, j)] += pd.stiffness[(i, j)];
            dv6[(i, j)] += pd.damping[(i, j)];
        }
        work.tau[o + i] = tau;
    }
    if at.dense {
        put_block(work, o, k, &dq6, &dv6);
    }
    (dq6, dv6)
}

/// Writes the diagonal blocks `(bq, bv)` of the coordinates `o .. o + k`
/// into the dense `∂τ/∂q`, `∂τ/∂q̇`.
#[inline(always)]
pub(crate) fn put_block(work: &mut IdDerivatives, o: usize, k: usize, bq: &Mat6, bv: &Mat6) {
    for i in 0..k {
        for j in 0..k {
            work.dtau_dq[(o + i, o + j)] = bq[(i, j)];
            work.dtau_dqd[(o + i, o + j)] = bv[(i, j)];
        }
    }
}
