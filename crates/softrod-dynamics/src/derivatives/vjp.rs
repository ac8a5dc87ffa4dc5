//! O(N) vector–Jacobian products of the inverse dynamics
//! (docs/theory-derivatives.md §8, D81–D83): `uᵀ ∂τ/∂q` and `uᵀ ∂τ/∂q̇`
//! from what the derivative sweeps keep per piece, without the dense
//! matrices.
//!
//! Every off-diagonal block of `∂τ/∂q` is a product of a quantity of the
//! row's piece and one of the column's (D45–D46, D80), both in the world
//! frame: the proximal block `∂τ_i/∂q_j = (Ad S_i)ᵀ δW_j` (`i` on the path
//! of `j` to the root) and the distal block `∂τ_j/∂q_i = ℛ_j [w̄, u, Δ]_i`.
//! Contracted with `u`, each sum over rows splits into a sum over the
//! row pieces that does not depend on the column piece: a prefix sum of
//! the twists `Ad S_i u_i` down the path from the root (D82) and a suffix
//! sum of the wrenches `ℛ_jᵀ u_j` over the subtree (D83). One pass in each
//! direction, O(N) with 6×6 products, equal to `uᵀ` times the dense
//! matrices of [`crate::inverse_dynamics_derivatives`] to round-off (the
//! same quantities summed in another order).

use super::IdDerivatives;
use super::piece::PieceWork;
use super::tree::{Exit, TreeWork};
use crate::algorithms::check_vec;
use crate::error::DynamicsError;
use crate::forces::linearized::has_dead_loads;
use crate::model::tree::Tree;
use crate::model::{Model, RodModel};
use softrod_lie::Vec6;

/// `u`'s coordinates `o .. o + k` as a zero-padded 6-vector.
#[inline(always)]
fn local(u: &[f64], o: usize, k: usize) -> Vec6 {
    let mut x = Vec6::zeros();
    for c in 0..k {
        x[c] = u[o + c];
    }
    x
}

/// Adds the leading `k` entries of `x` to `out[o .. o + k]`.
#[inline(always)]
fn add_local(out: &mut [f64], o: usize, k: usize, x: &Vec6) {
    for c in 0..k {
        out[o + c] += x[c];
    }
}

/// `uᵀ ∂τ/∂q` into `out_q` and `uᵀ ∂τ/∂q̇` into `out_qd` (all dim
/// `n_dof`; `out_q[j] = Σᵢ uᵢ ∂τᵢ/∂q_j`) at the point of the last
/// successful [`crate::inverse_dynamics_linearization_with`] or
/// [`crate::inverse_dynamics_derivatives_with`] on `work`
/// (docs/theory-derivatives.md D81–D83). O(N), no allocation; the
/// linearization is kept, so products with several `u` cost one
/// evaluation. `(∂τ/∂q̈)ᵀu = M u` is not among them.
///
/// Errors: `u` or an output of the wrong length, `u` not finite, no
/// linearization evaluated ([`DynamicsError::NotLinearized`]), a product
/// that is not finite.
pub fn inverse_dynamics_vjp(
    model: &Model,
    work: &mut IdDerivatives,
    u: &[f64],
    out_q: &mut [f64],
    out_qd: &mut [f64],
) -> Result<(), DynamicsError> {
    let nodes = model.tree.as_ref().map(|t| t.nodes.len());
    if work.n_dof != model.n_dof()
        || work.pieces.len() != model.rods().len()
        || work.tree.as_ref().map(|t| t.n_nodes()) != nodes
    {
        return Err(DynamicsError::WorkspaceMismatch {
            what: "IdDerivatives",
            built: work.n_dof,
            got: model.n_dof(),
        });
    }
    if !work.linearized {
        return Err(DynamicsError::NotLinearized {
            what: "inverse_dynamics_vjp",
        });
    }
    check_vec(model, "u", u)?;
    for (what, o) in [("out_q", out_q.len()), ("out_qd", out_qd.len())] {
        if o != model.n_dof() {
            return Err(DynamicsError::SizeMismatch {
                what,
                got: o,
                expected: model.n_dof(),
            });
        }
    }
    out_q.fill(0.0);
    out_qd.fill(0.0);
    match (&model.tree, work.tree.as_deref_mut()) {
        (Some(tree), Some(tw)) => tree_vjp(tree, tw, u, out_q, out_qd),
        _ => {
            for (r, rm) in model.rods().iter().enumerate() {
                chain_vjp(rm, &work.pieces[r], u, out_q, out_qd);
            }
        }
    }
    for (what, out) in [("u^T dtau/dq", &*out_q), ("u^T dtau/dqdot", &*out_qd)] {
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            return Err(DynamicsError::NotFinite {
                what: format!("{what} entry {i}"),
                value: out[i],
            });
        }
    }
    Ok(())
}

/// The products on one rod of a chain (pieces `0 … N−1` base to tip):
/// the diagonal blocks, the prefix sum `a_j = Σ_{i<j} Ad S_i u_i` against
/// the columns `δW_j` (D82), the suffix sums `Σ_{i>j} ℛᵢᵀ u_i` against the
/// sources `[w̄, u, Δ]_j` (D83).
fn chain_vjp(rm: &RodModel, ws: &[PieceWork], u: &[f64], out_q: &mut [f64], out_qd: &mut [f64]) {
    let pieces = rm.spec.geometry.pieces();
    let dead = has_dead_loads(rm);
    // Outward: the diagonal blocks and the proximal pairings.
    let mut a = Vec6::zeros();
    for (p, w) in pieces.iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let uj = local(u, o, k);
        let vq = w.blk_q.tr_mul(&uj) + w.dwq_world.tr_mul(&a);
        let vv = w.blk_v.tr_mul(&uj) + w.dwv_world.tr_mul(&a);
        add_local(out_q, o, k, &vq);
        add_local(out_qd, o, k, &vv);
        a += w.s_world * uj;
    }
    // Inward: the distal pairings.
    let (mut bm, mut bb, mut by) = (Vec6::zeros(), Vec6::zeros(), Vec6::zeros());
    for (p, w) in pieces.iter().zip(ws).rev() {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let mut vq = w.src_wq.tr_mul(&bm) + w.src_uq.tr_mul(&bb);
        if dead {
            vq += w.s_world.tr_mul(&by);
        }
        let vv = w.src_wv.tr_mul(&bm) + w.src_uv.tr_mul(&bb);
        add_local(out_q, o, k, &vq);
        add_local(out_qd, o, k, &vv);
        let uj = local(u, o, k);
        bm += w.rcv_m.tr_mul(&uj);
        bb += w.rcv_b.tr_mul(&uj);
        if dead {
            by += w.rcv_y.tr_mul(&uj);
        }
    }
}

/// The exit of node `p` towards its child `c` (D80): the section of an
/// inside attachment, or `p`'s tip.
#[inline(always)]
fn exit_towards(tree: &Tree, tw: &TreeWork, p: usize, c: usize) -> Exit {
    if tree.nodes[c].attach.is_some() {
        tw.exit[c]
    } else {
        let w = &tw.nodes[p];
        Exit {
            s: w.s_world,
            wq: w.src_wq,
            uq: w.src_uq,
            wv: w.src_wv,
        }
    }
}

/// The products on a tree (D81–D83 on the paths to the root, D80): nodes
/// are numbered parents first, so one pass forward carries the prefix sums
/// `Σ Ad S_exit u` of the ancestors to each node and one pass backward the
/// subtree sums of `ℛᵀu`, each handed to the parent through the exit its
/// child's branch leaves it by. Nodes without coordinates (bodies, fixed
/// and prescribed joints) pass the sums on.
fn tree_vjp(tree: &Tree, tw: &mut TreeWork, u: &[f64], out_q: &mut [f64], out_qd: &mut [f64]) {
    let dead = tw.dead;
    for (i, node) in tree.nodes.iter().enumerate() {
        let up = match node.parent {
            None => Vec6::zeros(),
            Some(p) => {
                let pn = &tree.nodes[p];
                let mut a = tw.up[p];
                if pn.k > 0 {
                    let ex = exit_towards(tree, tw, p, i);
                    a += ex.s * local(u, pn.dof, pn.k);
                }
                a
            }
        };
        tw.up[i] = up;
        if node.k > 0 {
            let w = &tw.nodes[i];
            let ui = local(u, node.dof, node.k);
            let vq = w.blk_q.tr_mul(&ui) + w.dwq_world.tr_mul(&up);
            let vv = w.blk_v.tr_mul(&ui) + w.dwv_world.tr_mul(&up);
            add_local(out_q, node.dof, node.k, &vq);
            add_local(out_qd, node.dof, node.k, &vv);
        }
    }
    for d in tw.down.iter_mut() {
        *d = [Vec6::zeros(); 3];
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        // `down[i]` holds its children's sums; add its own receivers.
        if node.k > 0 {
            let w = &tw.nodes[i];
            let ui = local(u, node.dof, node.k);
            let d = &mut tw.down[i];
            d[0] += w.rcv_m.tr_mul(&ui);
            d[1] += w.rcv_b.tr_mul(&ui);
            if dead {
                d[2] += w.rcv_y.tr_mul(&ui);
            }
        }
        let Some(p) = node.parent else { continue };
        let [sm, sb, sy] = tw.down[i];
        let pn = &tree.nodes[p];
        if pn.k > 0 {
            let ex = exit_towards(tree, tw, p, i);
            let mut vq = ex.wq.tr_mul(&sm) + ex.uq.tr_mul(&sb);
            if dead {
                vq += ex.s.tr_mul(&sy);
            }
            let vv = ex.wv.tr_mul(&sm) + ex.s.tr_mul(&sb);
            add_local(out_q, pn.dof, pn.k, &vq);
            add_local(out_qd, pn.dof, pn.k, &vv);
        }
        let d = &mut tw.down[p];
        d[0] += sm;
        d[1] += sb;
        d[2] += sy;
    }
}
