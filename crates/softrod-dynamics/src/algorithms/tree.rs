//! The algorithms on the tree of an articulated model (docs/theory.md §11,
//! D54–D58): the same recursions as the chain path (D17–D27) with a node's
//! children summed at its tip, joints as massless unit pieces and bodies as
//! single rigid inertias. Dense 6×6 arithmetic per node (no block tricks):
//! the chain path of joint-free models is untouched.

use super::frames::parent_column;
use super::{Motion, Pass};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::forces::external::{external_density, world_acceleration};
use crate::forces::strain::{joint_forces, strain_forces};
use crate::kernels::inertia::{FullSums, PointInertia};
use crate::model::Model;
use crate::model::data::Data;
use crate::model::tree::{NodeKind, Tree};
use softrod_lie::{Mat6, PieceMaps, Pose, Vec6, ad_vec, coad_vec};

/// `q_n` (or a rate) of a node, zero-padded to 6.
#[inline]
pub(crate) fn local(v: &[f64], dof: usize, k: usize) -> Vec6 {
    Vec6::from_fn(|i, _| if i < k { v[dof + i] } else { 0.0 })
}

/// The outward sweep over the nodes (D7–D10, D54): poses, velocities,
/// accelerations (inverse), and per node what `pass` needs.
///
/// Prescribed joints (D59) take their coordinates from
/// `data.prescribed_q`, their rates when `qd` is given and their
/// accelerations in the dynamics passes (neither when `forces` holds them
/// at rest, nor for gravity alone); the
/// prescribed acceleration is folded into the node's tip acceleration
/// `acc_tip`, so the recursions treat the node as one without coordinates.
///
/// Returns the kinetic energy `½Σ w ηᵀ𝓜η` (points and bodies) for an
/// `Inverse` pass with `qd` and without `qdd` (what [`energies`] asks), else
/// zero.
pub(crate) fn outward(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    motion: Motion,
    pass: Pass,
    forces: Forces,
) -> f64 {
    outward_from(model, tree, data, motion, pass, forces, 0)
}

/// [`outward`] over the nodes `from..` only: the nodes before `from` keep
/// what the last sweep left (valid when `motion` differs from that sweep's
/// only in coordinates of nodes `from..`, whose descendants come after
/// them in the tree's order). The kinetic energy is of those nodes.
pub(crate) fn outward_from(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    motion: Motion,
    pass: Pass,
    forces: Forces,
    from: usize,
) -> f64 {
    let Motion { q, qd, qdd } = motion;
    let scale = forces.load_scale;
    let only_gravity = forces.gravity_only;
    let want_kinetic = pass == Pass::Inverse && qd.is_some() && qdd.is_none();
    let mut kinetic = 0.0;
    let moving = forces.drives_move();
    let drive_rates = qd.is_some() && moving;
    let drive_acc = moving && pass != Pass::Composite;
    let a_world = if pass == Pass::Inverse {
        world_acceleration(model, scale)
    } else {
        Vec6::zeros()
    };
    let has_vel = qd.is_some();
    for (i, node) in tree.nodes.iter().enumerate().skip(from) {
        // A prescribed joint's acceleration `T₋(1)Bq̈_p`, added to its tip's.
        let mut drive = Vec6::zeros();
        let (parent_pose, eta_p, etadot_p) = match node.parent {
            Some(p) if node.attach.is_some() => {
                let w = &data.nodes[i];
                (
                    data.nodes[p].base_world.compose(&w.attach_pose),
                    w.attach_eta,
                    w.attach_etadot,
                )
            }
            Some(p) => {
                let w = &data.nodes[p];
                (w.base_world.compose(&w.tip), w.eta_tip, w.etadot_tip)
            }
            None => (Pose::identity(), Vec6::zeros(), a_world),
        };
        let x = node.offset.ad_inv();
        let eta_b = x.mul_vec(&eta_p);
        let etadot_b = x.mul_vec(&etadot_p);
        let base_world = parent_pose.compose(&node.offset);
        let w = &mut data.nodes[i];
        w.base_world = base_world;
        w.mt = Mat6::zeros();
        w.ut = Mat6::zeros();
        w.dt = Mat6::zeros();
        w.p_big = Vec6::zeros();
        w.p_small = Vec6::zeros();
        let k = node.k;
        let mut ps6 = Vec6::zeros();
        // (ξ, ξ̇, ξ̈, piece length) of a piece-like node; bodies apart.
        let (xi, dxi, ddxi, length) = match node.kind {
            NodeKind::Body { body } => {
                let bm = &model.bodies[body];
                let m = &bm.inertia;
                let mut f = coad_vec(&eta_b, &(m * eta_b));
                if pass == Pass::Inverse {
                    f += m * etadot_b;
                }
                if !only_gravity && pass != Pass::Composite {
                    for l in &bm.spec.loads {
                        f -= l.wrench(&base_world) * scale;
                    }
                }
                if want_kinetic {
                    kinetic += 0.5 * eta_b.dot(&(m * eta_b));
                }
                w.p_big = f;
                w.mt = *m;
                w.tip = Pose::identity();
                w.s_tip = Mat6::zeros();
                w.acc_tip = Vec6::zeros();
                w.eta_tip = eta_b;
                w.etadot_tip = etadot_b;
                if pass == Pass::Composite {
                    w.s_world = Mat6::zeros();
                }
                continue;
            }
            NodeKind::Joint { .. } => {
                let b = &node.bpad;
                if let Some((o, kp)) = node.prescribed {
                    let rates = if drive_rates {
                        b * local(data.prescribed_qd.as_slice(), o, kp)
                    } else {
                        Vec6::zeros()
                    };
                    if drive_acc {
                        drive = b * local(data.prescribed_qdd.as_slice(), o, kp);
                    }
                    (
                        b * local(data.prescribed_q.as_slice(), o, kp),
                        rates,
                        Vec6::zeros(),
                        1.0,
                    )
                } else {
                    (
                        b * local(q, node.dof, k),
                        qd.map_or(Vec6::zeros(), |v| b * local(v, node.dof, k)),
                        qdd.map_or(Vec6::zeros(), |v| b * local(v, node.dof, k)),
                        1.0,
                    )
                }
            }
            NodeKind::Piece { rod, piece } => {
                let rm = &model.rods[rod];
                let pc = &rm.spec.geometry.pieces()[piece];
                let r = rm.dofs();
                (
                    pc.strain(&q[r.clone()]),
                    qd.map_or(Vec6::zeros(), |v| pc.strain_rate(&v[r.clone()])),
                    qdd.map_or(Vec6::zeros(), |v| pc.strain_rate(&v[r.clone()])),
                    pc.length,
                )
            }
        };
        let maps = PieceMaps::new(&xi, has_vel.then_some(&dxi));
        if let (&NodeKind::Piece { rod, piece }, false) = (&node.kind, pass == Pass::Kinematic) {
            let rm = &model.rods[rod];
            let pd = &rm.pieces[piece];
            let has_ext =
                !only_gravity && (rm.spec.drag.is_some() || !rm.spec.distributed_loads.is_empty());
            // The chain path's block sums (crate::kernels::inertia): 𝓤ᶠ, 𝓓ᶠ on the full
            // T₋ projected once per piece, 𝓜ᵗ in spatial-inertia form.
            let mut fs = FullSums::new(
                pd.points
                    .iter()
                    .all(|p| p.inertia[3] == p.inertia[4] && p.inertia[3] == p.inertia[5]),
                maps.theta_squared() * (length * length),
            );
            let mut pi = PointInertia::default();
            for qp in &pd.points {
                let (gl, tm, dbias, ta) = maps.eval_with_ta(qp.x);
                let a = gl.ad_inv();
                let m = &qp.inertia;
                if pass != Pass::Composite {
                    let carried = a.mul_vec(&eta_b);
                    let sv = tm.mul_vec(&dxi);
                    let eta = carried + sv;
                    let bias = if has_vel {
                        ad_vec(&carried, &sv) + dbias
                    } else {
                        Vec6::zeros()
                    };
                    if want_kinetic {
                        kinetic += 0.5 * qp.w * eta.dot(&m.component_mul(&eta));
                    }
                    let mut f = coad_vec(&eta, &m.component_mul(&eta));
                    f += if pass == Pass::Inverse {
                        let etadot = a.mul_vec(&etadot_b) + tm.mul_vec(&ddxi) + bias;
                        m.component_mul(&etadot)
                    } else {
                        m.component_mul(&bias)
                    };
                    if has_ext {
                        f -= external_density(rm, scale, &base_world.compose(&gl), &eta);
                    }
                    let fw = f * qp.w;
                    w.p_big += a.tr_mul_vec(&fw);
                    ps6 += tm.tr_mul_vec(&fw);
                }
                if pass != Pass::Inverse {
                    let mw = m * qp.w;
                    fs.add(&gl, &tm, &mw, &ta, maps.theta_squared());
                    pi.add(&gl, &mw);
                }
            }
            if pass != Pass::Inverse {
                fs.project(
                    &maps,
                    &rm.spec.geometry.pieces()[piece].basis,
                    &mut w.ut,
                    &mut w.dt,
                );
                w.mt = pi.finish().dense();
            }
            if pass != Pass::Composite && !only_gravity {
                for pl in &pd.loads {
                    let load = &rm.spec.point_loads[pl.index];
                    let (gl, tm) = maps.exp_and_tangent_minus(pl.x);
                    let f = load.wrench(&base_world.compose(&gl)) * scale;
                    w.p_big -= gl.ad_inv().tr_mul_vec(&f);
                    ps6 -= tm.tr_mul_vec(&f);
                }
            }
        }
        w.p_small = node.bpad.tr_mul(&ps6);
        // Children hanging inside this piece (D62): the frame at x.
        for &c in &tree.inner_children[i] {
            let x = tree.nodes[c].attach.unwrap_or(length);
            let (gl, tm, dbias) = maps.eval(x);
            let a = gl.ad_inv();
            let carried = a.mul_vec(&eta_b);
            let sv = tm.mul_vec(&dxi);
            let acc = if has_vel {
                ad_vec(&carried, &sv) + dbias
            } else {
                Vec6::zeros()
            };
            let wc = &mut data.nodes[c];
            wc.attach_pose = gl;
            wc.attach_a = a.to_mat6();
            wc.attach_s = tm.to_mat6() * node.bpad;
            wc.attach_acc = acc;
            wc.attach_eta = carried + sv;
            wc.attach_etadot = a.mul_vec(&etadot_b) + tm.mul_vec(&ddxi) + acc;
        }
        let w = &mut data.nodes[i];
        let (gl, tm, dbias) = maps.eval(length);
        let a = gl.ad_inv();
        let carried = a.mul_vec(&eta_b);
        let sv = tm.mul_vec(&dxi);
        let mut acc = if has_vel {
            ad_vec(&carried, &sv) + dbias
        } else {
            Vec6::zeros()
        };
        if node.prescribed.is_some() {
            acc += tm.mul_vec(&drive);
        }
        w.tip = gl;
        w.s_tip = tm.to_mat6() * node.bpad;
        w.acc_tip = acc;
        w.eta_tip = carried + sv;
        w.etadot_tip = a.mul_vec(&etadot_b) + tm.mul_vec(&ddxi) + acc;
        if pass == Pass::Composite {
            w.s_world = base_world.compose(&gl).ad().to_mat6() * w.s_tip;
        }
    }
    kinetic
}

/// Inverse dynamics on the tree (D17–D18 with children summed at the tip,
/// D55). Result in `data.tau`.
pub(crate) fn inverse_dynamics(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    forces: Forces,
    t: f64,
    motion: Motion,
) {
    let Motion { q, qd, .. } = motion;
    outward(model, tree, data, motion, Pass::Inverse, forces);
    strain_forces(model, data, forces, t, q, qd, None);
    joint_forces(model, data, forces, t, q, qd);
    for w in &mut data.nodes {
        w.f_tip = Vec6::zeros();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let w = &data.nodes[i];
        let v = w.p_small + w.s_tip.tr_mul(&w.f_tip);
        for c in 0..node.k {
            data.tau[node.dof + c] = v[c];
        }
        if let Some((o, kp)) = node.prescribed {
            for c in 0..kp {
                data.prescribed_force[o + c] = v[c];
            }
        }
        let wb = w.p_big + w.tip.ad_inv().tr_mul_vec(&w.f_tip);
        if let Some(p) = node.parent {
            let wx = node.offset.ad_inv().tr_mul_vec(&wb);
            if node.attach.is_some() {
                // Into the parent piece at x, like a point load (D62).
                let (a, sx) = (w.attach_a, w.attach_s);
                let pw = &mut data.nodes[p];
                pw.p_big += a.transpose() * wx;
                pw.p_small += sx.transpose() * wx;
            } else {
                data.nodes[p].f_tip += wx;
            }
        }
    }
    data.tau -= &data.strain_force;
}

/// `D̂⁻¹` of a `k×k` block padded to 6×6 (zeros outside), or `None` if not
/// positive definite.
pub(crate) fn inverse_k(d: &Mat6, k: usize) -> Option<Mat6> {
    let padded = Mat6::from_fn(|i, j| {
        if i < k && j < k {
            0.5 * (d[(i, j)] + d[(j, i)])
        } else if i == j {
            1.0
        } else {
            0.0
        }
    });
    let inv = padded.cholesky()?.inverse();
    Some(Mat6::from_fn(|i, j| {
        if i < k && j < k { inv[(i, j)] } else { 0.0 }
    }))
}

/// O(N) forward dynamics on the tree: the articulated-body recursion of
/// (D24–D27) with the children's articulated inertias and biases summed at
/// each tip (D56). Result in `data.qdd`.
pub(crate) fn forward_dynamics(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    forces: Forces,
    t: f64,
    motion: Motion,
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    let Motion { q, qd, .. } = motion;
    outward(model, tree, data, motion, Pass::Articulated, forces);
    strain_forces(model, data, forces, t, q, qd, tau_act);
    joint_forces(model, data, forces, t, q, qd);
    for w in &mut data.nodes {
        w.m_tip = Mat6::zeros();
        w.f_tip = Vec6::zeros();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let k = node.k;
        let sf = local(data.strain_force.as_slice(), node.dof, k);
        let w = &mut data.nodes[i];
        let a = w.tip.ad_inv().to_mat6();
        let ma = w.m_tip;
        let mas = ma * w.s_tip;
        let uhat = w.ut + a.transpose() * mas;
        let dhat = w.dt + w.s_tip.transpose() * mas;
        let y = ma * w.acc_tip + w.f_tip;
        let u = sf - w.p_small - w.s_tip.tr_mul(&y);
        let u = Vec6::from_fn(|r, _| if r < k { u[r] } else { 0.0 });
        let dinv = if k > 0 {
            inverse_k(&dhat, k).ok_or_else(|| DynamicsError::SingularNode {
                node: tree.describe(model, i),
                what: "articulated inertia D̂",
            })?
        } else {
            Mat6::zeros()
        };
        let ud = uhat * dinv;
        let mb = w.mt + a.transpose() * ma * a - ud * uhat.transpose();
        let pb = w.p_big + a.transpose() * y + ud * u;
        w.uhat = uhat;
        // The mass matrix is symmetric: `tree_solve` reads `Û_L = Û`.
        w.uhat_l = uhat;
        w.dinv = dinv;
        w.u = u;
        if let Some(p) = node.parent {
            let x = node.offset.ad_inv().to_mat6();
            let (mx, px) = (x.transpose() * mb * x, x.transpose() * pb);
            if node.attach.is_some() {
                // A rigid articulated inertia inside the parent piece at x
                // (D62): it joins the piece's own sums (D20, D23).
                let (a, sx, acc) = (w.attach_a, w.attach_s, w.attach_acc);
                let y = mx * acc + px;
                let pw = &mut data.nodes[p];
                let ma = mx * a;
                pw.mt += a.transpose() * ma;
                pw.ut += a.transpose() * mx * sx;
                pw.dt += sx.transpose() * mx * sx;
                pw.p_big += a.transpose() * y;
                pw.p_small += sx.transpose() * y;
            } else {
                let pw = &mut data.nodes[p];
                pw.m_tip += mx;
                pw.f_tip += px;
            }
        }
    }
    let a_world = world_acceleration(model, forces.load_scale);
    for (i, node) in tree.nodes.iter().enumerate() {
        let etadot_p = match node.parent {
            Some(p) if node.attach.is_some() => {
                let (pw, w) = (&data.nodes[p], &data.nodes[i]);
                w.attach_a * pw.etadot_base + w.attach_s * pw.qn + w.attach_acc
            }
            Some(p) => data.nodes[p].etadot_tip,
            None => a_world,
        };
        let etadot_b = node.offset.ad_inv().mul_vec(&etadot_p);
        let w = &mut data.nodes[i];
        let qn = w.dinv * (w.u - w.uhat.tr_mul(&etadot_b));
        w.etadot_base = etadot_b;
        w.qn = qn;
        for c in 0..node.k {
            data.qdd[node.dof + c] = qn[c];
        }
        w.etadot_tip = w.tip.ad_inv().mul_vec(&etadot_b) + w.s_tip * qn + w.acc_tip;
        if let Some((o, kp)) = node.prescribed {
            // What the joint transmits to its child: 𝓜ᴬη̇ + 𝓟ᴬ at its tip,
            // projected on its motion subspace (D59).
            let f = w.p_small + w.s_tip.tr_mul(&(w.m_tip * w.etadot_tip + w.f_tip));
            for c in 0..kp {
                data.prescribed_force[o + c] = f[c];
            }
        }
    }
    Ok(())
}

/// Mass matrix on the tree by the composite recursion (D20, D57): for node
/// `i`, `M_ii = 𝓓 + S(ℓ)ᵀ𝓜ᶜS(ℓ)` and, for every ancestor `j` with
/// coordinates, `M_ji = (Ad_{g_j(ℓ)}S_j(ℓ))ᵀ Ad*_{g_i(0)⁻¹}F_i` with
/// `F_i = 𝓤 + A_ℓᵀ𝓜ᶜS(ℓ)` — the motion of an ancestor moves `i`'s base
/// rigidly. Nodes off each other's paths to the root do not couple.
pub(crate) fn mass_matrix(model: &Model, tree: &Tree, data: &mut Data, q: &[f64]) {
    outward(
        model,
        tree,
        data,
        Motion::at_rest(q),
        Pass::Composite,
        Forces::ALL,
    );
    let n = model.n_dof();
    if data.mass.nrows() != n {
        data.mass = nalgebra::DMatrix::zeros(n, n);
    }
    data.mass.fill(0.0);
    for w in &mut data.nodes {
        w.m_tip = Mat6::zeros();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let k = node.k;
        let w = &data.nodes[i];
        let a = w.tip.ad_inv().to_mat6();
        let mc = w.m_tip;
        let mcs = mc * w.s_tip;
        let f = w.ut + a.transpose() * mcs;
        let mii = w.dt + w.s_tip.transpose() * mcs;
        let mb = w.mt + a.transpose() * mc * a;
        for r in 0..k {
            for c in 0..k {
                data.mass[(node.dof + r, node.dof + c)] = mii[(r, c)];
            }
        }
        if k > 0 {
            let f_world = w.base_world.ad_inv().to_mat6().transpose() * f;
            // Walk to the root; the column of ancestor j is taken where the
            // path leaves it (its tip, or inside it, D62).
            let mut c = i;
            let mut anc = node.parent;
            while let Some(j) = anc {
                let nj = &tree.nodes[j];
                if nj.k > 0 {
                    let col = if tree.nodes[c].attach.is_some() {
                        parent_column(tree, data, c)
                    } else {
                        data.nodes[j].s_world
                    };
                    let blk = col.transpose() * f_world;
                    for r in 0..nj.k {
                        for c in 0..k {
                            data.mass[(nj.dof + r, node.dof + c)] = blk[(r, c)];
                            data.mass[(node.dof + c, nj.dof + r)] = blk[(r, c)];
                        }
                    }
                }
                c = j;
                anc = nj.parent;
            }
        }
        if let Some(p) = node.parent {
            let x = node.offset.ad_inv().to_mat6();
            let mx = x.transpose() * mb * x;
            if node.attach.is_some() {
                let (a, sx) = (data.nodes[i].attach_a, data.nodes[i].attach_s);
                let pw = &mut data.nodes[p];
                pw.mt += a.transpose() * mx * a;
                pw.ut += a.transpose() * mx * sx;
                pw.dt += sx.transpose() * mx * sx;
            } else {
                data.nodes[p].m_tip += mx;
            }
        }
    }
}
