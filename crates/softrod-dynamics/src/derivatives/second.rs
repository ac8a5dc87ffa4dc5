//! First and second derivatives of a material point's position along its
//! path to the root (docs/theory-contact.md CT12), on the tree and on the
//! chain: the point Jacobian `j_i = v_i + ω_i × p` from the spatial
//! columns `S_i = (ω_i, v_i)` of the nodes on the path, the Hessian
//! `∂²p/∂q_i∂q_l` (`ω_e × j_o` between two nodes, `e` the one nearer the
//! root; the strain derivatives of the node's `T₋` within one node, D32),
//! and `∂ṗ/∂q` from the same pieces and the frames' twists.

use crate::algorithms::frames::frame_state;
use crate::kernels::piece_derivs::{Coefficients, PieceDerivMaps};
use crate::model::Model;
use crate::model::closure::{ResolvedFrame, Target};
use crate::model::data::Data;
use crate::model::second::{Block, Col, PointPath};
use crate::model::tree::{NodeKind, Tree};
use nalgebra::DMatrix;
use softrod_kinematics::{Frame, RodKinematics};
use softrod_lie::{Mat3, Mat6, Pose, Vec3, Vec6, ad_vec, angular, exp_and_tangent_minus, linear};

fn local6(b: &Mat6, v: &[f64], dof: usize, k: usize) -> Vec6 {
    let mut x = Vec6::zeros();
    for c in 0..k {
        x += b.column(c) * v[dof + c];
    }
    x
}

fn clear(out: &mut PointPath) {
    out.blocks.clear();
    out.cols.clear();
    out.inner.clear();
    out.inner_at.clear();
    out.rotation = Mat3::identity();
    out.strain = Vec6::zeros();
    out.strain_rate = Vec6::zeros();
}

fn block(dof: usize, k: usize, pose: Pose, xi: Vec6, x: f64, bpad: Mat6, vel: Vec6) -> Block {
    Block {
        dof,
        k,
        pose,
        xi,
        x,
        bpad,
        vel,
        first: 0,
        omega_pre: Vec3::zeros(),
        pdot_frame: Vec3::zeros(),
    }
}

/// The ancestors of tree node `from` that have coordinates, into
/// `out.blocks`: each node's columns taken at its tip, or at the point
/// inside it the path's child hangs from (D62), as `add_frame_columns`
/// takes them.
fn tree_ancestors(
    model: &Model,
    tree: &Tree,
    data: &Data,
    q: &[f64],
    from: usize,
    out: &mut PointPath,
) {
    let mut c = from;
    let mut anc = tree.nodes[from].parent;
    while let Some(j) = anc {
        let nj = &tree.nodes[j];
        if nj.k > 0 {
            let wj = &data.nodes[j];
            let (pose, eta, x) = match tree.nodes[c].attach {
                Some(xa) => {
                    let wc = &data.nodes[c];
                    (wj.base_world.compose(&wc.attach_pose), wc.attach_eta, xa)
                }
                None => (
                    wj.base_world.compose(&wj.tip),
                    wj.eta_tip,
                    node_length(model, tree, j),
                ),
            };
            let xi = node_strain(model, tree, q, j);
            let vel = pose.ad().mul_vec(&eta);
            out.blocks
                .push(block(nj.dof, nj.k, pose, xi, x, nj.bpad, vel));
        }
        c = j;
        anc = nj.parent;
    }
}

fn node_length(model: &Model, tree: &Tree, j: usize) -> f64 {
    match tree.nodes[j].kind {
        NodeKind::Piece { rod, piece } => model.rods[rod].spec.geometry.pieces()[piece].length,
        _ => 1.0,
    }
}

fn node_strain(model: &Model, tree: &Tree, q: &[f64], j: usize) -> Vec6 {
    let nj = &tree.nodes[j];
    match nj.kind {
        NodeKind::Piece { rod, piece } => {
            let rm = &model.rods[rod];
            rm.spec.geometry.pieces()[piece].strain(&q[rm.dofs()])
        }
        _ => local6(&nj.bpad, q, nj.dof, nj.k),
    }
}

/// The path of the material point of rod `rod`'s section at `s` at
/// `offset` in the section's frame (zero: the centreline) on a tree model,
/// from the node data of the last outward sweep (at `(q, q̇)`). Returns the
/// point (world).
#[allow(clippy::too_many_arguments)]
pub(crate) fn tree_rod(
    model: &Model,
    data: &Data,
    q: &[f64],
    qd: Option<&[f64]>,
    rod: usize,
    s: f64,
    offset: Vec3,
    out: &mut PointPath,
) -> Vec3 {
    let tree = model.tree.as_ref().expect("a tree model");
    clear(out);
    let rm = &model.rods[rod];
    let g = &rm.spec.geometry;
    let (piece, x) = g.locate(s).expect("a contact point lies on its rod");
    let node = tree.rod_nodes[rod][piece];
    let frame = ResolvedFrame {
        target: Target::Rod {
            rod,
            piece,
            x,
            node,
        },
        offset: Pose::identity(),
    };
    let fs = frame_state(model, tree, data, &frame, q, qd);
    let nd = &tree.nodes[node];
    let pc = &g.pieces()[piece];
    let xi = pc.strain(&q[rm.dofs()]);
    out.rotation = fs.pose.rotation;
    out.strain = xi;
    out.strain_rate = qd.map_or(Vec6::zeros(), |v| pc.strain_rate(&v[rm.dofs()]));
    out.blocks
        .push(block(nd.dof, nd.k, fs.pose, xi, x, nd.bpad, fs.vel));
    tree_ancestors(model, tree, data, q, node, out);
    let p = fs.pose.transform_point(&offset);
    finish(out, p, qd);
    p
}

/// The path of the material point of body `body` at the world point `p`
/// (its frame's velocity from the last outward sweep).
pub(crate) fn tree_body(
    model: &Model,
    data: &Data,
    q: &[f64],
    qd: Option<&[f64]>,
    body: usize,
    p: Vec3,
    out: &mut PointPath,
) {
    let tree = model.tree.as_ref().expect("a tree model");
    clear(out);
    let node = tree.body_nodes[body];
    let frame = ResolvedFrame {
        target: Target::Body { node },
        offset: Pose::identity(),
    };
    let fs = frame_state(model, tree, data, &frame, q, qd);
    out.rotation = fs.pose.rotation;
    // The body's own frame carries the point but has no coordinates: a
    // block of none, for its twist.
    out.blocks.push(block(
        0,
        0,
        fs.pose,
        Vec6::zeros(),
        0.0,
        Mat6::zeros(),
        fs.vel,
    ));
    tree_ancestors(model, tree, data, q, node, out);
    finish(out, p, qd);
}

/// The path of the material point of rod `rod`'s section at `s` at
/// `offset` in the section's frame on a chain model (rods clamped to the
/// world), from the rod's kinematics updated at `(q, q̇)`. Returns the
/// point (world).
#[allow(clippy::too_many_arguments)]
pub(crate) fn chain_rod(
    model: &Model,
    kin: &RodKinematics,
    q: &[f64],
    qd: Option<&[f64]>,
    rod: usize,
    s: f64,
    offset: Vec3,
    out: &mut PointPath,
) -> Vec3 {
    clear(out);
    let rm = &model.rods[rod];
    let g = &rm.spec.geometry;
    let (piece, x) = g.locate(s).expect("a contact point lies on its rod");
    let qr = &q[rm.dofs()];
    let spatial = |s: f64| -> (Pose, Vec6) {
        let pose = kin.pose_at(g, s).expect("on the rod");
        let vel = if qd.is_some() {
            let eta = kin.velocity_at(g, s, Frame::Mixed).expect("on the rod");
            let (w, v) = (angular(&eta), linear(&eta));
            softrod_lie::join(&w, &(v - w.cross(&pose.translation)))
        } else {
            Vec6::zeros()
        };
        (pose, vel)
    };
    let pieces = g.pieces();
    let add = |j: usize, at: f64, xj: f64, out: &mut PointPath| {
        let pc = &pieces[j];
        let (pose, vel) = spatial(at);
        let xi = pc.strain(qr);
        let bpad = super::point::basis6(&pc.basis);
        out.blocks.push(block(
            rm.dof_offset + pc.dof_offset,
            pc.basis.dof(),
            pose,
            xi,
            xj,
            bpad,
            vel,
        ));
    };
    add(piece, s, x, out);
    let pc = &pieces[piece];
    out.rotation = out.blocks[0].pose.rotation;
    out.strain = pc.strain(qr);
    out.strain_rate = qd.map_or(Vec6::zeros(), |v| pc.strain_rate(&v[rm.dofs()]));
    for j in (0..piece).rev() {
        add(j, pieces[j].end(), pieces[j].length, out);
    }
    let p = out.blocks[0].pose.transform_point(&offset);
    finish(out, p, qd);
    p
}

/// The columns, the in-node second derivatives and the frames' motion of
/// a path whose blocks are set (CT12).
fn finish(out: &mut PointPath, p: Vec3, qd: Option<&[f64]>) {
    out.p = p;
    let point_of = |vel: &Vec6| linear(vel) + angular(vel).cross(&p);
    out.pdot = out
        .blocks
        .first()
        .map_or(Vec3::zeros(), |b| point_of(&b.vel));
    let mut tb = [Vec6::zeros(); 6];
    for bi in 0..out.blocks.len() {
        let b = out.blocks[bi];
        let ad = b.pose.ad();
        let first = out.cols.len();
        let mut own = Vec6::zeros();
        let tm = if b.k > 0 {
            exp_and_tangent_minus(b.x, &b.xi).1
        } else {
            softrod_lie::AdOp::ad(&Vec6::zeros())
        };
        for l in 0..b.k {
            tb[l] = tm.mul_vec(&b.bpad.column(l).into_owned());
            let sw = ad.mul_vec(&tb[l]);
            let (w, v) = (angular(&sw), linear(&sw));
            out.cols.push(Col {
                dof: b.dof + l,
                block: bi,
                w,
                j: v + w.cross(&p),
            });
            if let Some(qd) = qd {
                own += sw * qd[b.dof + l];
            }
        }
        out.blocks[bi].first = first;
        out.blocks[bi].omega_pre = angular(&b.vel) - angular(&own);
        out.blocks[bi].pdot_frame = point_of(&b.vel);
        // In-node: ∂S_i/∂q_l = Ad_G(ad_{T B_l} T B_i + D_ξT₋[B_l] B_i)
        // (the frame's body twist per unit rate of q_l is T B_l), then
        // ∂j_i/∂q_l = ∂v_i + ∂ω_i × p + ω_i × j_l.
        out.inner_at.push(out.inner.len());
        let zero = Vec6::zeros();
        for i in 0..b.k {
            let bi6 = b.bpad.column(i).into_owned();
            let dm = PieceDerivMaps::new(&b.xi, &bi6, &zero);
            let co = Coefficients::at(b.x, dm.theta);
            let m = dm.d_tangent_applied(&co, false);
            for l in 0..b.k {
                let d = ad.mul_vec(&(ad_vec(&tb[l], &tb[i]) + m * b.bpad.column(l)));
                let (ci, cl) = (out.cols[first + i], out.cols[first + l]);
                out.inner
                    .push(linear(&d) + angular(&d).cross(&p) + ci.w.cross(&cl.j));
            }
        }
    }
}

impl PointPath {
    /// `∂²p/∂q_i∂q_l` of the path's columns `i`, `l` (CT12).
    #[inline]
    pub(crate) fn hessian(&self, i: usize, l: usize) -> Vec3 {
        let (ci, cl) = (&self.cols[i], &self.cols[l]);
        if ci.block == cl.block {
            let b = &self.blocks[ci.block];
            self.inner[self.inner_at[ci.block] + (i - b.first) * b.k + (l - b.first)]
        } else if ci.block > cl.block {
            // i nearer the root: turning it turns j_l.
            ci.w.cross(&cl.j)
        } else {
            cl.w.cross(&ci.j)
        }
    }

    /// `∂ṗ/∂q_i` of column `i` at the rates `qd` (CT12): the frame above
    /// its node turns `j_i`, `j_i`'s rotation carries what moves below it,
    /// and the node's own rates through its Hessian.
    pub(crate) fn velocity_derivative(&self, i: usize, qd: &[f64]) -> Vec3 {
        let c = &self.cols[i];
        let b = &self.blocks[c.block];
        let mut out = b.omega_pre.cross(&c.j) + c.w.cross(&(self.pdot - b.pdot_frame));
        for l in 0..b.k {
            out += self.hessian(i, b.first + l) * qd[b.dof + l];
        }
        out
    }

    /// Fills `sorted`: the column indices in increasing coordinate order
    /// (blocks run from the point's node to the root, each block's
    /// coordinates increasing; a node's coordinates follow its parent's).
    pub(crate) fn sorted_columns(&mut self) {
        self.sorted.clear();
        self.sorted.extend(0..self.cols.len());
        let cols = &self.cols;
        self.sorted.sort_unstable_by_key(|&c| cols[c].dof);
    }

    /// Adds `sign · J` (3 × n) into `out`.
    pub(crate) fn add_jacobian(&self, sign: f64, out: &mut DMatrix<f64>) {
        for c in &self.cols {
            for r in 0..3 {
                out[(r, c.dof)] += sign * c.j[r];
            }
        }
    }

    /// Adds `sign · J_ω` (3 × n, the angular rows) into `out`.
    pub(crate) fn add_angular(&self, sign: f64, out: &mut DMatrix<f64>) {
        for c in &self.cols {
            for r in 0..3 {
                out[(r, c.dof)] += sign * c.w[r];
            }
        }
    }

    /// Adds `sign · ∂ṗ/∂q` (3 × n) into `out`.
    pub(crate) fn add_velocity_derivative(&self, qd: &[f64], sign: f64, out: &mut DMatrix<f64>) {
        for i in 0..self.cols.len() {
            let a = self.velocity_derivative(i, qd);
            let d = self.cols[i].dof;
            for r in 0..3 {
                out[(r, d)] += sign * a[r];
            }
        }
    }

    /// Adds `sign · f·∂²p/∂q∂q` (n × n) into `m`, the geometric term
    /// (CT6): between two nodes `f·(ω_e × j_o) = ω_e·(j_o × f)`, one dot
    /// product per entry with `j_o × f` formed once per column.
    pub(crate) fn add_hessian_contraction(&mut self, f: &Vec3, sign: f64, m: &mut DMatrix<f64>) {
        let n = m.nrows();
        let mut u = std::mem::take(&mut self.scratch);
        u.clear();
        u.extend(self.cols.iter().map(|c| c.j.cross(f) * sign));
        let out = m.as_mut_slice();
        for (l, cl) in self.cols.iter().enumerate() {
            let col = cl.dof * n;
            for (i, ci) in self.cols.iter().enumerate() {
                let v = if ci.block == cl.block {
                    sign * f.dot(&self.hessian(i, l))
                } else if ci.block > cl.block {
                    ci.w.dot(&u[l])
                } else {
                    cl.w.dot(&u[i])
                };
                out[col + ci.dof] += v;
            }
        }
        self.scratch = u;
    }

    /// Adds `sign · ∂t/∂q` (3 × n) of the tangent `t = R ν` of a rod
    /// point's section into `out`: `ω_l × t` for every column, plus
    /// `R (B_l)_ν` for the point's own piece (CT13).
    pub(crate) fn add_tangent_derivative(&self, sign: f64, out: &mut DMatrix<f64>) {
        let t = self.tangent();
        let own = &self.blocks[0];
        for (i, c) in self.cols.iter().enumerate() {
            let mut d = c.w.cross(&t);
            if c.block == 0 {
                d += self.rotation * linear(&own.bpad.column(i - own.first).into_owned());
            }
            for r in 0..3 {
                out[(r, c.dof)] += sign * d[r];
            }
        }
    }

    /// The tangent `∂p/∂s = R ν` of a rod point (CT8).
    pub(crate) fn tangent(&self) -> Vec3 {
        self.rotation * linear(&self.strain)
    }

    /// `∂t/∂s = R (k × ν)` within the point's piece (CT13).
    pub(crate) fn curvature(&self) -> Vec3 {
        self.rotation * angular(&self.strain).cross(&linear(&self.strain))
    }

    /// `ṫ = ω × t + R ν̇` (CT13).
    pub(crate) fn tangent_rate(&self) -> Vec3 {
        let w = self
            .blocks
            .first()
            .map_or(Vec3::zeros(), |b| angular(&b.vel));
        w.cross(&self.tangent()) + self.rotation * linear(&self.strain_rate)
    }
}
