//! The off-diagonal pairings and the O(N) products of a planar rod
//! (docs/theory-derivatives.md D107): those of [`super::chain::pairs`]
//! and [`super::vjp`] (D45–D46, D81–D86) on the planar buffers
//! ([`PlanarWork`]), whose pairing quantities are 3×k blocks in the axes
//! of the rod's base frame. The prefix and suffix sums are 3-vectors of
//! `P` in those axes; every pairing contracts a twist with a wrench of the
//! same rod, so the products are those of the world-frame quantities of
//! the six-direction sweeps, to round-off.

use super::IdDerivatives;
use super::planar::PlanarWork;
use crate::forces::linearized::has_dead_loads;
use crate::model::RodModel;
use softrod_lie::{Mat3, Vec3};

/// `x`'s coordinates `o .. o + k` (k ≤ 3) as a zero-padded 3-vector.
#[inline(always)]
fn local3(x: &[f64], o: usize, k: usize) -> Vec3 {
    Vec3::from_fn(|i, _| if i < k { x[o + i] } else { 0.0 })
}

/// Adds the leading `k` entries of `v` to `out[o .. o + k]`.
#[inline(always)]
fn add3(out: &mut [f64], o: usize, k: usize, v: &Vec3) {
    for i in 0..k {
        out[o + i] += v[i];
    }
}

/// The off-diagonal blocks of one planar rod into the dense `∂τ/∂q`,
/// `∂τ/∂q̇` (D45–D46): `i < j` pairs `Ad S_i` with `δW_j`, `i > j` the
/// receivers of `i` with the sources of `j`.
// Out of line for the same reason as `planar::outward`: inlined into
// `open_tree_core` it would grow the six-strain path's caller.
#[inline(never)]
pub(crate) fn pairs(rm: &RodModel, work: &mut IdDerivatives, r: usize) {
    let pieces = rm.spec.geometry.pieces();
    let dead = has_dead_loads(rm);
    let ws = &work.planar[r];
    for (j, pj) in pieces.iter().enumerate() {
        let kj = pj.basis.dof();
        let oj = rm.dof_offset + pj.dof_offset;
        let wj = &ws[j];
        for (i, pi) in pieces.iter().enumerate() {
            if i == j {
                continue;
            }
            let ki = pi.basis.dof();
            let oi = rm.dof_offset + pi.dof_offset;
            let wi = &ws[i];
            let (bq, bv): (Mat3, Mat3) = if i < j {
                (wi.s_rod.tr_mul(&wj.dwq), wi.s_rod.tr_mul(&wj.dwv))
            } else {
                let mut bq = wi.rcv_m * wj.src_wq + wi.rcv_b * wj.src_uq;
                if dead {
                    bq += wi.rcv_y * wj.s_rod;
                }
                (bq, wi.rcv_m * wj.src_wv + wi.rcv_b * wj.s_rod)
            };
            for c in 0..kj {
                for rr in 0..ki {
                    work.dtau_dq[(oi + rr, oj + c)] = bq[(rr, c)];
                    work.dtau_dqd[(oi + rr, oj + c)] = bv[(rr, c)];
                }
            }
        }
    }
}

/// `uᵀ∂τ/∂q`, `uᵀ∂τ/∂q̇` of one planar rod, added to `out_q`, `out_qd`
/// (as [`super::vjp`]'s chain products, D82–D83).
pub(crate) fn vjp(
    rm: &RodModel,
    ws: &[PlanarWork],
    u: &[f64],
    out_q: &mut [f64],
    out_qd: &mut [f64],
) {
    let pieces = rm.spec.geometry.pieces();
    let dead = has_dead_loads(rm);
    let mut a = Vec3::zeros();
    for (p, w) in pieces.iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let uj = local3(u, o, k);
        add3(out_q, o, k, &(w.blk_q.tr_mul(&uj) + w.dwq.tr_mul(&a)));
        add3(out_qd, o, k, &(w.blk_v.tr_mul(&uj) + w.dwv.tr_mul(&a)));
        a += w.s_rod * uj;
    }
    let (mut bm, mut bb, mut by) = (Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
    for (p, w) in pieces.iter().zip(ws).rev() {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let uj = local3(u, o, k);
        let mut vq = w.src_wq.tr_mul(&bm) + w.src_uq.tr_mul(&bb);
        if dead {
            vq += w.s_rod.tr_mul(&by);
            by += w.rcv_y.tr_mul(&uj);
        }
        add3(out_q, o, k, &vq);
        add3(out_qd, o, k, &(w.src_wv.tr_mul(&bm) + w.s_rod.tr_mul(&bb)));
        bm += w.rcv_m.tr_mul(&uj);
        bb += w.rcv_b.tr_mul(&uj);
    }
}

/// `∂τ/∂q · a + ∂τ/∂q̇ · b` of one planar rod, added to `out` (D84).
pub(crate) fn jvp(rm: &RodModel, ws: &[PlanarWork], a: &[f64], b: &[f64], out: &mut [f64]) {
    let pieces = rm.spec.geometry.pieces();
    let dead = has_dead_loads(rm);
    let (mut sm, mut sb, mut sy) = (Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
    for (p, w) in pieces.iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let (aj, bj) = (local3(a, o, k), local3(b, o, k));
        let mut v = w.blk_q * aj + w.blk_v * bj + w.rcv_m * sm + w.rcv_b * sb;
        if dead {
            v += w.rcv_y * sy;
            sy += w.s_rod * aj;
        }
        add3(out, o, k, &v);
        sm += w.src_wq * aj + w.src_wv * bj;
        sb += w.src_uq * aj + w.s_rod * bj;
    }
    let mut d = Vec3::zeros();
    for (p, w) in pieces.iter().zip(ws).rev() {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        add3(out, o, k, &w.s_rod.tr_mul(&d));
        d += w.dwq * local3(a, o, k) + w.dwv * local3(b, o, k);
    }
}

/// `M v` of one planar rod, added to `out` (D86).
pub(crate) fn mass(rm: &RodModel, ws: &[PlanarWork], v: &[f64], out: &mut [f64]) {
    let pieces = rm.spec.geometry.pieces();
    let mut a = Vec3::zeros();
    for (p, w) in pieces.iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let vj = local3(v, o, k);
        add3(out, o, k, &(w.blk_a * vj + w.rcv_m * a));
        a += w.s_rod * vj;
    }
    let mut d = Vec3::zeros();
    for (p, w) in pieces.iter().zip(ws).rev() {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        add3(out, o, k, &w.s_rod.tr_mul(&d));
        d += w.rcv_m.tr_mul(&local3(v, o, k));
    }
}

/// `zᵀ∂τ/∂s` of one planar rod's inertia (D85): the virtual power of its
/// points' inertial wrenches in the twists `J z`.
pub(crate) fn inertia(rm: &RodModel, ws: &[PlanarWork], z: &[f64]) -> f64 {
    let mut a = Vec3::zeros();
    let mut out = 0.0;
    for (p, w) in rm.spec.geometry.pieces().iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let zj = local3(z, o, k);
        out += w.base_rel.ad_inv_vec(&a).dot(&w.s.win) + zj.dot(&w.tin_b);
        a += w.s_rod * zj;
    }
    out
}
