//! The linearization of the contact force (docs/theory-contact.md CT6):
//! `∂τ_c/∂q = Σ J_pᵀ (∂f/∂p) J_p + J_pᵀ (∂f/∂v) ∂v/∂q + G(f)` and
//! `∂τ_c/∂q̇ = Σ J_pᵀ (∂f/∂v) J_p`, with `J_p` the translational Jacobian of
//! the contact point and, on the chain, the two second-order terms exact
//! from the kinematics' `J̇`: `∂v/∂q = J̇_p[q̇]` and the geometric term
//! `G(f) e_l = J̇_p[e_l]ᵀ f` (the symmetry of the position's Hessian). On a
//! tree (joints, bodies carrying obstacles) the Jacobian is taken by
//! central differences of `τ_c` (CT6).

use crate::algorithms::contact::{Ask, evaluate_pairs_only};
use crate::algorithms::contact_force;
use crate::algorithms::pairs::{Search, seed_differences};
use crate::forces::Forces;
use crate::model::Model;
use crate::model::contact::ContactWork;
use crate::model::data::Data;
use nalgebra::{DMatrix, DVector};
use softrod_kinematics::Frame;
use softrod_lie::Vec3;

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
        let pairs_touch = work.pairs.as_ref().is_some_and(|p| !p.active.is_empty());
        if pairs_touch {
            pairs_by_differences(model, data, &mut work, forces, q, qd, dq, dqd);
        }
        data.contact = Some(work);
    } else {
        data.contact = Some(work);
        by_differences(model, data, forces, t, q, qd, dq, dqd);
    }
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

/// Central differences of the rod–rod part of `τ_c` on a chain model
/// (CT11): `2 n_dof` pair evaluations each for `q` and `q̇`, relative
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

/// Central differences of `τ_c` on a tree model (CT6): `2 n_dof`
/// evaluations each for `q` and `q̇`, relative steps `1e-6` and `1e-4`.
#[allow(clippy::too_many_arguments)]
fn by_differences(
    model: &Model,
    data: &mut Data,
    forces: Forces,
    t: f64,
    q: &[f64],
    qd: &[f64],
    dq: &mut DMatrix<f64>,
    dqd: &mut DMatrix<f64>,
) {
    let n = model.n_dof();
    let mut x = q.to_vec();
    let mut plus = DVector::zeros(n);
    for pass in 0..2 {
        let base = if pass == 0 { q } else { qd };
        x.copy_from_slice(base);
        // As for the pairs: a larger step in q̇, where the force is linear
        // but for the slip direction.
        let step = if pass == 0 { 1e-6 } else { 1e-4 };
        for l in 0..n {
            let h = step * (1.0 + base[l].abs());
            for (sign, out) in [(1.0, true), (-1.0, false)] {
                x[l] = base[l] + sign * h;
                let (qq, vv) = if pass == 0 { (&x[..], qd) } else { (q, &x[..]) };
                contact_force(model, data, forces, t, qq, Some(vv));
                let w = data.contact.as_ref().expect("contact work");
                if out {
                    plus.copy_from(&w.tau);
                } else {
                    let m = if pass == 0 { &mut *dq } else { &mut *dqd };
                    for i in 0..n {
                        m[(i, l)] -= (plus[i] - w.tau[i]) / (2.0 * h);
                    }
                }
            }
            x[l] = base[l];
        }
    }
    // Leave the state of (q, q̇) behind, as the chain does.
    contact_force(model, data, forces, t, q, Some(qd));
}
