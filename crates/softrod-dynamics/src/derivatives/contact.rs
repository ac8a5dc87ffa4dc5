//! The linearization of the contact force (docs/theory-contact.md CT6,
//! CT12): `∂τ_c/∂q = Σ J_pᵀ (∂f/∂p) J_p + J_pᵀ (∂f/∂v) ∂v/∂q + G(f)` and
//! `∂τ_c/∂q̇ = Σ J_pᵀ (∂f/∂v) J_p`, with `J_p` the translational Jacobian of
//! the contact point and the two second-order terms exact: on the chain
//! from the kinematics' `J̇` (`∂v/∂q = J̇_p[q̇]`, `G(f) e_l = J̇_p[e_l]ᵀ f`),
//! on a tree from the point's path to the root ([`super::second`]), the
//! obstacle's carrier on the other side. Rod pairs: [`super::pairs`]
//! (CT13–CT14); central differences only for pairs of rods whose contact
//! radius varies along them (CT14).

use super::second;
use crate::algorithms::contact::{Ask, evaluate_pairs_only};
use crate::algorithms::contact_force;
use crate::algorithms::pairs::{Search, seed_differences};
use crate::forces::Forces;
use crate::model::Model;
use crate::model::contact::ContactWork;
use crate::model::data::Data;
use crate::model::second::{self as second_path, Gathered};
use nalgebra::{DMatrix, DVector};
use softrod_kinematics::Frame;
use softrod_lie::{Vec3, angular};

/// Subtracts the contact force and its derivatives from the inverse
/// dynamics' `τ`, `∂τ/∂q`, `∂τ/∂q̇` (`τ_ID = … − τ_c`), evaluating contact
/// with `data` (its friction anchors). Nothing for a model without contact.
#[allow(clippy::too_many_arguments)]
pub(crate) fn subtract_contact(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    tau: &mut DVector<f64>,
    dq: &mut DMatrix<f64>,
    dqd: &mut DMatrix<f64>,
) {
    if !contact_force(model, data, forces, t, q, Some(qd)) {
        return;
    }
    let mut work = data.contact.take().expect("contact work");
    *tau -= &work.tau;
    if model.tree.is_none() {
        chain(model, &mut work, q, qd, dq, dqd);
    } else {
        tree(model, data, &mut work, q, qd, dq, dqd);
    }
    let pairs_touch = work.pairs.as_ref().is_some_and(|p| !p.active.is_empty());
    if pairs_touch {
        if super::pairs::analytic_applies(model, &work) {
            super::pairs::linearize(model, data, &mut work, q, qd, dq, dqd);
        } else {
            pairs_by_differences(model, data, &mut work, forces, q, qd, dq, dqd);
        }
    }
    data.contact = Some(work);
}

/// The analytic linearization of rod–obstacle contact on a tree (CT12):
/// the relative Jacobian `J_w = J_p − J_b` of the rod point and the
/// carrying body's point at the same place, the rotation of the carrier
/// (it turns the force and the relative velocity with it), and both
/// points' second-order terms.
#[allow(clippy::too_many_arguments)]
fn tree(
    model: &Model,
    data: &Data,
    work: &mut ContactWork,
    q: &[f64],
    qd: &[f64],
    dq: &mut DMatrix<f64>,
    dqd: &mut DMatrix<f64>,
) {
    let ContactWork { active, second, .. } = work;
    let sw = &mut **second;
    for a in active.iter() {
        let s = model.contact.samples[a.rod][a.sample].s;
        let p = second::tree_rod(model, data, q, Some(qd), a.rod, s, Vec3::zeros(), &mut sw.a);
        let body = model.contact.parents[a.obstacle];
        if let Some(b) = body {
            second::tree_body(model, data, q, Some(qd), b, p, &mut sw.b);
        }
        sw.dofs.clear();
        sw.dofs.extend(sw.a.cols.iter().map(|c| c.dof));
        if body.is_some() {
            sw.dofs.extend(sw.b.cols.iter().map(|c| c.dof));
        }
        sw.dofs.sort_unstable();
        sw.dofs.dedup();
        for m in [&mut sw.jw, &mut sw.jomega, &mut sw.vq] {
            m.fill(0.0);
        }
        sw.a.add_jacobian(1.0, &mut sw.jw);
        sw.a.add_velocity_derivative(qd, 1.0, &mut sw.vq);
        let (mut v, mut wb) = (sw.a.pdot, Vec3::zeros());
        if body.is_some() {
            sw.b.add_jacobian(-1.0, &mut sw.jw);
            sw.b.add_angular(1.0, &mut sw.jomega);
            sw.b.add_velocity_derivative(qd, -1.0, &mut sw.vq);
            v -= sw.b.pdot;
            wb = angular(&sw.b.blocks[0].vel);
        }
        // ∂f/∂q = f_p J_w + f_v (∂v/∂q + [v]× J_ω) − [f]× J_ω (CT12); the
        // carrier's rotation also turns J_w: the term f·(ω_i × j_l).
        sw.gather.clear();
        for &l in &sw.dofs {
            let jl = column(&sw.jw, l);
            let ol = column(&sw.jomega, l);
            let vl = column(&sw.vq, l) - wb.cross(&jl);
            sw.gather.push(Gathered {
                j: jl,
                f: a.dp * jl + a.dv * (vl + v.cross(&ol)) - a.force.cross(&ol),
                g: a.dv * jl,
                u: ol,
                a: 0.0,
                b: 0.0,
            });
        }
        let n = dq.nrows();
        if body.is_none() {
            // A world obstacle: the carrier's angular columns are zero, and
            // the geometric term `−f·∂²p/∂q∂q` is added in the same pass as
            // the rank terms, entry by entry in the order of the two
            // separate passes (the same sums, one sweep over the n × n).
            sw.a.sorted_columns();
            product_and_hessian(&mut sw.a, &sw.gather, &a.force, n, dq, dqd);
            continue;
        }
        let (mq, mqd) = (dq.as_mut_slice(), dqd.as_mut_slice());
        for (gl, &l) in sw.gather.iter().zip(&sw.dofs) {
            let jf = gl.j.cross(&a.force);
            for (gi, &i) in sw.gather.iter().zip(&sw.dofs) {
                mq[l * n + i] -= gi.j.dot(&gl.f) - gi.u.dot(&jf);
                mqd[l * n + i] -= gi.j.dot(&gl.g);
            }
        }
        sw.a.add_hessian_contraction(&a.force, -1.0, dq);
        sw.b.add_hessian_contraction(&a.force, 1.0, dq);
    }
}

/// Subtracts one point's `∂τ_c/∂q = J_wᵀ ∂f/∂q + f·∂²p/∂q∂q` and
/// `∂τ_c/∂q̇ = J_wᵀ ∂f/∂q̇` (a world obstacle: no carrier, CT6, CT12) from
/// the inverse dynamics' `dq`, `dqd`; `gather` in the order of the path's
/// sorted coordinates (`path.sorted`). Each entry first loses
/// its rank term, then gains the geometric one, as
/// [`second_path::PointPath::add_hessian_contraction`] after the rank pass
/// would.
fn product_and_hessian(
    path: &mut second_path::PointPath,
    gather: &[Gathered],
    force: &Vec3,
    n: usize,
    dq: &mut DMatrix<f64>,
    dqd: &mut DMatrix<f64>,
) {
    let sign = -1.0;
    let mut u = std::mem::take(&mut path.scratch);
    u.clear();
    u.extend(path.cols.iter().map(|c| c.j.cross(force) * sign));
    let (mq, mqd) = (dq.as_mut_slice(), dqd.as_mut_slice());
    for (gl, &lc) in gather.iter().zip(&path.sorted) {
        let cl = path.cols[lc];
        let col = cl.dof * n;
        for (gi, &ic) in gather.iter().zip(&path.sorted) {
            let ci = path.cols[ic];
            let e = col + ci.dof;
            mq[e] -= gi.j.dot(&gl.f);
            mqd[e] -= gi.j.dot(&gl.g);
            mq[e] += if ci.block == cl.block {
                sign * force.dot(&path.hessian(ic, lc))
            } else if ci.block > cl.block {
                ci.w.dot(&u[lc])
            } else {
                cl.w.dot(&u[ic])
            };
        }
    }
    path.scratch = u;
}

/// Column `c` of a 3 × n matrix.
#[inline]
pub(crate) fn column(m: &DMatrix<f64>, c: usize) -> Vec3 {
    Vec3::new(m[(0, c)], m[(1, c)], m[(2, c)])
}

fn column3(m: &nalgebra::Matrix6xX<f64>, c: usize) -> Vec3 {
    Vec3::new(m[(3, c)], m[(4, c)], m[(5, c)])
}

/// The analytic linearization on the chain (CT6).
fn chain(
    model: &Model,
    work: &mut ContactWork,
    q: &[f64],
    qd: &[f64],
    dq: &mut DMatrix<f64>,
    dqd: &mut DMatrix<f64>,
) {
    let ContactWork {
        kin,
        jac,
        jdot,
        active,
        tau_total,
        ..
    } = work;
    for (r, rm) in model.rods.iter().enumerate() {
        if !active.iter().any(|a| a.rod == r) {
            continue;
        }
        let g = &rm.spec.geometry;
        let off = rm.dof_offset;
        let k = rm.n_dof();
        for a in active.iter().filter(|a| a.rod == r) {
            let s = model.contact.samples[r][a.sample].s;
            kin[r]
                .jacobian_at(g, s, Frame::Mixed, &mut jac[r])
                .expect("on the rod");
            kin[r]
                .jacobian_dot_at(g, s, Frame::Mixed, &mut jdot[r])
                .expect("on the rod");
            for j in 0..k {
                let (jp, jd) = (column3(&jac[r], j), column3(&jdot[r], j));
                let aj = a.dp * jp + a.dv * jd;
                let bj = a.dv * jp;
                for i in 0..k {
                    let ji = column3(&jac[r], i);
                    dq[(off + i, off + j)] -= ji.dot(&aj);
                    dqd[(off + i, off + j)] -= ji.dot(&bj);
                }
            }
        }
        // G(f): one sweep per coordinate direction e_l.
        let unit = &mut tau_total.as_mut_slice()[..k];
        unit.fill(0.0);
        for l in 0..k {
            unit[l] = 1.0;
            kin[r]
                .update(g, &q[rm.dofs()], Some(unit), None)
                .expect("checked coordinates");
            unit[l] = 0.0;
            for a in active.iter().filter(|a| a.rod == r) {
                let s = model.contact.samples[r][a.sample].s;
                kin[r]
                    .jacobian_dot_at(g, s, Frame::Mixed, &mut jdot[r])
                    .expect("on the rod");
                for i in 0..k {
                    dq[(off + i, off + l)] -= column3(&jdot[r], i).dot(&a.force);
                }
            }
        }
        kin[r]
            .update(g, &q[rm.dofs()], Some(&qd[rm.dofs()]), None)
            .expect("checked coordinates");
    }
}

/// Central differences of the rod–rod part of `τ_c` (CT11; only for rods
/// whose contact radius varies, CT14): `2 n_dof` pair evaluations each for `q` and `q̇`, relative
/// steps `1e-6` and `1e-4`, in the pair work's buffers — each only of the
/// segment pairs that seeded the touching pairs (no broadphase). Zero without touching pairs: the
/// penalty is C¹ with `φ'(0) = 0`, so a pair about to touch adds nothing.
#[allow(clippy::too_many_arguments)]
fn pairs_by_differences(
    model: &Model,
    data: &mut Data,
    work: &mut ContactWork,
    forces: Forces,
    q: &[f64],
    qd: &[f64],
    dq: &mut DMatrix<f64>,
    dqd: &mut DMatrix<f64>,
) {
    let Some(ask) = Ask::of(forces, true) else {
        return;
    };
    let n = model.n_dof();
    seed_differences(work);
    let mut x = std::mem::take(&mut work.pairs.as_mut().expect("pair work").scratch);
    for pass in 0..2 {
        let base = if pass == 0 { q } else { qd };
        x.copy_from_slice(base);
        // In q̇ the force is linear but for the slip direction: a larger
        // step keeps the round-off of τ (amplified by M⁻¹ on stiff
        // coordinates) out of the column.
        let step = if pass == 0 { 1e-6 } else { 1e-4 };
        for l in 0..n {
            let h = step * (1.0 + base[l].abs());
            for sign in [1.0, -1.0] {
                x[l] = base[l] + sign * h;
                let (qq, vv) = if pass == 0 { (&x[..], qd) } else { (q, &x[..]) };
                evaluate_pairs_only(model, data, work, qq, Some(vv), ask, Search::Seeded);
                let tau = &work.pairs.as_ref().expect("pair work").tau;
                if sign > 0.0 {
                    work.tau_total.copy_from(tau);
                } else {
                    let m = if pass == 0 { &mut *dq } else { &mut *dqd };
                    for i in 0..n {
                        m[(i, l)] -= (work.tau_total[i] - tau[i]) / (2.0 * h);
                    }
                }
            }
            x[l] = base[l];
        }
    }
    // Leave the kinematics and the pairs of (q, q̇) behind.
    evaluate_pairs_only(model, data, work, q, Some(qd), ask, Search::All);
    work.pairs.as_mut().expect("pair work").scratch = x;
}
