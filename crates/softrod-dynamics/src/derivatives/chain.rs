//! The derivative sweeps on a chain of rods clamped to the world
//! (docs/theory-derivatives.md §2–§4, D37–D47): one outward sweep
//! linearizes every point in its own piece's strain, one inward sweep
//! closes the pieces, and the off-diagonal blocks pair per-piece
//! world-frame quantities.

use super::piece::{PieceWork, Subtree, close_mass, close_piece, write_piece};
use super::point::{PieceLin, basis6, linearize_point, own_points};
use super::{At, IdDerivatives};
use crate::forces::external::gravity_base_acceleration;
use crate::forces::linearized::{drag_diagonal, has_dead_loads};
use crate::kernels::mat6::{Cols, mm, tm};
use crate::kernels::piece_derivs::PieceDerivMaps;
use crate::model::{Model, RodModel};
use softrod_lie::{PieceMaps, Vec6};

/// The outward sweep (D39–D43) of a rod that is not on the planar path
/// (those: [`super::planar::outward`]): velocities, accelerations, force
/// densities and their linearizations at every point; own-point sums.
#[inline(always)]
pub(crate) fn outward(model: &Model, rm: &RodModel, works: &mut [PieceWork], at: &At) {
    let (q, qd, qdd) = (at.q, at.qd, at.qdd);
    let scale = at.forces.load_scale;
    let rod = &rm.spec.geometry;
    let range = rm.dofs();
    let (qr, qdr, qddr) = (&q[range.clone()], &qd[range.clone()], &qdd[range]);
    let mut pose = *rod.base();
    let mut eta0 = Vec6::zeros();
    let mut etad0 = gravity_base_acceleration(model, rm, scale);
    let drag = drag_diagonal(rm);
    for ((piece, pd), w) in rod.pieces().iter().zip(&rm.pieces).zip(works.iter_mut()) {
        let xi = piece.strain(qr);
        let xid = piece.strain_rate(qdr);
        let xidd = piece.strain_rate(qddr);
        let maps = PieceMaps::new(&xi, Some(&xid));
        let dm = PieceDerivMaps::new(&xi, &xid, &xidd);
        w.reset_sums();
        w.base_world = pose;
        let cols = Cols::of(&basis6(&piece.basis));
        let pc = PieceLin {
            maps: &maps,
            dm: &dm,
            eta0: &eta0,
            etad0: &etad0,
            xid: &xid,
            xidd: &xidd,
            cols: &cols,
        };
        own_points(rm, pd, &pc, &pose, drag.as_ref(), scale, !at.dense, w);
        let (g, p) = linearize_point(&pc, piece.length);
        w.set_tip(g, &p, &dm);
        eta0 = p.eta;
        etad0 = p.etad;
        pose = w.tip_world;
    }
}

/// The inward sweep (D43–D46): composites, each piece's diagonal block,
/// `τ`, and the world-frame pairing quantities.
pub(crate) fn inward(model: &Model, rm: &RodModel, work: &mut IdDerivatives, r: usize, at: &At) {
    // Dead loads only: the 𝒴 composites and receivers are zero otherwise.
    let dead = has_dead_loads(rm);
    let mut sub = Subtree::zero();
    for (n, piece) in rm.spec.geometry.pieces().iter().enumerate().rev() {
        let bm = basis6(&piece.basis);
        let (diag_q, diag_v, wrench, base) = close_piece(&mut work.pieces[r][n], &sub, &bm, dead);
        if !at.dense {
            close_mass(&mut work.pieces[r][n], &sub.m, &bm);
        }
        sub = base;
        let (bq, bv) = write_piece(model, rm, n, work, at, &bm, (&diag_q, &diag_v, &wrench));
        let w = &mut work.pieces[r][n];
        w.blk_q = bq;
        w.blk_v = bv;
    }
}

/// The off-diagonal blocks (D45–D46): `i < j` pairs the world tip column
/// `Ad_{G_i}S_i(ℓ)` with the change of the transmitted wrench of piece `j`;
/// `i > j` pairs the receivers of piece `i` with the tip sources of `j`.
pub(crate) fn pairs(rm: &RodModel, work: &mut IdDerivatives, r: usize) {
    let pieces = rm.spec.geometry.pieces();
    let dead = has_dead_loads(rm);
    let ws = &work.pieces[r];
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
            let (bq, bv) = if i < j {
                (
                    tm(&wi.s_world, &wj.dwq_world),
                    tm(&wi.s_world, &wj.dwv_world),
                )
            } else {
                (
                    if dead {
                        mm(&wi.rcv_m, &wj.src_wq)
                            + mm(&wi.rcv_b, &wj.src_uq)
                            + mm(&wi.rcv_y, &wj.s_world)
                    } else {
                        mm(&wi.rcv_m, &wj.src_wq) + mm(&wi.rcv_b, &wj.src_uq)
                    },
                    mm(&wi.rcv_m, &wj.src_wv) + mm(&wi.rcv_b, &wj.src_uv),
                )
            };
            let ld = work.dtau_dq.nrows();
            let (sq, sv) = (work.dtau_dq.as_mut_slice(), work.dtau_dqd.as_mut_slice());
            for c in 0..kj {
                let col = (oj + c) * ld + oi;
                // Element loops, not `copy_from_slice`: a `memcpy` call per
                // column of at most six entries costs more than the copy.
                for (d, v) in sq[col..col + ki].iter_mut().zip(&bq.as_slice()[6 * c..]) {
                    *d = *v;
                }
                for (d, v) in sv[col..col + ki].iter_mut().zip(&bv.as_slice()[6 * c..]) {
                    *d = *v;
                }
            }
        }
    }
}
