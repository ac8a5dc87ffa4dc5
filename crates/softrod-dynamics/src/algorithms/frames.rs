//! Frames on the tree (D51, D57, D62): the motion of the frame a node
//! hangs from, the spatial columns `Ad_{g_world} S` of a node's
//! coordinates where a path to the root leaves it, the pose, world twist
//! and acceleration of any section of a rod (or body frame) after an
//! outward sweep, and the world poses of every rod base and body. What the
//! closures' Jacobians and `section_jacobian` are made of.

use super::tree::outward;
use super::{Motion, Pass};
use crate::forces::Forces;
use crate::model::Model;
use crate::model::closure::{ResolvedFrame, Target};
use crate::model::data::Data;
use crate::model::tree::Tree;
use nalgebra::DMatrix;
use softrod_lie::{Mat6, PieceMaps, Pose, Vec3, Vec6, ad_vec};

/// The motion `(η, η̇)` of the frame node `c` hangs from (its parent's tip,
/// or the point inside the parent piece, D62), in that frame's axes.
pub(crate) fn parent_motion(tree: &Tree, data: &Data, c: usize) -> (Vec6, Vec6) {
    match tree.nodes[c].parent {
        None => (Vec6::zeros(), Vec6::zeros()),
        Some(_) if tree.nodes[c].attach.is_some() => {
            (data.nodes[c].attach_eta, data.nodes[c].attach_etadot)
        }
        Some(p) => (data.nodes[p].eta_tip, data.nodes[p].etadot_tip),
    }
}

/// The spatial columns of node `c`'s parent's coordinates at the frame `c`
/// hangs from, `Ad_{g_world} S` (6×k padded; D57, D62): what moves `c` and
/// everything beyond it per unit rate of the parent's coordinates.
pub(crate) fn parent_column(tree: &Tree, data: &Data, c: usize) -> Mat6 {
    let Some(p) = tree.nodes[c].parent else {
        return Mat6::zeros();
    };
    let wp = &data.nodes[p];
    if tree.nodes[c].attach.is_some() {
        let wc = &data.nodes[c];
        wp.base_world.compose(&wc.attach_pose).ad().to_mat6() * wc.attach_s
    } else {
        wp.base_world.compose(&wp.tip).ad().to_mat6() * wp.s_tip
    }
}

/// Pose, world twist and world acceleration (velocity-product part, no
/// gravity) of a closure frame, from the nodes of the last outward pass.
pub(crate) struct FrameState {
    pub pose: Pose,
    /// World (spatial) twist `Ad_G η` and its rate `Ad_G η̇` at `q̈ = 0`.
    pub vel: Vec6,
    pub acc: Vec6,
    /// In-piece spatial column block `Ad_{G(x)} T₋(x) B` (6×k padded) and
    /// its node; `None` for bodies and the world.
    pub own: Option<(usize, Mat6)>,
    /// A rod section's local pose in its node `g(x)` and its node's local
    /// columns `T₋(x) B` (6×k padded); `None` for bodies and the world.
    pub local: Option<(Pose, Mat6)>,
    /// First ancestor node whose coordinates move the frame rigidly.
    pub ancestors: Option<usize>,
    /// The node whose parent that is (where the path to the root starts).
    pub from: Option<usize>,
}

pub(crate) fn frame_state(
    model: &Model,
    tree: &Tree,
    data: &Data,
    f: &ResolvedFrame,
    q: &[f64],
    qd: Option<&[f64]>,
) -> FrameState {
    match f.target {
        Target::World => FrameState {
            pose: f.offset,
            vel: Vec6::zeros(),
            acc: Vec6::zeros(),
            own: None,
            local: None,
            ancestors: None,
            from: None,
        },
        Target::Body { node } => {
            let w = &data.nodes[node];
            let ad = w.base_world.ad();
            FrameState {
                pose: w.base_world.compose(&f.offset),
                vel: ad.mul_vec(&w.eta_tip),
                acc: ad.mul_vec(&w.etadot_tip),
                own: None,
                local: None,
                ancestors: tree.nodes[node].parent,
                from: Some(node),
            }
        }
        Target::Rod {
            rod,
            piece,
            x,
            node,
        } => {
            let nd = &tree.nodes[node];
            let (eta_p, etadot_p) = parent_motion(tree, data, node);
            let xo = nd.offset.ad_inv();
            let eta_b = xo.mul_vec(&eta_p);
            let etadot_b = xo.mul_vec(&etadot_p);
            let rm = &model.rods[rod];
            let pc = &rm.spec.geometry.pieces()[piece];
            let r = rm.dofs();
            let xi = pc.strain(&q[r.clone()]);
            let dxi = qd.map_or(Vec6::zeros(), |v| pc.strain_rate(&v[r]));
            let maps = PieceMaps::new(&xi, qd.is_some().then_some(&dxi));
            let (gl, tm, dbias) = maps.eval(x);
            let g = data.nodes[node].base_world.compose(&gl);
            let a = gl.ad_inv();
            let carried = a.mul_vec(&eta_b);
            let sv = tm.mul_vec(&dxi);
            let eta = carried + sv;
            let etadot = a.mul_vec(&etadot_b)
                + if qd.is_some() {
                    ad_vec(&carried, &sv) + dbias
                } else {
                    Vec6::zeros()
                };
            let ad = g.ad();
            let sb = tm.to_mat6() * nd.bpad;
            FrameState {
                pose: g.compose(&f.offset),
                vel: ad.mul_vec(&eta),
                acc: ad.mul_vec(&etadot),
                own: Some((node, ad.to_mat6() * sb)),
                local: Some((gl, sb)),
                ancestors: nd.parent,
                from: Some(node),
            }
        }
    }
}

/// The pose of a frame after an outward sweep: [`frame_state`]`(…, None)`'s
/// `pose` to the bit (the same exponential, D4, and compositions), without
/// the twists, the tangent map's column blocks and their 6×6 products —
/// what contact needs of every sample before it knows whether it touches
/// (CT7).
pub(crate) fn frame_pose(model: &Model, data: &Data, f: &ResolvedFrame, q: &[f64]) -> Pose {
    match f.target {
        Target::World => f.offset,
        Target::Body { node } => data.nodes[node].base_world.compose(&f.offset),
        Target::Rod {
            rod,
            piece,
            x,
            node,
        } => {
            let rm = &model.rods[rod];
            let pc = &rm.spec.geometry.pieces()[piece];
            let xi = pc.strain(&q[rm.dofs()]);
            let (gl, _) = PieceMaps::new(&xi, None).exp_and_tangent_minus(x);
            data.nodes[node].base_world.compose(&gl).compose(&f.offset)
        }
    }
}

/// A block of rows to fill with a frame's spatial columns: the row
/// operator `C` (its first `m` rows), the first row and the sign.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowBlock<'a> {
    pub c: &'a Mat6,
    pub m: usize,
    pub row: usize,
    pub sign: f64,
}

/// Adds `sign · C · (spatial columns of the frame)` into the rows
/// `row..row + m` of `jac` (D64): the in-piece block, then every ancestor's
/// `Ad_{g_world(ℓ)} S(ℓ)`.
pub(crate) fn add_frame_columns(
    tree: &Tree,
    data: &Data,
    fs: &FrameState,
    block: RowBlock,
    jac: &mut DMatrix<f64>,
) {
    let RowBlock { c, m, row, sign } = block;
    let mut put = |dof: usize, k: usize, sw: &Mat6| {
        let blk = c * sw;
        for r in 0..m {
            for col in 0..k {
                jac[(row + r, dof + col)] += sign * blk[(r, col)];
            }
        }
    };
    if let Some((node, sw)) = &fs.own {
        let nd = &tree.nodes[*node];
        put(nd.dof, nd.k, sw);
    }
    // The column of ancestor j is taken where the path leaves it (its
    // tip, or inside it: D62).
    let mut c = fs.from;
    let mut anc = fs.ancestors;
    while let Some(j) = anc {
        let nj = &tree.nodes[j];
        if nj.k > 0 {
            let sw = match c {
                Some(c) => parent_column(tree, data, c),
                None => {
                    let w = &data.nodes[j];
                    w.base_world.compose(&w.tip).ad().to_mat6() * w.s_tip
                }
            };
            put(nj.dof, nj.k, &sw);
        }
        c = Some(j);
        anc = nj.parent;
    }
}

/// Adds `S_pᵀ W` into `out` (n_prescribed) for every prescribed joint on
/// the frame's path to the root (D59, D62): the generalized force on the
/// prescribed coordinates of the world wrench `W` (spatial, at the world
/// origin, angular first) acting on the frame's node — `J_pᵀ f` of a
/// force `f` at a point `p` with `W = (p × f, f)`.
pub(crate) fn add_prescribed_wrench(
    tree: &Tree,
    data: &Data,
    fs: &FrameState,
    wrench: &Vec6,
    out: &mut [f64],
) {
    let mut c = fs.from;
    let mut anc = fs.ancestors;
    while let Some(j) = anc {
        let nj = &tree.nodes[j];
        if let (Some((o, kp)), Some(cc)) = (nj.prescribed, c) {
            let col = parent_column(tree, data, cc);
            for k in 0..kp {
                out[o + k] += col.column(k).dot(wrench);
            }
        }
        c = Some(j);
        anc = nj.parent;
    }
}

/// The first half of a point force's generalized force (CT28): the force
/// `f` \[N\] (world) at the world point `p` \[m\] of the frame `fs` — a rod
/// section (offset identity) or a body's frame — as the wrench `F` in that
/// frame's own coordinates, `(r × Rᵀf, Rᵀf)` with `r = Rᵀ(p − o)` (zero at
/// a section's centreline point: no moment arm to round). A section adds
/// its own piece's share `(T₋(x) B)ᵀ F` into `out` (n_dof) at once; the
/// wrench moved to its node's base frame, `Ad_{g(x)⁻¹}ᵀ F`, is kept in
/// `acc[node]` (per node of the tree) for [`inward_wrenches`].
pub(crate) fn add_frame_wrench(
    tree: &Tree,
    fs: &FrameState,
    p: &Vec3,
    f: &Vec3,
    acc: &mut [Vec6],
    out: &mut [f64],
) {
    let rot = &fs.pose.rotation;
    let fl = rot.tr_mul(f);
    let r = rot.tr_mul(&(p - fs.pose.translation));
    let m = r.cross(&fl);
    let wrench = Vec6::new(m.x, m.y, m.z, fl.x, fl.y, fl.z);
    match (&fs.own, &fs.local) {
        (Some((node, _)), Some((gl, sb))) => {
            let nd = &tree.nodes[*node];
            let own = sb.tr_mul(&wrench);
            for (o, v) in out[nd.dof..nd.dof + nd.k].iter_mut().zip(own.iter()) {
                *o += v;
            }
            acc[*node] += gl.ad_inv().tr_mul_vec(&wrench);
        }
        _ => {
            if let Some(from) = fs.from {
                acc[from] += wrench;
            }
        }
    }
}

/// The second half (CT28): one inward sweep, children before parents, that
/// carries the wrenches gathered in `acc` by [`add_frame_wrench`] (each in
/// its node's base frame) to the root: a node's sum, its own and its
/// subtree's, moves across its offset into the frame it hangs from (its
/// parent's tip, or a point inside the parent: D62), is projected there on
/// the parent's coordinates by `S(ℓ)ᵀ`, and moves on to the parent's base
/// frame — the articulated recursion's backward pass for forces alone.
/// Adds `Σ J_pᵀ f` into `out`: `O(N)` for all the forces together, against
/// `O(N)` per force for their dense point Jacobians. Leaves `acc` zero.
/// The node data of `data` must be the state's (any outward sweep at the
/// same `q`).
pub(crate) fn inward_wrenches(tree: &Tree, data: &Data, acc: &mut [Vec6], out: &mut [f64]) {
    for i in (0..tree.nodes.len()).rev() {
        let w = acc[i];
        if w == Vec6::zeros() {
            continue;
        }
        acc[i] = Vec6::zeros();
        let node = &tree.nodes[i];
        let Some(p) = node.parent else {
            continue;
        };
        let at = node.offset.ad_inv().tr_mul_vec(&w);
        let (pose, s) = if node.attach.is_some() {
            (&data.nodes[i].attach_pose, &data.nodes[i].attach_s)
        } else {
            (&data.nodes[p].tip, &data.nodes[p].s_tip)
        };
        let np = &tree.nodes[p];
        if np.k > 0 {
            let g = s.tr_mul(&at);
            for (o, v) in out[np.dof..np.dof + np.k].iter_mut().zip(g.iter()) {
                *o += v;
            }
        }
        acc[p] += pose.ad_inv().tr_mul_vec(&at);
    }
}

/// World poses of every rod's base frame and every body's frame into
/// `data.rod_bases`, `data.body_poses` (D51).
pub(crate) fn frames(model: &Model, tree: &Tree, data: &mut Data, q: &[f64]) {
    outward(
        model,
        tree,
        data,
        Motion::at_rest(q),
        Pass::Inverse,
        Forces::ALL,
    );
    for (r, nodes) in tree.rod_nodes.iter().enumerate() {
        data.rod_bases[r] = data.nodes[nodes[0]].base_world;
    }
    for (b, &i) in tree.body_nodes.iter().enumerate() {
        data.body_poses[b] = data.nodes[i].base_world;
    }
}
