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
use super::planar_products;
use super::point::basis6;
use super::tree::{Exit, TreeWork};
use crate::algorithms::check_vec;
use crate::error::DynamicsError;
use crate::forces::linearized::has_dead_loads;
use crate::kernels::chol::with_k;
use crate::model::tree::{NodeKind, Tree};
use crate::model::{Model, RodModel};
use softrod_lie::{Mat6, Vec6, coad};

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

/// `out[c] = Σ_{r<R} A[r, c] x[r]` for `c < C`, the rest zero: `Aᵀx` for
/// an `A` whose rows from `R` on or `x`'s entries from `R` on are zero and
/// of which only the first `C` outputs are read (D101: a piece's
/// quantities live in its basis's `k` columns or rows). The sizes are
/// compile-time constants so the loops unroll.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops over compile-time sizes, as kernels/mat6.rs
fn trk<const R: usize, const C: usize>(m: &Mat6, x: &Vec6) -> Vec6 {
    let (a, x) = (m.as_slice(), x.as_slice());
    let mut out = Vec6::zeros();
    if R == 0 {
        return out;
    }
    for c in 0..C {
        let col = &a[6 * c..6 * c + R];
        let mut s = col[0] * x[0];
        for r in 1..R {
            s += col[r] * x[r];
        }
        out[c] = s;
    }
    out
}

/// `out[r] = Σ_{c<C} A[r, c] x[c]` for `r < R`, the rest zero: `A x` for an
/// `A` whose columns from `C` on or `x`'s entries from `C` on are zero and
/// of which only the first `R` outputs are read (D101).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // index loops over compile-time sizes, as kernels/mat6.rs
fn mk<const R: usize, const C: usize>(m: &Mat6, x: &Vec6) -> Vec6 {
    let (a, x) = (m.as_slice(), x.as_slice());
    let mut out = Vec6::zeros();
    if C == 0 {
        return out;
    }
    let o = out.as_mut_slice();
    for r in 0..R {
        o[r] = a[r] * x[0];
    }
    for c in 1..C {
        for r in 0..R {
            o[r] += a[6 * c + r] * x[c];
        }
    }
    out
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
    check_work(model, work, "inverse_dynamics_vjp")?;
    check_vec(model, "u", u)?;
    check_len(model, "out_q", out_q.len())?;
    check_len(model, "out_qd", out_qd.len())?;
    out_q.fill(0.0);
    out_qd.fill(0.0);
    match (&model.tree, work.tree.as_deref_mut()) {
        (Some(tree), Some(tw)) => tree_vjp(tree, tw, u, out_q, out_qd),
        _ => {
            for (r, rm) in model.rods().iter().enumerate() {
                if work.planar_taken[r] {
                    planar_products::vjp(rm, &work.planar[r], u, out_q, out_qd);
                } else {
                    chain_vjp(rm, &work.pieces[r], u, out_q, out_qd);
                }
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

/// `∂τ/∂q · a + ∂τ/∂q̇ · b` into `out` (all dim `n_dof`) at the point of
/// the last successful linearization on `work`, the forward (column)
/// products of the same quantities as [`inverse_dynamics_vjp`]: the sums
/// run the other way along the paths (D84). O(N), no allocation. Errors as
/// [`inverse_dynamics_vjp`].
pub fn inverse_dynamics_jvp(
    model: &Model,
    work: &mut IdDerivatives,
    a: &[f64],
    b: &[f64],
    out: &mut [f64],
) -> Result<(), DynamicsError> {
    check_work(model, work, "inverse_dynamics_jvp")?;
    check_vec(model, "a", a)?;
    check_vec(model, "b", b)?;
    check_len(model, "out", out.len())?;
    out.fill(0.0);
    match (&model.tree, work.tree.as_deref_mut()) {
        (Some(tree), Some(tw)) => tree_jvp(tree, tw, a, b, out),
        _ => {
            for (r, rm) in model.rods().iter().enumerate() {
                if work.planar_taken[r] {
                    planar_products::jvp(rm, &work.planar[r], a, b, out);
                } else {
                    chain_jvp(rm, &work.pieces[r], a, b, out);
                }
            }
        }
    }
    if let Some(i) = out.iter().position(|v| !v.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!("dtau/dq a + dtau/dqdot b entry {i}"),
            value: out[i],
        });
    }
    Ok(())
}

/// The inertia products (docs/theory-derivatives.md D85) at the point of
/// the last successful linearization on `work`: for every rod `r`,
/// `rods[r] = zᵀ ∂τ/∂s_r`, the derivative of `τ(q, q̇, q̈)` by a factor
/// `s_r` on the screw inertia of all of rod `r`'s points (at `s_r = 1`;
/// `τ` is linear in it, so `zᵀ∂τ/∂ρ_r = rods[r]/ρ_r` for its density
/// `ρ_r`); for every body `b`, the 6×6 `bodies[b] = G_b` with
/// `zᵀ ∂τ/∂𝓜_b [δ𝓜] = Σᵢⱼ G_b,ij δ𝓜ᵢⱼ` for a change `δ𝓜` of its screw
/// inertia at its frame. Each is the virtual power of the inertial wrenches
/// in the twists `J z` (`zᵀτ = Σ_points (J z)ᵀ f`): one outward pass of the
/// prefix sums of [`inverse_dynamics_vjp`] against the sums the
/// linearization kept, O(N), no allocation. Overwrites `rods`, `bodies`.
///
/// Errors: `z` of the wrong length or not finite, `rods` or `bodies` of the
/// wrong length, no linearization evaluated, a product that is not finite.
pub fn inverse_dynamics_inertia_vjp(
    model: &Model,
    work: &mut IdDerivatives,
    z: &[f64],
    rods: &mut [f64],
    bodies: &mut [Mat6],
) -> Result<(), DynamicsError> {
    check_work(model, work, "inverse_dynamics_inertia_vjp")?;
    check_vec(model, "z", z)?;
    for (what, got, expected) in [
        ("rods", rods.len(), model.rods().len()),
        ("bodies", bodies.len(), model.bodies().len()),
    ] {
        if got != expected {
            return Err(DynamicsError::SizeMismatch {
                what,
                got,
                expected,
            });
        }
    }
    rods.fill(0.0);
    bodies.fill(Mat6::zeros());
    match (&model.tree, work.tree.as_deref_mut()) {
        (Some(tree), Some(tw)) => tree_inertia(model, tree, tw, z, rods, bodies),
        _ => {
            for (r, rm) in model.rods().iter().enumerate() {
                if work.planar_taken[r] {
                    rods[r] = planar_products::inertia(rm, &work.planar[r], z);
                    continue;
                }
                let mut a = Vec6::zeros();
                for (p, w) in rm.spec.geometry.pieces().iter().zip(&work.pieces[r]) {
                    let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
                    let zj = local(z, o, k);
                    rods[r] += piece_power(w, &basis6(&p.basis), &zj, &a);
                    a += w.s_world * zj;
                }
            }
        }
    }
    let bad = rods
        .iter()
        .position(|v| !v.is_finite())
        .map(|i| (format!("z^T dtau/ds of rod {i}"), rods[i]))
        .or_else(|| {
            bodies.iter().enumerate().find_map(|(b, g)| {
                g.iter()
                    .find(|v| !v.is_finite())
                    .map(|v| (format!("z^T dtau/dM of body {b}"), *v))
            })
        });
    match bad {
        Some((what, value)) => Err(DynamicsError::NotFinite { what, value }),
        None => Ok(()),
    }
}

/// `M(q) v` into `out` (dim `n_dof`; `M = ∂τ/∂q̈`, [`crate::mass_matrix`])
/// at the point of the last successful
/// [`crate::inverse_dynamics_linearization_with`] on `work`
/// (docs/theory-derivatives.md D86): the diagonal blocks that linearization
/// kept, the receivers `ℛ^𝓜` of each piece against the prefix sum of the
/// world twists `Ad S v` of the pieces before it (the distal blocks
/// `M_ji = ℛ^𝓜_j Ad S_i`), and by the symmetry of `M` the suffix sums of
/// `ℛ^𝓜ᵀ v` against `Ad S` (the proximal blocks). O(N), no allocation, no
/// `n_dof × n_dof` matrix; equal to [`crate::mass_matrix`] times `v` to
/// round-off.
///
/// Errors: `v` or `out` of the wrong length, `v` not finite, no
/// linearization without the dense matrices evaluated on `work` (the dense
/// [`crate::inverse_dynamics_derivatives_with`] does not keep `M`'s
/// blocks: [`DynamicsError::NotLinearized`]), a product that is not finite.
pub fn inverse_dynamics_mass_product(
    model: &Model,
    work: &mut IdDerivatives,
    v: &[f64],
    out: &mut [f64],
) -> Result<(), DynamicsError> {
    check_work(model, work, "inverse_dynamics_mass_product")?;
    if !work.mass_kept {
        return Err(DynamicsError::NotLinearized {
            what: "inverse_dynamics_mass_product (after a dense linearization)",
        });
    }
    check_vec(model, "v", v)?;
    check_len(model, "out", out.len())?;
    out.fill(0.0);
    match (&model.tree, work.tree.as_deref_mut()) {
        (Some(tree), Some(tw)) => tree_mass(tree, tw, v, out),
        _ => {
            for (r, rm) in model.rods().iter().enumerate() {
                if work.planar_taken[r] {
                    planar_products::mass(rm, &work.planar[r], v, out);
                } else {
                    chain_mass(rm, &work.pieces[r], v, out);
                }
            }
        }
    }
    if let Some(i) = out.iter().position(|x| !x.is_finite()) {
        return Err(DynamicsError::NotFinite {
            what: format!("M v entry {i}"),
            value: out[i],
        });
    }
    Ok(())
}

/// A piece of [`chain_mass`]'s outward pass in its `K` directions.
#[inline(always)]
fn mass_outward<const K: usize>(w: &PieceWork, vj: &Vec6, a: &mut Vec6) -> Vec6 {
    let out = mk::<K, K>(&w.blk_a, vj) + mk::<K, 6>(&w.rcv_m, a);
    *a += mk::<6, K>(&w.s_world, vj);
    out
}

/// A piece of [`chain_mass`]'s inward pass in its `K` directions.
#[inline(always)]
fn mass_inward<const K: usize>(w: &PieceWork, vj: &Vec6, d: &mut Vec6) -> Vec6 {
    let out = trk::<6, K>(&w.s_world, d);
    *d += trk::<K, 6>(&w.rcv_m, vj);
    out
}

/// [`inverse_dynamics_mass_product`] on one rod of a chain, each piece's
/// products in its basis's `k` directions (D101).
#[inline(never)]
fn chain_mass(rm: &RodModel, ws: &[PieceWork], v: &[f64], out: &mut [f64]) {
    let pieces = rm.spec.geometry.pieces();
    let mut a = Vec6::zeros();
    for (p, w) in pieces.iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let vj = local(v, o, k);
        let x = with_k!(k, mass_outward(w, &vj, &mut a));
        add_local(out, o, k, &x);
    }
    let mut d = Vec6::zeros();
    for (p, w) in pieces.iter().zip(ws).rev() {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let vj = local(v, o, k);
        let x = with_k!(k, mass_inward(w, &vj, &mut d));
        add_local(out, o, k, &x);
    }
}

/// [`inverse_dynamics_mass_product`] on a tree: forward, the prefix sums
/// of the ancestors' exit twists (as [`tree_vjp`]'s) against each node's
/// receivers; backward, each subtree's `Σ ℛ^𝓜ᵀ v` handed to its parent
/// through the exit the branch leaves it by.
fn tree_mass(tree: &Tree, tw: &mut TreeWork, v: &[f64], out: &mut [f64]) {
    for (i, node) in tree.nodes.iter().enumerate() {
        let up = up_through_parent(tree, tw, i, v);
        tw.up[i] = up;
        if node.k > 0 {
            let w = &tw.nodes[i];
            let vi = local(v, node.dof, node.k);
            add_local(out, node.dof, node.k, &(w.blk_a * vi + w.rcv_m * up));
        }
    }
    for d in tw.down.iter_mut() {
        d[0] = Vec6::zeros();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        if node.k > 0 {
            let w = &tw.nodes[i];
            tw.down[i][0] += w.rcv_m.tr_mul(&local(v, node.dof, node.k));
        }
        let Some(p) = node.parent else { continue };
        let d = tw.down[i][0];
        let pn = &tree.nodes[p];
        if pn.k > 0 {
            let ex = exit_towards(tree, tw, p, i);
            add_local(out, pn.dof, pn.k, &ex.s.tr_mul(&d));
        }
        tw.down[p][0] += d;
    }
}

/// A piece's own points' inertial virtual power (D85): the twist of `z` at
/// the piece's base is `up` (world axes) from the coordinates before it,
/// plus `T₋(x) B z_n` inside from its own.
#[inline(always)]
fn piece_power(w: &PieceWork, bm: &Mat6, zj: &Vec6, up: &Vec6) -> f64 {
    let base = w.base_world.ad_inv().mul_vec(up);
    base.dot(&w.win) + (bm * zj).dot(&w.tin)
}

/// [`inverse_dynamics_inertia_vjp`] on a tree: the prefix sums `up` of
/// [`tree_vjp`], then each piece's and body's virtual power.
fn tree_inertia(
    model: &Model,
    tree: &Tree,
    tw: &mut TreeWork,
    z: &[f64],
    rods: &mut [f64],
    bodies: &mut [Mat6],
) {
    for (i, node) in tree.nodes.iter().enumerate() {
        let up = up_through_parent(tree, tw, i, z);
        tw.up[i] = up;
        let w = &tw.nodes[i];
        match node.kind {
            NodeKind::Piece { rod, piece } => {
                let pc = &model.rods()[rod].spec.geometry.pieces()[piece];
                let zi = local(z, node.dof, node.k);
                rods[rod] += piece_power(w, &basis6(&pc.basis), &zi, &up);
            }
            NodeKind::Body { body } => {
                // f = 𝓜η̇′ + ad*_η 𝓜η at the body frame (its tip):
                // (J z)ᵀ δf = tr(δ𝓜 · (η̇′ (J z)ᵀ + η (ad*_ηᵀ J z)ᵀ)ᵀ).
                let ez = w.base_world.ad_inv().mul_vec(&up);
                let cz = coad(&w.eta_tip).tr_mul(&ez);
                bodies[body] = ez * w.etad_tip.transpose() + cz * w.eta_tip.transpose();
            }
            NodeKind::Joint { .. } => {}
        }
    }
}

/// The workspace fits the model and holds a linearization.
fn check_work(
    model: &Model,
    work: &IdDerivatives,
    what: &'static str,
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
        return Err(DynamicsError::NotLinearized { what });
    }
    Ok(())
}

fn check_len(model: &Model, what: &'static str, got: usize) -> Result<(), DynamicsError> {
    if got != model.n_dof() {
        return Err(DynamicsError::SizeMismatch {
            what,
            got,
            expected: model.n_dof(),
        });
    }
    Ok(())
}

/// The forward products on one rod of a chain (D84): the diagonal blocks,
/// the prefix sums of the sources `[w̄, u, Δ]_j` against the receivers of
/// the later pieces, the suffix sum of the columns `δW_j` against the
/// earlier pieces' `Ad S_i`.
fn chain_jvp(rm: &RodModel, ws: &[PieceWork], a: &[f64], b: &[f64], out: &mut [f64]) {
    let pieces = rm.spec.geometry.pieces();
    let dead = has_dead_loads(rm);
    let (mut sm, mut sb, mut sy) = (Vec6::zeros(), Vec6::zeros(), Vec6::zeros());
    for (p, w) in pieces.iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let (aj, bj) = (local(a, o, k), local(b, o, k));
        let mut v = w.blk_q * aj + w.blk_v * bj + w.rcv_m * sm + w.rcv_b * sb;
        if dead {
            v += w.rcv_y * sy;
            sy += w.s_world * aj;
        }
        add_local(out, o, k, &v);
        sm += w.src_wq * aj + w.src_wv * bj;
        sb += w.src_uq * aj + w.src_uv * bj;
    }
    let mut d = Vec6::zeros();
    for (p, w) in pieces.iter().zip(ws).rev() {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        add_local(out, o, k, &w.s_world.tr_mul(&d));
        d += w.dwq_world * local(a, o, k) + w.dwv_world * local(b, o, k);
    }
}

/// A piece of [`chain_vjp`]'s outward pass in its `K` directions: the
/// diagonal blocks and the proximal pairings against the prefix sum `a`,
/// then `a` advanced by the piece's `Ad S u`.
#[inline(always)]
fn vjp_outward<const K: usize>(w: &PieceWork, uj: &Vec6, a: &mut Vec6) -> (Vec6, Vec6) {
    let vq = trk::<K, K>(&w.blk_q, uj) + trk::<6, K>(&w.dwq_world, a);
    let vv = trk::<K, K>(&w.blk_v, uj) + trk::<6, K>(&w.dwv_world, a);
    *a += mk::<6, K>(&w.s_world, uj);
    (vq, vv)
}

/// A piece of [`chain_vjp`]'s inward pass in its `K` directions: the
/// distal pairings against the suffix sums, then the sums advanced by the
/// piece's `ℛᵀu`.
#[inline(always)]
fn vjp_inward<const K: usize>(
    w: &PieceWork,
    uj: &Vec6,
    dead: bool,
    sums: &mut [Vec6; 3],
) -> (Vec6, Vec6) {
    let [bm, bb, by] = sums;
    let mut vq = trk::<6, K>(&w.src_wq, bm) + trk::<6, K>(&w.src_uq, bb);
    if dead {
        vq += trk::<6, K>(&w.s_world, by);
    }
    let vv = trk::<6, K>(&w.src_wv, bm) + trk::<6, K>(&w.src_uv, bb);
    *bm += trk::<K, 6>(&w.rcv_m, uj);
    *bb += trk::<K, 6>(&w.rcv_b, uj);
    if dead {
        *by += trk::<K, 6>(&w.rcv_y, uj);
    }
    (vq, vv)
}

/// The products on one rod of a chain (pieces `0 … N−1` base to tip):
/// the diagonal blocks, the prefix sum `a_j = Σ_{i<j} Ad S_i u_i` against
/// the columns `δW_j` (D82), the suffix sums `Σ_{i>j} ℛᵢᵀ u_i` against the
/// sources `[w̄, u, Δ]_j` (D83); each piece's products in its basis's `k`
/// directions only (D101).
#[inline(never)]
fn chain_vjp(rm: &RodModel, ws: &[PieceWork], u: &[f64], out_q: &mut [f64], out_qd: &mut [f64]) {
    let pieces = rm.spec.geometry.pieces();
    let dead = has_dead_loads(rm);
    // Outward: the diagonal blocks and the proximal pairings.
    let mut a = Vec6::zeros();
    for (p, w) in pieces.iter().zip(ws) {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let uj = local(u, o, k);
        let (vq, vv) = with_k!(k, vjp_outward(w, &uj, &mut a));
        add_local(out_q, o, k, &vq);
        add_local(out_qd, o, k, &vv);
    }
    // Inward: the distal pairings.
    let mut sums = [Vec6::zeros(); 3];
    for (p, w) in pieces.iter().zip(ws).rev() {
        let (o, k) = (rm.dof_offset + p.dof_offset, p.basis.dof());
        let uj = local(u, o, k);
        let (vq, vv) = with_k!(k, vjp_inward(w, &uj, dead, &mut sums));
        add_local(out_q, o, k, &vq);
        add_local(out_qd, o, k, &vv);
    }
}

/// The exit of node `p` towards its child `c` (D80): the section of an
/// inside attachment, or `p`'s tip.
#[inline(always)]
/// The forward pass's sum at node `i`: its parent's sum (`tw.up`, already
/// set: nodes are in topological order) plus the parent's exit twist
/// towards `i` times the parent's coordinates of `x`; zero at a root.
fn up_through_parent(tree: &Tree, tw: &TreeWork, i: usize, x: &[f64]) -> Vec6 {
    let Some(p) = tree.nodes[i].parent else {
        return Vec6::zeros();
    };
    let pn = &tree.nodes[p];
    let mut a = tw.up[p];
    if pn.k > 0 {
        a += exit_towards(tree, tw, p, i).s * local(x, pn.dof, pn.k);
    }
    a
}

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
        let up = up_through_parent(tree, tw, i, u);
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

/// The forward products on a tree (D84): forward, each node gathers the
/// sources of its ancestors through the exits its branch leaves them by
/// (`down` holds the three sums); backward, each node hands the columns
/// `δW` of its subtree (`up`) to its parent, which pairs them with the
/// exit towards that child.
fn tree_jvp(tree: &Tree, tw: &mut TreeWork, a: &[f64], b: &[f64], out: &mut [f64]) {
    let dead = tw.dead;
    for (i, node) in tree.nodes.iter().enumerate() {
        let sums = match node.parent {
            None => [Vec6::zeros(); 3],
            Some(p) => {
                let pn = &tree.nodes[p];
                let mut s = tw.down[p];
                if pn.k > 0 {
                    let ex = exit_towards(tree, tw, p, i);
                    let (ap, bp) = (local(a, pn.dof, pn.k), local(b, pn.dof, pn.k));
                    s[0] += ex.wq * ap + ex.wv * bp;
                    s[1] += ex.uq * ap + ex.s * bp;
                    if dead {
                        s[2] += ex.s * ap;
                    }
                }
                s
            }
        };
        tw.down[i] = sums;
        if node.k > 0 {
            let w = &tw.nodes[i];
            let (ai, bi) = (local(a, node.dof, node.k), local(b, node.dof, node.k));
            let mut v = w.blk_q * ai + w.blk_v * bi + w.rcv_m * sums[0] + w.rcv_b * sums[1];
            if dead {
                v += w.rcv_y * sums[2];
            }
            add_local(out, node.dof, node.k, &v);
        }
    }
    for u in tw.up.iter_mut() {
        *u = Vec6::zeros();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        if node.k > 0 {
            let w = &tw.nodes[i];
            let (ai, bi) = (local(a, node.dof, node.k), local(b, node.dof, node.k));
            tw.up[i] += w.dwq_world * ai + w.dwv_world * bi;
        }
        let Some(p) = node.parent else { continue };
        let d = tw.up[i];
        let pn = &tree.nodes[p];
        if pn.k > 0 {
            let ex = exit_towards(tree, tw, p, i);
            add_local(out, pn.dof, pn.k, &ex.s.tr_mul(&d));
        }
        tw.up[p] += d;
    }
}
