//! The geometric stiffness in the O(N) shifted solve (docs/theory-contact.md
//! CT19–CT22): how the world-fixed forces — gravity on the rods'
//! quadrature points and on the bodies, the contact forces against
//! obstacles fixed in the world — change the generalized force when the
//! configuration moves their points of application.
//!
//! A world force `f` at a point `p` of the tree gives the Hessian of its
//! potential `−f·p(q)` the block `K_ij = S_iᵀ B S_j` for a coordinate `i`
//! inboard of (or equal to) `j` (CT19), `B = [[[f]×(−[p]×), [f]×], [0, 0]]`
//! (CT20; angular first, any frame in which `f`, `p` and the twists are
//! written), and `K_ji = K_ijᵀ`. That is the mass matrix's pattern
//! (`M_ij = S_iᵀ 𝓜ᶜ_j S_j`) with a non-symmetric "inertia" `a·B` at the
//! point, so the articulated recursion takes it unchanged as long as its
//! articulated inertia is read "inboard coordinate on the left" (CT21):
//! `𝓜ᵗ += AᵀBA`, `𝓤 += AᵀBS(x)`, `𝓓 += S(x)ᵀBS(x)` with `D̂` symmetrized.
//! Inside a piece (a rod's, or a joint's virtual one) the within-node block
//! also has the second derivative of the piece map under the wrench the
//! forces beyond it put there (CT22), added after an inward sweep of those
//! wrenches. Exact (to rounding) for these forces.

use super::shifted_contact::{ContactShift, Site};
use super::tree::local;
use crate::forces::Forces;
use crate::kernels::piece_derivs::Coefficients;
use crate::model::Model;
use crate::model::data::{Data, NodeWork};
use crate::model::tree::{Node, NodeKind, Tree};
use softrod_lie::{AdOp, Mat6, PieceMaps, Pose, Vec3, Vec6, ad, angular, join, skew};

/// `B = [[0, [f]×], [0, 0]]·a` of a force `f` (frame coordinates) acting at
/// the frame's origin (CT20 with `p = 0`).
fn point_b(f: &Vec3, a: f64) -> Mat6 {
    let mut b = Mat6::zeros();
    b.fixed_view_mut::<3, 3>(0, 3).copy_from(&(skew(f) * a));
    b
}

/// Adds the geometric block of a force `f_world` at the centreline point of
/// the frame `gl` (pose in the node's base frame, `tm` its `T₋(x)`) to the
/// node's sums (CT21).
pub(crate) fn add_point(
    w: &mut NodeWork,
    bpad: &Mat6,
    gl: &Pose,
    tm: &AdOp,
    f_world: &Vec3,
    a: f64,
) {
    let rot = w.base_world.compose(gl).rotation;
    let b = point_b(&(rot.transpose() * f_world), a);
    let am = gl.ad_inv().to_mat6();
    let s = tm.to_mat6() * bpad;
    let bs = b * s;
    w.mt += am.transpose() * (b * am);
    w.ut += am.transpose() * bs;
    w.dt += s.transpose() * bs;
}

/// `H` (padded 6×6, `k×k` used) with `H_ab = −Wᵀ D_ξT₋(x)[ζ_a] ζ_b`,
/// `ζ = B` (`bpad`'s columns): the second derivative of the piece map
/// under the wrench `W` carried at `x` (frame at `x`) — the within-piece
/// part of the Hessian that `S(x)ᵀBS(x)` leaves out (CT22). From (D32):
/// `D_ξT₋[ζ]v = Σ_i d_i (k̄ᵀζ) P^i v − c_i E_i(v) ζ`, and
/// `Wᵀ E_i(v) = Σ_{l<i} ((Pᵀ)^{i−1−l}W)ᵀ ad_{P^l v}`.
fn map_hessian(xi: &Vec6, x: f64, w: &Vec6, bpad: &Mat6, k: usize) -> Mat6 {
    let p = ad(xi);
    let pt = p.transpose();
    let co = Coefficients::at(x, angular(xi).norm());
    let kbar = join(&angular(xi), &Vec3::zeros());
    let mut y = [*w; 4];
    for j in 1..4 {
        y[j] = pt * y[j - 1];
    }
    let mut h = Mat6::zeros();
    for b in 0..k {
        let mut pv = [Vec6::zeros(); 5];
        pv[0] = bpad.column(b).into_owned();
        for l in 1..5 {
            pv[l] = p * pv[l - 1];
        }
        // r·ζ = Wᵀ D_ξT₋[ζ] v_b.
        let mut r = Vec6::zeros();
        let mut dk = 0.0;
        for i in 1..=4 {
            dk += co.d[i - 1] * w.dot(&pv[i]);
            for l in 0..i {
                r -= (ad(&pv[l]).transpose() * y[i - 1 - l]) * co.c[i - 1];
            }
        }
        r += kbar * dk;
        for a in 0..k {
            h[(a, b)] = -r.dot(&bpad.column(a));
        }
    }
    h
}

/// The wrench `(0, f)` of a force `f` at a frame's origin.
fn force_wrench(f: &Vec3) -> Vec6 {
    join(&Vec3::zeros(), f)
}

/// A wrench held fixed in the world on a frame of the tree (a loop
/// closure's force on one of its frames at given multipliers,
/// docs/theory-derivatives.md CD11): moment `m` \[N·m\] and force `f` \[N\]
/// at the origin of the frame, both in that frame's axes at the
/// linearization point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrameWrench {
    /// The node that carries the frame (a rod piece or a body).
    pub node: usize,
    /// A rod piece's local abscissa of the frame's section \[m\]; `None`
    /// for a body (the frame is then an offset of the body's base frame).
    pub x: Option<f64>,
    /// The frame in the section at `x` (a rod) or in the body's base frame.
    pub offset: Pose,
    /// `(m, f)` in the frame's axes.
    pub wrench: Vec6,
}

/// `B·a` of a wrench `w = (m, f)` at a frame's origin, in that frame
/// (CD11): `[[[m]×, [f]×], [0, 0]]` — the moment's part `ω_iᵀ[m]×ω_j` of
/// `K_ij = −w·(ad_{S_i} S_j)` beside the force's (CT20 with `p = 0`).
fn wrench_b(w: &Vec6, a: f64) -> Mat6 {
    let mut b = Mat6::zeros();
    b.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(skew(&angular(w)) * a));
    b.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(skew(&Vec3::new(w[3], w[4], w[5])) * a));
    b
}

/// Adds the blocks of the frame wrenches `extra` (CD11; after the point
/// forces of [`add`], before its inward sweep): a wrench at an offset
/// frame `o` of the section at `x` is `B_x = Ad_{o⁻¹}ᵀ B_o Ad_{o⁻¹}`
/// there (B transforms like a spatial inertia, CT20), and its wrench at
/// `x` is `Ad_{o⁻¹}ᵀ w_o` for the map Hessian (CT22) and the inward sweep.
fn add_frame_wrenches(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q: &[f64],
    a: f64,
    extra: &[FrameWrench],
) {
    for fw in extra {
        let node = &tree.nodes[fw.node];
        let ao = fw.offset.ad_inv();
        let aom = ao.to_mat6();
        let bx = aom.transpose() * (wrench_b(&fw.wrench, a) * aom);
        let wx = ao.tr_mul_vec(&fw.wrench);
        match (&node.kind, fw.x) {
            (&NodeKind::Piece { rod, piece }, Some(x)) => {
                let rm = &model.rods[rod];
                let xi = rm.spec.geometry.pieces()[piece].strain(&q[rm.dofs()]);
                let (gl, tm) = PieceMaps::new(&xi, None).exp_and_tangent_minus(x);
                let w = &mut data.nodes[fw.node];
                let am = gl.ad_inv().to_mat6();
                let s = tm.to_mat6() * node.bpad;
                let bs = bx * s;
                w.mt += am.transpose() * (bx * am);
                w.ut += am.transpose() * bs;
                w.dt += s.transpose() * bs;
                w.dt += map_hessian(&xi, x, &wx, &node.bpad, node.k) * a;
                w.p_big += gl.ad_inv().tr_mul_vec(&wx);
            }
            (NodeKind::Body { .. }, None) => {
                let w = &mut data.nodes[fw.node];
                w.mt += bx;
                w.p_big += wx;
            }
            // The caller builds the wrenches from the closures' resolved
            // frames: a rod frame is on a piece, a body frame on a body.
            _ => {}
        }
    }
}

/// Adds `a`× the geometric stiffness of the world-fixed forces to every
/// node's sums (after the composite outward sweep at `q`, CT21–CT22):
/// gravity (each rod quadrature point's weight `m g` at its centreline
/// point; each body's `m g` at its centre of mass, `B = E_g 𝓜`,
/// `E_g = [[0, [g]×], [0, 0]]` in the body frame) and the contact forces
/// of `contact`'s one-sided blocks (held at their values at the
/// linearization) and the wrenches `extra` (a closed model's closure
/// forces at held multipliers, CD11). Then an inward sweep of the wrenches those forces put on
/// each node's tip and attachment points adds the pieces' map Hessians
/// under them ([`map_hessian`]). Uses the nodes' `p_big` and `f_tip` as
/// scratch (the factorization does not read them).
pub(crate) fn add(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q: &[f64],
    a: f64,
    contact: Option<&ContactShift>,
    extra: &[FrameWrench],
) {
    let g = model.gravity.map(|g| g * Forces::ALL.load_scale);
    for w in &mut data.nodes {
        w.p_big = Vec6::zeros();
        w.f_tip = Vec6::zeros();
    }
    if a == 0.0 {
        return;
    }
    // The forces at points: their blocks, their within-piece Hessians, and
    // their wrench at the node's base.
    let point = |data: &mut Data, i: usize, x: f64, f: &Vec3| {
        let node = &tree.nodes[i];
        let NodeKind::Piece { rod, piece } = node.kind else {
            return;
        };
        let rm = &model.rods[rod];
        let xi = rm.spec.geometry.pieces()[piece].strain(&q[rm.dofs()]);
        let (gl, tm) = PieceMaps::new(&xi, None).exp_and_tangent_minus(x);
        let w = &mut data.nodes[i];
        add_point(w, &node.bpad, &gl, &tm, f, a);
        let fl = force_wrench(&(w.base_world.compose(&gl).rotation.transpose() * f));
        w.dt += map_hessian(&xi, x, &fl, &node.bpad, node.k) * a;
        w.p_big += gl.ad_inv().tr_mul_vec(&fl);
    };
    if let Some(g) = g.filter(|g| g.norm() > 0.0) {
        for (i, node) in tree.nodes.iter().enumerate() {
            match node.kind {
                NodeKind::Body { body } => {
                    let w = &mut data.nodes[i];
                    let gb = w.base_world.rotation.transpose() * g;
                    let inertia = &model.bodies[body].inertia;
                    w.mt += point_b(&gb, a) * inertia;
                    w.p_big += inertia * force_wrench(&gb);
                }
                NodeKind::Piece { rod, piece } => {
                    for qp in &model.rods[rod].pieces[piece].points {
                        point(data, i, qp.x, &(g * (qp.inertia[3] * qp.w)));
                    }
                }
                NodeKind::Joint { .. } => {}
            }
        }
    }
    if let Some(c) = contact {
        for blk in &c.blocks {
            let Site::Section { rod, piece, x } = blk.site;
            point(data, tree.rod_nodes[rod][piece], x, &blk.f);
        }
    }
    add_frame_wrenches(model, tree, data, q, a, extra);
    // Inward: the wrench beyond each tip or attachment point, and the map
    // Hessian of the node that carries it there.
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let w = &data.nodes[i];
        let xi = node_strain(model, node, data, q);
        let (tip_w, tip, length) = (w.f_tip, w.tip, node_length(model, node));
        if node.k > 0 && tip_w != Vec6::zeros() {
            data.nodes[i].dt += map_hessian(&xi, length, &tip_w, &node.bpad, node.k) * a;
        }
        let w = &data.nodes[i];
        let wb = w.p_big + tip.ad_inv().tr_mul_vec(&tip_w);
        let Some(p) = node.parent else {
            continue;
        };
        let wx = node.offset.ad_inv().tr_mul_vec(&wb);
        match node.attach {
            Some(x) => {
                let pn = &tree.nodes[p];
                let attach_a = data.nodes[i].attach_a;
                if pn.k > 0 {
                    let pxi = node_strain(model, pn, data, q);
                    data.nodes[p].dt += map_hessian(&pxi, x, &wx, &pn.bpad, pn.k) * a;
                }
                data.nodes[p].p_big += attach_a.transpose() * wx;
            }
            None => data.nodes[p].f_tip += wx,
        }
    }
}

/// The strain `ξ` of a piece-like node (a rod piece, or a joint's virtual
/// piece, D50); zero for bodies.
fn node_strain(model: &Model, node: &Node, data: &Data, q: &[f64]) -> Vec6 {
    match node.kind {
        NodeKind::Piece { rod, piece } => {
            let rm = &model.rods[rod];
            rm.spec.geometry.pieces()[piece].strain(&q[rm.dofs()])
        }
        NodeKind::Joint { .. } => match node.prescribed {
            Some((o, kp)) => node.bpad * local(data.prescribed_q.as_slice(), o, kp),
            None => node.bpad * local(q, node.dof, node.k),
        },
        NodeKind::Body { .. } => Vec6::zeros(),
    }
}

/// A node's length: its piece's, 1 for a joint's unit virtual piece.
fn node_length(model: &Model, node: &Node) -> f64 {
    match node.kind {
        NodeKind::Piece { rod, piece } => model.rods[rod].spec.geometry.pieces()[piece].length,
        _ => 1.0,
    }
}

/// `|D|⁻¹` of the symmetric part of `d`'s leading `k×k` block (padded like
/// [`super::tree::inverse_k`]): the eigenvalues replaced by their
/// magnitudes, floored at `1e-12` of the largest (CT23). `None` if `d` is
/// not finite or zero.
pub(crate) fn abs_inverse_k(d: &Mat6, k: usize) -> Option<Mat6> {
    let padded = Mat6::from_fn(|i, j| {
        if i < k && j < k {
            0.5 * (d[(i, j)] + d[(j, i)])
        } else if i == j {
            1.0
        } else {
            0.0
        }
    });
    if !padded.iter().all(|v| v.is_finite()) {
        return None;
    }
    let e = padded.symmetric_eigen();
    let top = e.eigenvalues.amax();
    if top == 0.0 {
        return None;
    }
    let inv = e.eigenvalues.map(|l| 1.0 / l.abs().max(1e-12 * top));
    let full = e.eigenvectors * Mat6::from_diagonal(&inv) * e.eigenvectors.transpose();
    Some(Mat6::from_fn(|i, j| {
        if i < k && j < k { full[(i, j)] } else { 0.0 }
    }))
}
