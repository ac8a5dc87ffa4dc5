//! Analytic `∂τ/∂q`, `∂τ/∂q̇` of the inverse dynamics on the tree of an
//! articulated model (docs/theory-derivatives.md §7, (D76)–(D80)): the
//! chain's sweeps (D37)–(D47) node by node. A joint is a piece without
//! points (D50), a body a single rigid inertia without coordinates (D52), a
//! prescribed joint a piece whose strain is given (D59); what a node's
//! subtree hands to the frame it hangs from is summed at its parent's tip,
//! or enters the parent piece like a point load at `x` (D62); the blocks of
//! two nodes on one path to the root are pairings of world-frame quantities
//! taken where that path leaves the proximal node, and nodes on different
//! branches do not couple.

use super::piece::{PieceWork, Subtree, close_mass, close_piece, put_block, write_piece};
use super::point::{PieceLin, PointLin, basis6, linearize_point, own_points};
use super::{At, IdDerivatives};
use crate::algorithms::tree::local;
use crate::forces::external::world_acceleration;
use crate::forces::linearized::{dead_load_map, drag_diagonal, has_dead_loads};
use crate::kernels::mat6::{Cols, mm_part, tm_part};
use crate::kernels::piece_derivs::{PieceDerivMaps, lambda as lambda_of};
use crate::model::Model;
use crate::model::tree::{NodeKind, Tree};
use nalgebra::DVector;
use softrod_lie::{Mat6, PieceMaps, Pose, Vec6, ad, coad, coad_vec};
use softrod_mechanics::LoadFrame;

/// The world-frame quantities of a node's coordinates at the frame a
/// distal branch leaves it from (D46, D80): the columns `Ad_G S` of that
/// frame and the sources `Ad_G w̄`, `Ad_G u` per unit strain (coordinates)
/// and `Ad_G w̄` per unit rate (6×k each).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Exit {
    pub(super) s: Mat6,
    pub(super) wq: Mat6,
    pub(super) uq: Mat6,
    pub(super) wv: Mat6,
}

impl Exit {
    fn zero() -> Self {
        Self {
            s: Mat6::zeros(),
            wq: Mat6::zeros(),
            uq: Mat6::zeros(),
            wv: Mat6::zeros(),
        }
    }
}

/// Per-node buffers of the tree derivatives (allocated once).
#[derive(Clone, Debug)]
pub(crate) struct TreeWork {
    pub(super) nodes: Vec<PieceWork>,
    /// For a node hanging inside its parent piece (D62): the parent's
    /// section there, linearized in the parent's strain (its local pose and
    /// (D39)–(D41)), and the parent's exit quantities at it.
    at: Vec<Option<(Pose, PointLin)>>,
    pub(super) exit: Vec<Exit>,
    /// The products' sums per node ([`super::vjp`], D81): `Σ S_exit u` over
    /// the ancestors, and `Σ ℛᵀu` (`𝓜`, `𝓑`, `𝒴` receivers) over the subtree.
    pub(super) up: Vec<Vec6>,
    pub(super) down: Vec<[Vec6; 3]>,
    /// What the children at a node's tip hand to it, and what the node
    /// hands to its own base frame (D43, D77).
    tip: Vec<Subtree>,
    base: Vec<Subtree>,
    /// The prescribed joints' values, rates and accelerations at `t`.
    pq: DVector<f64>,
    pqd: DVector<f64>,
    pqdd: DVector<f64>,
    /// Any dead (world-frame) load in the model: the `𝒴` terms.
    pub(super) dead: bool,
}

impl TreeWork {
    pub(crate) fn new(model: &Model, tree: &Tree) -> Self {
        let n = tree.nodes.len();
        let np = model.n_prescribed();
        let dead = model.rods().iter().any(has_dead_loads)
            || model
                .bodies()
                .iter()
                .any(|b| b.spec.loads.iter().any(|l| l.frame == LoadFrame::World));
        Self {
            nodes: (0..n).map(|_| PieceWork::new()).collect(),
            at: vec![None; n],
            exit: vec![Exit::zero(); n],
            up: vec![Vec6::zeros(); n],
            down: vec![[Vec6::zeros(); 3]; n],
            tip: vec![Subtree::zero(); n],
            base: vec![Subtree::zero(); n],
            pq: DVector::zeros(np),
            pqd: DVector::zeros(np),
            pqdd: DVector::zeros(np),
            dead,
        }
    }

    pub(crate) fn n_nodes(&self) -> usize {
        self.nodes.len()
    }
}

/// `∂τ/∂q`, `∂τ/∂q̇` and `τ` of an articulated model without closures into
/// `work` (arguments checked by the caller). Kept out of line: inlined into
/// the chain path's caller it would change that path's inlining (measured
/// +4 % instructions on the chain).
#[inline(never)]
pub(crate) fn tree_id_derivatives(
    model: &Model,
    tree: &Tree,
    work: &mut IdDerivatives,
    tw: &mut TreeWork,
    at: &At,
) {
    let (t, forces) = (at.t, at.forces);
    model.prescribed_values(
        t,
        tw.pq.as_mut_slice(),
        tw.pqd.as_mut_slice(),
        tw.pqdd.as_mut_slice(),
    );
    if !forces.drives_move() {
        tw.pqd.fill(0.0);
        tw.pqdd.fill(0.0);
    }
    // Nodes on different branches do not couple: those blocks stay zero.
    if at.dense {
        work.dtau_dq.fill(0.0);
        work.dtau_dqd.fill(0.0);
    }
    outward(model, tree, tw, at);
    inward(model, tree, work, tw, at);
    if at.dense {
        pairs(tree, work, tw);
    }
}

/// The outward sweep (D76): each node's base motion from its parent's tip
/// (or section, D62), then its own points (pieces), its body sums (bodies)
/// and its tip, as in the chain's (D39)–(D43).
fn outward(model: &Model, tree: &Tree, tw: &mut TreeWork, at: &At) {
    let (q, qd, qdd) = (at.q, at.qd, at.qdd);
    let scale = at.forces.load_scale;
    let a_world = world_acceleration(model, scale);
    for (i, node) in tree.nodes.iter().enumerate() {
        let (parent_pose, eta_p, etad_p) = match (node.parent, &tw.at[i]) {
            (None, _) => (Pose::identity(), Vec6::zeros(), a_world),
            (Some(p), Some((g, lin))) => (tw.nodes[p].base_world.compose(g), lin.eta, lin.etad),
            (Some(p), None) => {
                let w = &tw.nodes[p];
                (w.tip_world, w.eta_tip, w.etad_tip)
            }
        };
        let x = node.offset.ad_inv();
        let (eta_b, etad_b) = (x.mul_vec(&eta_p), x.mul_vec(&etad_p));
        let base_world = parent_pose.compose(&node.offset);
        let w = &mut tw.nodes[i];
        w.reset_sums();
        w.base_world = base_world;
        let (xi, xid, xidd, length) = match node.kind {
            NodeKind::Body { body } => {
                body_sums(model, body, &eta_b, &etad_b, scale, w);
                continue;
            }
            NodeKind::Joint { .. } => {
                let b = &node.bpad;
                let (v, vd, vdd, o, k) = match node.prescribed {
                    Some((o, kp)) => (
                        tw.pq.as_slice(),
                        tw.pqd.as_slice(),
                        tw.pqdd.as_slice(),
                        o,
                        kp,
                    ),
                    None => (q, qd, qdd, node.dof, node.k),
                };
                (
                    b * local(v, o, k),
                    b * local(vd, o, k),
                    b * local(vdd, o, k),
                    1.0,
                )
            }
            NodeKind::Piece { rod, piece } => {
                let rm = &model.rods()[rod];
                let pc = &rm.spec.geometry.pieces()[piece];
                let r = rm.dofs();
                (
                    pc.strain(&q[r.clone()]),
                    pc.strain_rate(&qd[r.clone()]),
                    pc.strain_rate(&qdd[r]),
                    pc.length,
                )
            }
        };
        let maps = PieceMaps::new(&xi, Some(&xid));
        let dm = PieceDerivMaps::new(&xi, &xid, &xidd);
        let cols = Cols::of(&node.bpad);
        let pc = PieceLin {
            maps: &maps,
            dm: &dm,
            eta0: &eta_b,
            etad0: &etad_b,
            xid: &xid,
            xidd: &xidd,
            cols: &cols,
        };
        if let NodeKind::Piece { rod, piece } = node.kind {
            let rm = &model.rods()[rod];
            let drag = drag_diagonal(rm);
            own_points(
                rm,
                &rm.pieces[piece],
                &pc,
                &base_world,
                drag.as_ref(),
                scale,
                !at.dense,
                w,
            );
        }
        let (g, p) = linearize_point(&pc, length);
        w.set_tip(g, &p, &dm);
        for &c in &tree.inner_children[i] {
            let x = tree.nodes[c].attach.unwrap_or(length);
            tw.at[c] = Some(linearize_point(&pc, x));
        }
    }
}

/// A rigid body's own sums (D52, D77): its screw inertia `𝓜` at the body
/// frame, the net wrench `f = 𝓜η̇′ + ad*_η𝓜η − 𝓕_ext` and its
/// linearization `B̄ = Λ(𝓜η) + ad*_η𝓜 − 𝓜 ad_η` (D38, D43 with a full
/// `𝓜`), `𝒴` of its dead loads. Its tip is its frame.
fn body_sums(model: &Model, body: usize, eta: &Vec6, etad: &Vec6, scale: f64, w: &mut PieceWork) {
    let bm = &model.bodies()[body];
    let m = &bm.inertia;
    let me = m * eta;
    let mut f = m * etad + coad_vec(eta, &me);
    for l in &bm.spec.loads {
        let load = l.wrench(&w.base_world) * scale;
        f -= load;
        if l.frame == LoadFrame::World {
            w.yt += dead_load_map(&load);
        }
    }
    w.mt = *m;
    w.bt = lambda_of(&me) + coad(eta) * m - m * ad(eta);
    w.wsum = f;
    w.tip = Pose::identity();
    w.tip_world = w.base_world;
    w.eta_tip = *eta;
    w.etad_tip = *etad;
}

/// A subtree hanging inside a piece at `x` (D62, D78), `sub` in the axes
/// of that section: it enters the piece's sums like a point load that
/// carries the subtree's response `δW = 𝓜ᶜw̄(x) + 𝓑ᶜu(x) + 𝒴ᶜΔ(x)` (D42–D45
/// at `x`). Returns the piece's exit quantities at `x` (D80).
fn add_inner(
    w: &mut PieceWork,
    g: &Pose,
    lin: &PointLin,
    sub: &Subtree,
    bm: &Mat6,
    dead: bool,
) -> Exit {
    // The piece's strain directions on its basis's `k` columns (D90):
    // `lin`'s `H` and `T₋B` are 6×k already.
    let k = Cols::of(bm).k;
    let a = lin.a.to_mat6();
    let t = lin.t.to_mat6();
    let tb = &lin.tb;
    let adeta = ad(&lin.eta);
    let wq = lin.h_etad + mm_part(&adeta, &lin.h_eta, 6, k);
    let uq = lin.h_eta;
    let mut dwq = mm_part(&sub.m, &wq, 6, k) + mm_part(&sub.b, &uq, 6, k);
    if dead {
        dwq += mm_part(&sub.y, tb, 6, k);
    }
    let wv = lin.h_vd + mm_part(&adeta, tb, 6, k);
    let dwv = mm_part(&sub.m, &wv, 6, k) + mm_part(&sub.b, tb, 6, k);
    let (at, tt) = (a.transpose(), t.transpose());
    w.dq_diag += tm_part(tb, &dwq, k, k);
    w.dv_diag += tm_part(tb, &dwv, k, k);
    w.dq_w += mm_part(&at, &(mm_part(&lambda_of(&sub.w), tb, 6, k) + dwq), 6, k);
    w.dv_w += mm_part(&at, &dwv, 6, k);
    w.tsum += tt * sub.w;
    w.wsum += at * sub.w;
    for i in 0..4 {
        w.phi[i] += sub.w * lin.co.d[i];
        w.chi[i] += sub.w * lin.co.c[i];
    }
    let (ma, ba) = (sub.m * a, sub.b * a);
    w.mtt += tm_part(tb, &mm_part(&sub.m, tb, 6, k), k, k);
    w.mt += at * ma;
    w.bt += at * ba;
    w.rm += tm_part(tb, &ma, k, 6);
    w.rb += tm_part(tb, &ba, k, 6);
    if dead {
        let ya = sub.y * a;
        w.yt += at * ya;
        w.ry += tm_part(tb, &ya, k, 6);
    }
    let to_world = w.base_world.compose(g).ad().to_mat6();
    Exit {
        s: mm_part(&to_world, tb, 6, k),
        wq: mm_part(&to_world, &wq, 6, k),
        uq: mm_part(&to_world, &uq, 6, k),
        wv: mm_part(&to_world, &wv, 6, k),
    }
}

/// The inward sweep (D77–D79): children before parents; each node closes
/// with what its tip children handed it and its inside children added to
/// its sums, writes its `τ` and diagonal blocks, and hands its subtree to
/// its parent.
fn inward(model: &Model, tree: &Tree, work: &mut IdDerivatives, tw: &mut TreeWork, at: &At) {
    let dead = tw.dead;
    for s in tw.tip.iter_mut() {
        *s = Subtree::zero();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        for &c in &tree.inner_children[i] {
            let xc = tree.nodes[c].offset.ad_inv().to_mat6();
            let sub = tw.base[c].through(&xc, dead);
            let Some((g, lin)) = &tw.at[c] else {
                unreachable!("the outward sweep linearized every inside attachment")
            };
            tw.exit[c] = add_inner(&mut tw.nodes[i], g, lin, &sub, &node.bpad, dead);
        }
        let base = match node.kind {
            NodeKind::Body { .. } => {
                let (w, tip) = (&tw.nodes[i], &tw.tip[i]);
                Subtree {
                    m: w.mt + tip.m,
                    b: w.bt + tip.b,
                    y: w.yt + tip.y,
                    w: w.wsum + tip.w,
                }
            }
            NodeKind::Piece { rod, piece } => {
                let rm = &model.rods()[rod];
                let bm = basis6(&rm.spec.geometry.pieces()[piece].basis);
                let (dq, dv, wrench, base) = close_piece(&mut tw.nodes[i], &tw.tip[i], &bm, dead);
                if !at.dense {
                    close_mass(&mut tw.nodes[i], &tw.tip[i].m, &bm);
                }
                let (bq, bv) = write_piece(model, rm, piece, work, at, &bm, (&dq, &dv, &wrench));
                let w = &mut tw.nodes[i];
                w.blk_q = bq;
                w.blk_v = bv;
                base
            }
            NodeKind::Joint { element } => {
                let (dq, dv, wrench, base) =
                    close_piece(&mut tw.nodes[i], &tw.tip[i], &node.bpad, dead);
                if node.k > 0 && !at.dense {
                    close_mass(&mut tw.nodes[i], &tw.tip[i].m, &node.bpad);
                }
                if node.k > 0 {
                    let (bq, bv) = write_joint(model, element, node, work, at, (&dq, &dv, &wrench));
                    let w = &mut tw.nodes[i];
                    w.blk_q = bq;
                    w.blk_v = bv;
                }
                base
            }
        };
        tw.base[i] = base;
        if let (Some(p), None) = (node.parent, node.attach) {
            let x = node.offset.ad_inv().to_mat6();
            let carried = base.through(&x, dead);
            tw.tip[p].add(&carried);
        }
    }
}

/// A joint's `τ` and diagonal blocks: the projection of its transmitted
/// wrench plus its spring and damper (D53) on the diagonal; the blocks are
/// returned (k×k in the leading part) and written into the dense matrices
/// when the evaluation forms them.
fn write_joint(
    model: &Model,
    element: usize,
    node: &crate::model::tree::Node,
    work: &mut IdDerivatives,
    at: &At,
    (diag_q, diag_v, wrench): (&Mat6, &Mat6, &Vec6),
) -> (Mat6, Mat6) {
    let (q, qd) = (at.q, at.qd);
    let info = &model.elements()[element];
    let joint = &info.attachment.joint;
    let first = node.dof - info.joint_dofs.start;
    let b = &node.bpad;
    // `close_piece` returned them in the joint's coordinates already.
    let (mut dq6, mut dv6) = (*diag_q, *diag_v);
    let o = node.dof;
    for i in 0..node.k {
        let (kc, dc, rest) = joint.coefficients(first + i);
        work.tau[o + i] = b.column(i).dot(wrench) + kc * (q[o + i] - rest) + dc * qd[o + i];
        if let (Some(a), false) = (&joint.actuator, at.forces.gravity_only) {
            // A force of time alone (IS14): in τ, not in its derivatives.
            work.tau[o + i] -= at.forces.load_scale
                * crate::forces::strain::actuator_force(
                    work.joint_inputs.as_ref(),
                    info,
                    a,
                    first + i,
                    at.t,
                );
        }
        dq6[(i, i)] += kc;
        dv6[(i, i)] += dc;
    }
    if at.dense {
        put_block(work, o, node.k, &dq6, &dv6);
    }
    (dq6, dv6)
}

/// The off-diagonal blocks (D80): for every node `i` with coordinates and
/// every ancestor `j` with coordinates, the exit of `j` its path leaves by
/// (the tip, or the section of an inside attachment) gives
/// `∂τ_i/∂q_j = ℛ_i [w̄, u, Δ]_exit` (the distal block, D45) and
/// `∂τ_j/∂q_i = S_exitᵀ δW_i` (the proximal block, D46), both in the world
/// frame.
fn pairs(tree: &Tree, work: &mut IdDerivatives, tw: &TreeWork) {
    let dead = tw.dead;
    for (i, node) in tree.nodes.iter().enumerate() {
        let ki = node.k;
        if ki == 0 {
            continue;
        }
        let wi = &tw.nodes[i];
        let mut cur = i;
        while let Some(p) = tree.nodes[cur].parent {
            let pn = &tree.nodes[p];
            if pn.k > 0 {
                let ex = if tree.nodes[cur].attach.is_some() {
                    tw.exit[cur]
                } else {
                    let wp = &tw.nodes[p];
                    Exit {
                        s: wp.s_world,
                        wq: wp.src_wq,
                        uq: wp.src_uq,
                        wv: wp.src_wv,
                    }
                };
                let mut dq = wi.rcv_m * ex.wq + wi.rcv_b * ex.uq;
                if dead {
                    dq += wi.rcv_y * ex.s;
                }
                let dv = wi.rcv_m * ex.wv + wi.rcv_b * ex.s;
                let st = ex.s.transpose();
                let (pq, pv) = (st * wi.dwq_world, st * wi.dwv_world);
                let kp = pn.k;
                for r in 0..ki {
                    for c in 0..kp {
                        work.dtau_dq[(node.dof + r, pn.dof + c)] = dq[(r, c)];
                        work.dtau_dqd[(node.dof + r, pn.dof + c)] = dv[(r, c)];
                    }
                }
                for r in 0..kp {
                    for c in 0..ki {
                        work.dtau_dq[(pn.dof + r, node.dof + c)] = pq[(r, c)];
                        work.dtau_dqd[(pn.dof + r, node.dof + c)] = pv[(r, c)];
                    }
                }
            }
            cur = p;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{
        Attachment, Curve, Data, Drives, Forces, IdDerivatives, Joint, Model, Prescribed, Rod,
        inverse_dynamics_derivatives_with, static_force,
    };
    use softrod_mechanics::{Material, RodProperties, Section};

    /// With the prescribed joints held at rest (what statics linearizes),
    /// `∂τ/∂q` is the derivative of `static_force`, not of the inverse
    /// dynamics with the drive moving (which differs by the drive's
    /// velocity and acceleration terms).
    #[test]
    fn prescribed_at_rest_differentiates_the_static_force() {
        let rod = softrod_kinematics::RodGeometry::uniform(
            0.3,
            3,
            softrod_kinematics::Basis::all(),
            softrod_kinematics::straight(),
            softrod_lie::Pose::identity(),
        )
        .unwrap();
        let material = Material::with_poisson(1000.0, 1e6, 0.5, 0.0).unwrap();
        let body = RodProperties::new(Section::Circle { radius: 0.01 }, material, 0.3).unwrap();
        let drive =
            Joint::revolute([0.0, 1.0, 0.0]).with_prescribed(Prescribed::new(vec![Curve::Sine {
                amplitude: 0.8,
                frequency: 2.0,
                phase: 0.3,
                offset: 0.1,
            }]));
        let m = Model::with_elements(
            vec![crate::Element::Rod(
                Rod::new("arm", rod, body),
                Attachment::world_joint(drive),
            )],
            Some(softrod_lie::Vec3::new(0.0, 0.0, -9.81)),
            4,
        )
        .unwrap();
        let n = m.n_dof();
        let q: Vec<f64> = (0..n).map(|i| 0.2 * (1.3 * i as f64).sin()).collect();
        let z = vec![0.0; n];
        let t = 0.17;
        let mut work = IdDerivatives::new(&m);
        let rest = Forces::ALL.with_drives(Drives::AtRest);
        inverse_dynamics_derivatives_with(&m, &mut work, rest, t, &q, &z, &z).unwrap();
        let at_rest = work.dtau_dq.clone();
        inverse_dynamics_derivatives_with(&m, &mut work, Forces::ALL, t, &q, &z, &z).unwrap();
        let moving = work.dtau_dq.clone();
        let mut data = Data::new(&m);
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        for j in 0..n {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[j] += h;
            qm[j] -= h;
            let fp = static_force(&m, &mut data, t, &qp).unwrap().clone();
            let fm = static_force(&m, &mut data, t, &qm).unwrap().clone();
            let col = (fp - fm) / (2.0 * h);
            worst = worst.max((at_rest.column(j) - col).amax());
        }
        let scale = at_rest.amax();
        assert!(worst < 1e-7 * scale, "{worst:e} of {scale:e}");
        // The moving drive changes it by more than the differences' error.
        assert!((&moving - &at_rest).amax() > 1e-4 * scale);
    }
}
