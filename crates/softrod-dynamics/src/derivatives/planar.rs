//! The outward sweep of the linearization on planar rods, in se(2)
//! (docs/theory-derivatives.md D95–D98): the strain-derivative maps of a
//! piece (D32–D35 restricted to `P`, D96), every evaluation point's
//! linearization (D39–D41, D97) and the own points' sums (D42–D43, D45)
//! on 3-vectors and 3×3 matrices, kept in the planar per-piece buffers
//! ([`PlanarWork`], D107) for the closes and products that follow.
//!
//! A planar rod ([`PlanarRod`], D71) of a model without a tree: every
//! twist and wrench the sweeps carry along a strain direction of its
//! basis, and every operator between them, maps `P = (ω_a, v_b, v_c)` to
//! itself and `P⊥` to itself (D95). The general path's blocks restricted
//! to `P` are the products of the restricted factors; the entries in
//! `P⊥` rows or columns are contracted by nothing downstream with a `P`
//! direction, and stay zero here.

use super::At;
use crate::forces::external::gravity_base_acceleration;
use crate::forces::linearized::{dead_load_map, drag_diagonal};
use crate::kernels::piece_derivs::Coefficients;
use crate::kernels::planar::{Pose2, ad2, coad2, maps};
use crate::model::planar::{PlanarPiece, PlanarRod};
use crate::model::rod::PieceData;
use crate::model::{Model, RodModel};
use softrod_lie::{Mat3, Mat6, Pose, Vec3, Vec6};
use softrod_mechanics::LoadFrame;

/// `ad_v` on `P` as a matrix, `v = (ω, v_b, v_c)`: `ad_v u = ad2(v, u)`
/// (D95), `[[0, 0, 0], [v_c, 0, −ω], [−v_b, ω, 0]]`.
#[inline(always)]
pub(crate) fn ad3(v: &Vec3) -> Mat3 {
    Mat3::new(0.0, 0.0, 0.0, v[2], 0.0, -v[0], -v[1], v[0], 0.0)
}

/// `ad*_η = −ad_ηᵀ` on `P` (the `P` block of [`softrod_lie::coad`]).
#[inline(always)]
pub(crate) fn coad3(v: &Vec3) -> Mat3 {
    Mat3::new(0.0, -v[2], v[1], 0.0, 0.0, -v[0], 0.0, v[0], 0.0)
}

/// `Λ(h)` on `P`, `Λ(h) ζ = ad*_ζ h` (the `P` block of
/// [`crate::kernels::piece_derivs::lambda`]): `[[0, h_c, −h_b], [−h_c, 0, 0], [h_b, 0, 0]]`.
#[inline(always)]
pub(crate) fn lambda3(h: &Vec3) -> Mat3 {
    Mat3::new(0.0, h[2], -h[1], -h[2], 0.0, 0.0, h[1], 0.0, 0.0)
}

/// `diag(d) X`.
#[inline(always)]
fn rows(d: &Vec3, x: &Mat3) -> Mat3 {
    Mat3::from_fn(|i, j| d[i] * x[(i, j)])
}

/// `X diag(d)`.
#[inline(always)]
fn cols(x: &Mat3, d: &Vec3) -> Mat3 {
    Mat3::from_fn(|i, j| x[(i, j)] * d[j])
}

/// The strain-derivative maps of one planar piece (D96): those of
/// [`crate::kernels::piece_derivs::PieceDerivMaps`] (D32–D35) restricted to
/// `P`, for the strain, rate and acceleration `ξ`, `ξ̇`, `ξ̈` in `P`
/// coordinates, `P = ad_ξ` (3×3). `k̄ = (k; 0)` is `(ξ_ω, 0, 0)` in `P`.
#[derive(Clone, Debug)]
pub(crate) struct PlanarDerivMaps {
    pub theta: f64,
    /// `P^i`, `i = 1…4` (index `i − 1`).
    pub p: [Mat3; 4],
    /// `ξ_ω`, `ξ̇_ω` and `k·ξ̇_k = ξ_ω ξ̇_ω`.
    k: f64,
    kdot: f64,
    kd: f64,
    vd: [Vec3; 4],
    vdd: [Vec3; 4],
    ed: [Mat3; 4],
    edd: [Mat3; 4],
    f: [Mat3; 4],
    e: [Vec3; 4],
    ehat: [Mat3; 4],
}

impl PlanarDerivMaps {
    /// The recurrences of D32–D35 on `P` (D96).
    #[inline(always)]
    pub fn new(xi: &Vec3, xid: &Vec3, xidd: &Vec3) -> Self {
        let pm = ad3(xi);
        let mut p = [pm; 4];
        for i in 1..4 {
            p[i] = pm * p[i - 1];
        }
        let powers = |v: &Vec3| {
            let mut out = [pm * v; 4];
            for i in 1..4 {
                out[i] = pm * out[i - 1];
            }
            out
        };
        let vd = powers(xid);
        let vdd = powers(xidd);
        // E_1(v) = ad_v, E_{i+1}(v) = P E_i(v) + ad_{P^i v}.
        let e_ops = |v: &Vec3, pv: &[Vec3; 4]| {
            let mut out = [ad3(v); 4];
            for i in 1..4 {
                out[i] = pm * out[i - 1] + ad3(&pv[i - 1]);
            }
            out
        };
        let ed = e_ops(xid, &vd);
        let edd = e_ops(xidd, &vdd);
        // F_1 = ad_ξ̇, F_{i+1} = P F_i + ad_ξ̇ P^i.
        let adv = ad3(xid);
        let mut f = [adv; 4];
        for i in 1..4 {
            f[i] = pm * f[i - 1] + adv * p[i - 1];
        }
        // e_1 = 0, e_{i+1} = ad_ξ̇ P^i ξ̇ + P e_i;
        // Ê_1 = 0, Ê_{i+1} = P Ê_i − ad_ξ̇ E_i(ξ̇) − ad_{e_i}.
        let mut e = [Vec3::zeros(); 4];
        let mut ehat = [Mat3::zeros(); 4];
        for i in 1..4 {
            e[i] = adv * vd[i - 1] + pm * e[i - 1];
            ehat[i] = pm * ehat[i - 1] - adv * ed[i - 1] - ad3(&e[i - 1]);
        }
        Self {
            theta: xi[0].abs(),
            p,
            k: xi[0],
            kdot: xid[0],
            kd: xi[0] * xid[0],
            vd,
            vdd,
            ed,
            edd,
            f,
            e,
            ehat,
        }
    }

    /// `𝒟_v` of (D32) on `P` for `v = ξ̇` or (`acc`) `ξ̈`:
    /// `Σ_i d_i (P^i v) k̄ᵀ − c_i E_i(v)`.
    #[inline(always)]
    pub fn d_tangent_applied(&self, co: &Coefficients, acc: bool) -> Mat3 {
        let (pv, e) = if acc {
            (&self.vdd, &self.edd)
        } else {
            (&self.vd, &self.ed)
        };
        let mut u = Vec3::zeros();
        let mut out = Mat3::zeros();
        for i in 0..4 {
            u += pv[i] * co.d[i];
            out -= e[i] * co.c[i];
        }
        let mut c0 = out.column_mut(0);
        c0 += u * self.k;
        out
    }

    /// `Ṫ = Σ_i d_i (k·ξ̇_k) P^i + c_i F_i` (D33) on `P`.
    #[inline(always)]
    pub fn tangent_rate(&self, co: &Coefficients) -> Mat3 {
        let mut out = Mat3::zeros();
        for i in 0..4 {
            out += self.p[i] * (co.d[i] * self.kd) + self.f[i] * co.c[i];
        }
        out
    }

    /// `𝒟²` of (D35) on `P`:
    /// `Σ_i h_i(k·ξ̇_k)(P^iξ̇)k̄ᵀ + d_i(P^iξ̇)ξ̇̄ᵀ − d_i(k·ξ̇_k)E_i(ξ̇) + d_i e_i k̄ᵀ + c_i Ê_i`.
    #[inline(always)]
    pub fn bias_strain_derivative(&self, co: &Coefficients) -> Mat3 {
        let mut uk = Vec3::zeros();
        let mut ud = Vec3::zeros();
        let mut out = Mat3::zeros();
        for i in 0..4 {
            uk += self.vd[i] * (co.h[i] * self.kd) + self.e[i] * co.d[i];
            ud += self.vd[i] * co.d[i];
            out += self.ehat[i] * co.c[i] - self.ed[i] * (co.d[i] * self.kd);
        }
        let mut c0 = out.column_mut(0);
        c0 += uk * self.k + ud * self.kdot;
        out
    }

    /// `k̄ = (k; 0)` in `P`.
    pub fn kbar(&self) -> Vec3 {
        Vec3::new(self.k, 0.0, 0.0)
    }
}

/// One evaluation point of a planar piece linearized on `P` (D97): `Ad⁻¹`,
/// `T₋`, `η`, `η̇′` and `H_η`, `H_η̇`, `H_v̇` over all three directions of
/// `P` (the basis's columns are taken when the piece's sums are written).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PointLin3 {
    pub a: Mat3,
    pub t: Mat3,
    pub eta: Vec3,
    pub etad: Vec3,
    pub h_eta: Mat3,
    pub h_etad: Mat3,
    pub h_vd: Mat3,
    pub co: Coefficients,
}

/// A planar piece's strain, rates, maps and base motion in `P` (gravity in
/// `η̇′₀`).
#[derive(Clone, Copy)]
pub(crate) struct PlanarLin<'a> {
    pub dm: &'a PlanarDerivMaps,
    pub xi: &'a Vec3,
    pub xid: &'a Vec3,
    pub xidd: &'a Vec3,
    pub eta0: &'a Vec3,
    pub etad0: &'a Vec3,
}

/// The point at local abscissa `x` of the planar piece `pc`: its planar
/// local pose and linearization (D39–D41 on `P`, D97).
#[inline(always)]
pub(crate) fn linearize_point3(pc: &PlanarLin, x: f64) -> (Pose2, PointLin3) {
    let PlanarLin {
        dm,
        xi,
        xid,
        xidd,
        eta0,
        etad0,
    } = *pc;
    let (g, t, beta) = maps(xi, xid, x, true);
    let a = g.ad_inv();
    let c = a * eta0;
    let sv = t * xid;
    let eta = c + sv;
    let a0 = a * etad0;
    let etad = a0 + t * xidd + ad2(&c, &sv) + beta;
    let co = Coefficients::at(x, dm.theta);
    let d1 = dm.d_tangent_applied(&co, false);
    let d2 = dm.d_tangent_applied(&co, true);
    let dd = dm.bias_strain_derivative(&co);
    let td = dm.tangent_rate(&co);
    let adc = ad3(&c);
    let adct = adc * t;
    // (D39): δη = ad_c Δ + 𝒟_ξ̇ ζ with Δ = T₋ζ.
    let h_eta = adct + d1;
    // (D40): δη̇′ = ad_{a₀}Δ − ad_{Tξ̇} ad_c Δ + 𝒟_ξ̈ ζ + ad_c 𝒟_ξ̇ ζ + 𝒟² ζ.
    let h_etad = ad3(&a0) * t - ad3(&sv) * adct + d2 + adc * d1 + dd;
    // (D41): ∂η̇′/∂ξ̇ = ad_c T₋ + 𝒟_ξ̇ + Ṫ.
    let h_vd = h_eta + td;
    (
        g,
        PointLin3 {
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

/// A piece's own-point sums on `P` (D42–D43, D45, D85–D86), in `P`
/// coordinates over all three directions (those of [`super::piece::PieceWork`] of the
/// six-direction sweeps, restricted to `P`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Sums3 {
    pub(crate) dq_diag: Mat3,
    pub(crate) dv_diag: Mat3,
    pub(crate) dq_w: Mat3,
    pub(crate) dv_w: Mat3,
    pub(crate) mt: Mat3,
    pub(crate) bt: Mat3,
    pub(crate) yt: Mat3,
    pub(crate) rm: Mat3,
    pub(crate) rb: Mat3,
    pub(crate) ry: Mat3,
    pub(crate) mtt: Mat3,
    pub(crate) tsum: Vec3,
    pub(crate) wsum: Vec3,
    pub(crate) tin: Vec3,
    pub(crate) win: Vec3,
    pub(crate) phi: [Vec3; 4],
    pub(crate) chi: [Vec3; 4],
}

impl Sums3 {
    pub(crate) fn zero() -> Self {
        let z = Mat3::zeros();
        Self {
            dq_diag: z,
            dv_diag: z,
            dq_w: z,
            dv_w: z,
            mt: z,
            bt: z,
            yt: z,
            rm: z,
            rb: z,
            ry: z,
            mtt: z,
            tsum: Vec3::zeros(),
            wsum: Vec3::zeros(),
            tin: Vec3::zeros(),
            win: Vec3::zeros(),
            phi: [Vec3::zeros(); 4],
            chi: [Vec3::zeros(); 4],
        }
    }
}

/// Per-piece buffers of the derivative sweeps of a planar rod (D98, D107):
/// what [`super::piece::PieceWork`] holds for the six-direction sweeps, on `P` and in
/// 3×3 blocks. The outward sweep writes the sums and the tip; the close
/// ([`super::planar_close::inward`]) the diagonal blocks and the pairing
/// quantities, which are taken in the axes of the rod's base frame (D107)
/// instead of the world's: every pairing contracts a twist with a wrench
/// of the same rod, so a common rigid change of axes cancels, and in the
/// base frame's axes the twists and wrenches of a planar rod stay in `P`.
/// A "3×k" block holds the basis's `k` columns in its leading columns
/// (zero beyond), a "k×3" block its rows, "k×k" both.
#[derive(Clone, Debug)]
pub(crate) struct PlanarWork {
    /// The own points' sums (frame `L_{n−1}`).
    pub(crate) s: Sums3,
    /// `Bᵀ` times the inertial sum `Σ w T₋ᵀ f` (k entries, D85).
    pub(crate) tin_b: Vec3,
    /// The local tip pose `g(ℓ)`, and the poses of the piece's base and tip
    /// relative to the rod's base frame.
    pub(crate) tip: Pose2,
    pub(crate) base_rel: Pose2,
    pub(crate) tip_rel: Pose2,
    /// `T₋(ℓ)`, `η(ℓ)`, `η̇′(ℓ)`; `H_η B`, `H_η̇ B`, `H_v̇ B` (3×k) at the tip.
    pub(crate) tm_tip: Mat3,
    pub(crate) eta_tip: Vec3,
    pub(crate) etad_tip: Vec3,
    pub(crate) h_eta: Mat3,
    pub(crate) h_etad: Mat3,
    pub(crate) h_vd: Mat3,
    pub(crate) co_tip: Coefficients,
    /// `P^i` and `k̄` of the piece's strain (D36 on `P`).
    pub(crate) powers: [Mat3; 4],
    pub(crate) kbar: Vec3,
    /// Pairing quantities (D46) in the rod base frame's axes: `Ad S` (3×k),
    /// the sources `Ad w̄`, `Ad u` (3×k), the columns `δW` (3×k), the
    /// receivers `ℛ` (k×3).
    pub(crate) s_rod: Mat3,
    pub(crate) src_wq: Mat3,
    pub(crate) src_uq: Mat3,
    pub(crate) src_wv: Mat3,
    pub(crate) dwq: Mat3,
    pub(crate) dwv: Mat3,
    pub(crate) rcv_m: Mat3,
    pub(crate) rcv_b: Mat3,
    pub(crate) rcv_y: Mat3,
    /// The diagonal blocks of `∂τ/∂q`, `∂τ/∂q̇` and `M` (k×k).
    pub(crate) blk_q: Mat3,
    pub(crate) blk_v: Mat3,
    pub(crate) blk_a: Mat3,
}

impl PlanarWork {
    pub(crate) fn new() -> Self {
        let z = Mat3::zeros();
        Self {
            s: Sums3::zero(),
            tin_b: Vec3::zeros(),
            tip: Pose2::IDENTITY,
            base_rel: Pose2::IDENTITY,
            tip_rel: Pose2::IDENTITY,
            tm_tip: z,
            eta_tip: Vec3::zeros(),
            etad_tip: Vec3::zeros(),
            h_eta: z,
            h_etad: z,
            h_vd: z,
            co_tip: Coefficients {
                c: [0.0; 4],
                d: [0.0; 4],
                h: [0.0; 4],
            },
            powers: [z; 4],
            kbar: Vec3::zeros(),
            s_rod: z,
            src_wq: z,
            src_uq: z,
            src_wv: z,
            dwq: z,
            dwv: z,
            rcv_m: z,
            rcv_b: z,
            rcv_y: z,
            blk_q: z,
            blk_v: z,
            blk_a: z,
        }
    }
}

/// Where a planar piece's basis sits in `P` and `P` in the six
/// directions: `idx` the full indices of `P`, `sel` the `P` position of
/// each of the basis's `k` columns.
#[derive(Clone, Copy)]
pub(crate) struct Place {
    pub(crate) idx: [usize; 3],
    pub(crate) sel: [usize; 3],
    pub(crate) k: usize,
}

impl Place {
    /// The `P` block of a 6×6.
    #[inline(always)]
    pub(crate) fn block(&self, m: &Mat6) -> Mat3 {
        Mat3::from_fn(|r, c| m[(self.idx[r], self.idx[c])])
    }

    #[inline(always)]
    pub(crate) fn gather(&self, v: &Vec6) -> Vec3 {
        Vec3::new(v[self.idx[0]], v[self.idx[1]], v[self.idx[2]])
    }
}

/// The own points and point loads of one planar piece (D42–D43, D45 on
/// `P`, D97–D98): as [`super::point::own_points`], every product 3×3.
/// `pose` is the world pose of the piece's base frame. Writes (does not
/// add to) the sums of `w`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn own_points3(
    rm: &RodModel,
    pr: &PlanarRod,
    pd: &PieceData,
    pp: &PlanarPiece,
    pc: &PlanarLin,
    pose: &Pose,
    drag: Option<&Vec3>,
    scale: f64,
    mass: bool,
    w: &mut PlanarWork,
) {
    let pl_ = Place {
        idx: pr.idx,
        sel: pp.sel,
        k: pp.k,
    };
    w.s = Sums3::zero();
    let s = &mut w.s;
    let apart = drag.is_some() || !rm.spec.distributed_loads.is_empty();
    for (qp, m) in pd.points.iter().zip(&pp.inertia) {
        let (g, p) = linearize_point3(pc, qp.x);
        let me = m.component_mul(&p.eta);
        let mut f = m.component_mul(&p.etad) + coad2(&p.eta, &me);
        if apart {
            let fw = f * qp.w;
            s.tin += p.t.tr_mul(&fw);
            s.win += p.a.tr_mul(&fw);
        }
        // (D38): b = Λ(𝓜η) + ad*_η 𝓜 + C.
        let mut b = lambda3(&me) + cols(&coad3(&p.eta), m);
        if let Some(c) = drag {
            f += c.component_mul(&p.eta);
            b += Mat3::from_diagonal(c);
        }
        let mut y = Mat3::zeros();
        let mut has_y = false;
        if !rm.spec.distributed_loads.is_empty() {
            let world = pose.compose(&pr.embed(&g));
            for dl in &rm.spec.distributed_loads {
                let load = dl.wrench_density(&world) * scale;
                f -= pl_.gather(&load);
                if dl.frame == LoadFrame::World {
                    y += pl_.block(&dead_load_map(&load));
                    has_y = true;
                }
            }
        }
        let wt = qp.w;
        let t = &p.t;
        let mut df_q = rows(m, &p.h_etad) + b * p.h_eta;
        if has_y {
            df_q += y * t;
        }
        let df_q = df_q * wt;
        let df_v = (rows(m, &p.h_vd) + b * t) * wt;
        let fw = f * wt;
        s.dq_diag += t.tr_mul(&df_q);
        s.dv_diag += t.tr_mul(&df_v);
        s.dq_w += p.a.tr_mul(&(lambda3(&fw) * t + df_q));
        s.dv_w += p.a.tr_mul(&df_v);
        s.tsum += t.tr_mul(&fw);
        s.wsum += p.a.tr_mul(&fw);
        for i in 0..4 {
            s.phi[i] += f * (wt * p.co.d[i]);
            s.chi[i] += f * (wt * p.co.c[i]);
        }
        // (D43): B̄ = b − 𝓜 ad_η.
        let bbar = b - rows(m, &ad3(&p.eta));
        let ma = rows(&(m * wt), &p.a);
        let ba = (bbar * wt) * p.a;
        s.mt += p.a.tr_mul(&ma);
        s.bt += p.a.tr_mul(&ba);
        s.rm += t.tr_mul(&ma);
        s.rb += t.tr_mul(&ba);
        if mass {
            s.mtt += t.tr_mul(&rows(&(m * wt), t));
        }
        if has_y {
            let ya = (y * wt) * p.a;
            s.yt += p.a.tr_mul(&ya);
            s.ry += t.tr_mul(&ya);
        }
    }
    if !apart {
        s.tin = s.tsum;
        s.win = s.wsum;
    }
    for pl in &pd.loads {
        let load = &rm.spec.point_loads[pl.index];
        let (g, t, _) = maps(pc.xi, pc.xid, pl.x, false);
        let a = g.ad_inv();
        let co = Coefficients::at(pl.x, pc.dm.theta);
        let fp6 = -(load.wrench(&pose.compose(&pr.embed(&g))) * scale);
        let fp = pl_.gather(&fp6);
        let mut dq = lambda3(&fp) * t;
        if load.frame == LoadFrame::World {
            let y = pl_.block(&dead_load_map(&-fp6));
            let yt_ = y * t;
            s.dq_diag += t.tr_mul(&yt_);
            dq += yt_;
            let ya = y * a;
            s.yt += a.tr_mul(&ya);
            s.ry += t.tr_mul(&ya);
        }
        s.dq_w += a.tr_mul(&dq);
        s.tsum += t.tr_mul(&fp);
        s.wsum += a.tr_mul(&fp);
        for i in 0..4 {
            s.phi[i] += fp * co.d[i];
            s.chi[i] += fp * co.c[i];
        }
    }
    w.tin_b = Vec3::from_fn(|i, _| if i < pl_.k { s.tin[pl_.sel[i]] } else { 0.0 });
}

/// The outward sweep of [`super::chain::outward`] on a planar rod (D97):
/// every piece's own points and tip linearized on `P`, kept in the
/// planar buffers (D107). The rod must be planar and the model without a
/// tree; its closes are [`super::planar_close::inward`]. Kept out of line:
/// inlined into [`super::chain::outward`] it would grow the six-strain
/// sweep's caller.
#[inline(never)]
pub(crate) fn outward(
    model: &Model,
    rm: &RodModel,
    pr: &PlanarRod,
    works: &mut [PlanarWork],
    at: &At,
) {
    let (q, qd, qdd) = (at.q, at.qd, at.qdd);
    let scale = at.forces.load_scale;
    let rod = &rm.spec.geometry;
    let range = rm.dofs();
    let (qr, qdr, qddr) = (&q[range.clone()], &qd[range.clone()], &qdd[range]);
    // The world pose of the piece's base (world loads), and its pose
    // relative to the rod's base (the pairing quantities' axes, D107).
    let mut pose = *rod.base();
    let mut rel = Pose2::IDENTITY;
    let mut eta0 = Vec3::zeros();
    let mut etad0 = pr.gather(&gravity_base_acceleration(model, rm, scale));
    let drag = drag_diagonal(rm).map(|d| pr.gather(&d));
    let pieces = rod.pieces().iter().zip(&rm.pieces).zip(&pr.pieces);
    for (((piece, pd), pp), w) in pieces.zip(works.iter_mut()) {
        let xi = pr.gather(&piece.strain(qr));
        let xid = pr.gather(&piece.strain_rate(qdr));
        let xidd = pr.gather(&piece.strain_rate(qddr));
        let dm = PlanarDerivMaps::new(&xi, &xid, &xidd);
        let pc = PlanarLin {
            dm: &dm,
            xi: &xi,
            xid: &xid,
            xidd: &xidd,
            eta0: &eta0,
            etad0: &etad0,
        };
        own_points3(
            rm,
            pr,
            pd,
            pp,
            &pc,
            &pose,
            drag.as_ref(),
            scale,
            !at.dense,
            w,
        );
        let (g, p) = linearize_point3(&pc, piece.length);
        let place = Place {
            idx: pr.idx,
            sel: pp.sel,
            k: pp.k,
        };
        w.tip = g;
        w.base_rel = rel;
        rel = rel.compose(&g);
        w.tip_rel = rel;
        w.tm_tip = p.t;
        w.eta_tip = p.eta;
        w.etad_tip = p.etad;
        w.h_eta = place.right(&p.h_eta);
        w.h_etad = place.right(&p.h_etad);
        w.h_vd = place.right(&p.h_vd);
        w.co_tip = p.co;
        w.powers = dm.p;
        w.kbar = dm.kbar();
        eta0 = p.eta;
        etad0 = p.etad;
        pose = pose.compose(&pr.embed(&g));
    }
}

/// The three bending planes' directions in a twist (`ky, qx, qz` and its
/// two rotations), and a 3-vector or 3×3 block placed at or taken from them:
/// what the planar tests compare against the six-direction path with.
#[cfg(test)]
pub(crate) mod plane_blocks {
    use softrod_lie::{Mat3, Mat6, Vec3, Vec6};

    pub(crate) const IDX: [[usize; 3]; 3] = [[0, 4, 5], [1, 5, 3], [2, 3, 4]];

    pub(crate) fn scatter(idx: &[usize; 3], v: &Vec3) -> Vec6 {
        let mut out = Vec6::zeros();
        for r in 0..3 {
            out[idx[r]] = v[r];
        }
        out
    }

    pub(crate) fn block(idx: &[usize; 3], m: &Mat6) -> Mat3 {
        Mat3::from_fn(|r, c| m[(idx[r], idx[c])])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::piece_derivs::{PieceDerivMaps, lambda};
    use softrod_lie::{ad, coad};

    use super::plane_blocks::{IDX, block, scatter};

    /// The `P` operators are the `P` blocks of the six-direction ones, and
    /// those are block diagonal on `P ⊕ P⊥` for `P` arguments (D95), for
    /// the three bending planes.
    #[test]
    fn operators_are_the_p_blocks() {
        let v = Vec3::new(0.7, -1.3, 0.4);
        for idx in &IDX {
            let v6 = scatter(idx, &v);
            for (got, full) in [
                (ad3(&v), ad(&v6)),
                (coad3(&v), coad(&v6)),
                (lambda3(&v), lambda(&v6)),
            ] {
                assert_eq!(got, block(idx, &full));
                // No coupling between P and P⊥.
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

    /// The maps of D96 against the six-direction ones (D32–D35) on `P`:
    /// equal to round-off, curvatures zero, small, moderate and large
    /// (both branches of the coefficients).
    #[test]
    fn planar_maps_are_the_p_blocks_of_the_six_direction_maps() {
        let xd = Vec3::new(0.3, -0.5, 0.9);
        let xdd = Vec3::new(0.2, 0.7, -0.6);
        for idx in &IDX {
            for kappa in [0.0, 1e-9, 1e-3, 0.8, 6.0, 40.0] {
                let xi = Vec3::new(kappa, 1.05, 0.2);
                let dm = PlanarDerivMaps::new(&xi, &xd, &xdd);
                let (xi6, xd6, xdd6) = (scatter(idx, &xi), scatter(idx, &xd), scatter(idx, &xdd));
                let d6 = PieceDerivMaps::new(&xi6, &xd6, &xdd6);
                assert_eq!(dm.theta, d6.theta);
                for x in [0.0, 0.05, 0.4, 1.0] {
                    let co = Coefficients::at(x, dm.theta);
                    for (got, full) in [
                        (
                            dm.d_tangent_applied(&co, false),
                            d6.d_tangent_applied(&co, false),
                        ),
                        (
                            dm.d_tangent_applied(&co, true),
                            d6.d_tangent_applied(&co, true),
                        ),
                        (dm.tangent_rate(&co), d6.tangent_rate(&co)),
                        (
                            dm.bias_strain_derivative(&co),
                            d6.bias_strain_derivative(&co),
                        ),
                    ] {
                        let want = block(idx, &full);
                        let err = (got - want).amax();
                        assert!(
                            err <= 1e-12 * want.amax().max(1e-300),
                            "{idx:?}, κ {kappa}, x {x}: {err:e} of {}",
                            want.amax()
                        );
                    }
                    for i in 0..4 {
                        assert!((dm.p[i] - block(idx, &d6.p[i])).amax() <= 1e-12 * d6.p[i].amax());
                    }
                    assert_eq!(scatter(idx, &dm.kbar()), d6.kbar());
                }
            }
        }
    }
}
