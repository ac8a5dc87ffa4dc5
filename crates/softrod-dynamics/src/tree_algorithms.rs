//! The algorithms on the tree of an articulated model (docs/theory.md §11,
//! D54–D58): the same recursions as the chain path (D17–D27) with a node's
//! children summed at its tip, joints as massless unit pieces and bodies as
//! single rigid inertias. Dense 6×6 arithmetic per node (no block tricks):
//! the chain path of joint-free models is untouched.

use crate::energy::Energies;
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::forces::external::{external_density, world_acceleration};
use crate::forces::strain::{joint_forces, strain_forces};
use crate::kernels::inertia::{FullSums, PointInertia};
use crate::model::Model;
use crate::model::data::{Data, SolveNode};
use crate::model::tree::{NodeKind, Tree};
use softrod_lie::{Mat6, PieceMaps, Pose, Vec6, ad_vec, coad_vec};
use softrod_mechanics::elastic_energy;

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

/// What the outward sweep accumulates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TreePass {
    /// Inverse dynamics: `f = 𝓜η̇ + ad*_η𝓜η − 𝓕_ext` with `q̈` given.
    Inverse,
    /// Forward dynamics: inertia sums and `h = 𝓜a + ad*_η𝓜η − 𝓕_ext`.
    Articulated,
    /// Mass matrix: inertia sums only, at rest.
    Composite,
}

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
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
    pass: TreePass,
    forces: Forces,
) -> f64 {
    let scale = forces.load_scale;
    let only_gravity = forces.gravity_only;
    let want_kinetic = pass == TreePass::Inverse && qd.is_some() && qdd.is_none();
    let mut kinetic = 0.0;
    let moving = forces.drives_move();
    let drive_rates = qd.is_some() && moving;
    let drive_acc = moving && pass != TreePass::Composite;
    let a_world = if pass == TreePass::Inverse {
        world_acceleration(model, scale)
    } else {
        Vec6::zeros()
    };
    let has_vel = qd.is_some();
    for (i, node) in tree.nodes.iter().enumerate() {
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
                if pass == TreePass::Inverse {
                    f += m * etadot_b;
                }
                if !only_gravity && pass != TreePass::Composite {
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
                if pass == TreePass::Composite {
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
                let pc = &rm.spec.rod.pieces()[piece];
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
        if let NodeKind::Piece { rod, piece } = node.kind {
            let rm = &model.rods[rod];
            let pd = &rm.pieces[piece];
            let has_ext =
                !only_gravity && (rm.spec.drag.is_some() || !rm.spec.distributed_loads.is_empty());
            // The chain path's block sums (crate::passes): 𝓤ᶠ, 𝓓ᶠ on the full
            // T₋ projected once per piece, 𝓜ᵗ in spatial-inertia form.
            let mut fs = FullSums::new(
                pd.points
                    .iter()
                    .all(|p| p.inertia[3] == p.inertia[4] && p.inertia[3] == p.inertia[5]),
            );
            let mut pi = PointInertia::default();
            for qp in &pd.points {
                let (gl, tm, dbias) = maps.eval(qp.x);
                let a = gl.ad_inv();
                let m = &qp.inertia;
                if pass != TreePass::Composite {
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
                    f += if pass == TreePass::Inverse {
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
                if pass != TreePass::Inverse {
                    let mw = m * qp.w;
                    fs.add(&gl, &tm, &mw);
                    pi.add(&gl, &mw);
                }
            }
            if pass != TreePass::Inverse {
                fs.project(&rm.spec.rod.pieces()[piece].basis, &mut w.ut, &mut w.dt);
                w.mt = pi.finish().dense();
            }
            if pass != TreePass::Composite && !only_gravity {
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
        if pass == TreePass::Composite {
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
    q: &[f64],
    qd: Option<&[f64]>,
    qdd: Option<&[f64]>,
) {
    outward(model, tree, data, q, qd, qdd, TreePass::Inverse, forces);
    strain_forces(model, data, forces, t, q, qd, None);
    joint_forces(model, data, forces, q, qd);
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
fn inverse_k(d: &Mat6, k: usize) -> Option<Mat6> {
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
    q: &[f64],
    qd: &[f64],
    tau_act: Option<&[f64]>,
) -> Result<(), DynamicsError> {
    outward(
        model,
        tree,
        data,
        q,
        Some(qd),
        None,
        TreePass::Articulated,
        forces,
    );
    strain_forces(model, data, forces, t, q, Some(qd), tau_act);
    joint_forces(model, data, forces, q, Some(qd));
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

/// The factorization of `S = M(q) + a·K + b·D` on the tree
/// (docs/theory-derivatives.md §6 on the recursion of D56): the
/// articulated inward pass of [`forward_dynamics`] without biases, with the
/// armature `a·K_n + b·D_n` of each node added to its `D̂` — a piece's
/// `K_n`, `D_n` (D13), a joint's spring and damper constants (D53), nothing
/// for bodies and prescribed joints. Leaves `Û`, `D̂⁻¹` per node in `data`;
/// prescribed joints at `data.prescribed_q` (their last [`Model::set_time`]).
pub(crate) fn shifted_factor(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q: &[f64],
    a: f64,
    b: f64,
) -> Result<(), DynamicsError> {
    outward(
        model,
        tree,
        data,
        q,
        None,
        None,
        TreePass::Composite,
        Forces::ALL,
    );
    for w in &mut data.nodes {
        w.m_tip = Mat6::zeros();
    }
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let k = node.k;
        let w = &mut data.nodes[i];
        let am = w.tip.ad_inv().to_mat6();
        let ma = w.m_tip;
        let mas = ma * w.s_tip;
        let uhat = w.ut + am.transpose() * mas;
        let mut dhat = w.dt + w.s_tip.transpose() * mas;
        match node.kind {
            NodeKind::Piece { rod, piece } => {
                let pd = &model.rods[rod].pieces[piece];
                if a != 0.0 {
                    dhat += pd.stiffness6 * a;
                }
                if b != 0.0 && pd.has_damping {
                    dhat += pd.damping6 * b;
                }
            }
            NodeKind::Joint { element } => {
                let joint = &model.elements[element].attachment.joint;
                for c in 0..k {
                    let (kc, dc, _) = joint.coefficients(c);
                    dhat[(c, c)] += a * kc + b * dc;
                }
            }
            NodeKind::Body { .. } => {}
        }
        let dinv = if k > 0 {
            inverse_k(&dhat, k).ok_or_else(|| DynamicsError::SingularNode {
                node: tree.describe(model, i),
                what: "shifted articulated block D̂ + aK + bD",
            })?
        } else {
            Mat6::zeros()
        };
        let ud = uhat * dinv;
        let mb = w.mt + am.transpose() * ma * am - ud * uhat.transpose();
        w.uhat = uhat;
        w.dinv = dinv;
        if let Some(p) = node.parent {
            let x = node.offset.ad_inv().to_mat6();
            let mx = x.transpose() * mb * x;
            if node.attach.is_some() {
                let (ax, sx) = (w.attach_a, w.attach_s);
                let pw = &mut data.nodes[p];
                pw.mt += ax.transpose() * mx * ax;
                pw.ut += ax.transpose() * mx * sx;
                pw.dt += sx.transpose() * mx * sx;
            } else {
                data.nodes[p].m_tip += mx;
            }
        }
    }
    Ok(())
}

/// `x ← S⁻¹x` with the factorization of [`shifted_factor`] in `data`: the
/// bias-free inward (D26) and outward (D27) sweeps of the tree, the
/// children's wrenches summed at each tip or at their point inside the
/// parent piece (D62). O(N).
pub(crate) fn shifted_solve(tree: &Tree, data: &Data, scratch: &mut [SolveNode], x: &mut [f64]) {
    scratch.fill(SolveNode::default());
    for (i, node) in tree.nodes.iter().enumerate().rev() {
        let k = node.k;
        let w = &data.nodes[i];
        let sc = scratch[i];
        let y = sc.f_tip;
        let xs = local(x, node.dof, k);
        let u = xs - sc.p_small - w.s_tip.tr_mul(&y);
        let u = Vec6::from_fn(|r, _| if r < k { u[r] } else { 0.0 });
        let pb = sc.p_big + w.tip.ad_inv().tr_mul_vec(&y) + w.uhat * (w.dinv * u);
        scratch[i].u = u;
        if let Some(p) = node.parent {
            let px = node.offset.ad_inv().tr_mul_vec(&pb);
            if node.attach.is_some() {
                let sp = &mut scratch[p];
                sp.p_big += w.attach_a.transpose() * px;
                sp.p_small += w.attach_s.transpose() * px;
            } else {
                scratch[p].f_tip += px;
            }
        }
    }
    for (i, node) in tree.nodes.iter().enumerate() {
        let w = &data.nodes[i];
        let etadot_p = match node.parent {
            Some(p) if node.attach.is_some() => {
                w.attach_a * scratch[p].etadot_base + w.attach_s * scratch[p].qn
            }
            Some(p) => scratch[p].etadot_tip,
            None => Vec6::zeros(),
        };
        let etadot_b = node.offset.ad_inv().mul_vec(&etadot_p);
        let qn = w.dinv * (scratch[i].u - w.uhat.tr_mul(&etadot_b));
        for c in 0..node.k {
            x[node.dof + c] = qn[c];
        }
        let sc = &mut scratch[i];
        sc.etadot_base = etadot_b;
        sc.qn = qn;
        sc.etadot_tip = w.tip.ad_inv().mul_vec(&etadot_b) + w.s_tip * qn;
    }
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
        q,
        None,
        None,
        TreePass::Composite,
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

/// Energies on the tree: kinetic `½q̇ᵀMq̇`, elastic (rods and joint
/// springs), gravitational (rod points and bodies' centres of mass).
pub(crate) fn energies(
    model: &Model,
    tree: &Tree,
    data: &mut Data,
    q: &[f64],
    qd: &[f64],
) -> Energies {
    // Kinetic energy point by point (D59: it includes the prescribed
    // joints' motion, which `½q̇ᵀMq̇` would miss); the poses of this pass
    // serve the gravitational energy below.
    let kinetic = outward(
        model,
        tree,
        data,
        q,
        Some(qd),
        None,
        TreePass::Inverse,
        Forces::ALL,
    );
    let mut e = Energies {
        kinetic,
        ..Energies::default()
    };
    for rm in model.rods() {
        e.elastic += elastic_energy(
            &rm.spec.rod,
            &rm.spec.body,
            rm.spec.stress_free.as_deref(),
            &q[rm.dofs()],
            &model.quadrature,
        );
    }
    for el in &model.elements {
        for (i, o) in el.joint_dofs.clone().enumerate() {
            let (k, _, rest) = el.attachment.joint.coefficients(i);
            e.elastic += 0.5 * k * (q[o] - rest).powi(2);
        }
    }
    if let Some(g) = model.gravity {
        for (i, node) in tree.nodes.iter().enumerate() {
            let base = &data.nodes[i].base_world;
            match node.kind {
                NodeKind::Piece { rod, piece } => {
                    let rm = &model.rods[rod];
                    let pc = &rm.spec.rod.pieces()[piece];
                    let maps = PieceMaps::new(&pc.strain(&q[rm.dofs()]), None);
                    for qp in &rm.pieces[piece].points {
                        let p = base.transform_point(&maps.exp(qp.x).translation);
                        e.gravitational -= qp.w * qp.mass_per_length * g.dot(&p);
                    }
                }
                NodeKind::Body { body } => {
                    let b = &model.bodies[body].spec;
                    let p = base.transform_point(&b.center_of_mass);
                    e.gravitational -= b.mass * g.dot(&p);
                }
                NodeKind::Joint { .. } => {}
            }
        }
    }
    e
}

/// World poses of every rod's base frame and every body's frame into
/// `data.rod_bases`, `data.body_poses` (D51).
pub(crate) fn frames(model: &Model, tree: &Tree, data: &mut Data, q: &[f64]) {
    outward(
        model,
        tree,
        data,
        q,
        None,
        None,
        TreePass::Inverse,
        Forces::ALL,
    );
    for (r, nodes) in tree.rod_nodes.iter().enumerate() {
        data.rod_bases[r] = data.nodes[nodes[0]].base_world;
    }
    for (b, &i) in tree.body_nodes.iter().enumerate() {
        data.body_poses[b] = data.nodes[i].base_world;
    }
}
